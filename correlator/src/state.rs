//! What a live correlator saves so that a restarted one resumes against the same reference:
//! one binary file, `reference.state`, written atomically (temporary sibling, then rename)
//! whenever the reference changes, and a human-readable `state.json` beside it. The live
//! process writes them off the frame path, on the thread of [`writer::StateWriter`].
//!
//! `reference.state`, all little-endian:
//!
//! | offset | size | content |
//! |---|---|---|
//! | 0 | 8 | magic `DICSREF1` |
//! | 8 | 4 | format version (3) |
//! | 12 | 8 | width, height (px, u32 each) |
//! | 20 | 8 | ZOI, step (px, u32 each) |
//! | 28 | 16 | ROI x, y, width, height (px, u32 each) |
//! | 44 | 8 | mesh nx, ny (u32 each) |
//! | 52 | 20 | reference mode, guess, strain measure, max iterations, strain window (u32 each) |
//! | 72 | 16 | auto thresholds: deformation (px), mean score (f64 each; 0 unless auto) |
//! | 88 | 8 | reference frame id (u64; `u64::MAX` for an image file) |
//! | 96 | 8 | origin frame id: the frame the mesh is defined in (u64; `u64::MAX`: an image file) |
//! | 104 | 8 | sequence id (u32), then the sub-pixel method (u32: 0 correli, 1 icgn1, 2 icgn2, 3 icgn) |
//! | 112 | 2 w h | reference pixels, row-major u16 |
//! | … | 16 nx ny | per-node base displacement u, v (px, f64 each): total displacement when the reference was taken |
//! | … | 8 | checksum (u64) of every byte before it |
//!
//! The frame the mesh is defined in goes to `origin.state` beside it when it changes (see
//! [`origin`]).
//!
//! Encoding reuses one buffer, and opening, writing and renaming short paths does not allocate,
//! so saving on every frame (incremental mode) allocates nothing. Written
//! files survive a killed process (the rename is atomic); they are not fsynced, so a power cut
//! may lose the last reference change.

mod origin;
pub mod writer;

pub use origin::ORIGIN_FILE;

use crate::settings::{
    CorrelatorSettings, GuessMode, Method, ReferenceMode, SettingsError, StrainMeasure,
};
use crate::Correlator;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"DICSREF1";
/// 3: the sub-pixel method in the header (a restart with another method is refused, the
/// difference named; a version 2 file is refused as of another format version).
const FORMAT_VERSION: u32 = 3;
const HEADER_BYTES: usize = 112;
/// Name of the binary state file inside the state folder.
pub const STATE_FILE: &str = "reference.state";
/// Name of the human-readable summary beside it (informative; never read back).
pub const SUMMARY_FILE: &str = "state.json";
/// `reference_frame_id` of a reference that came from an image file, not from a frame.
pub const REFERENCE_FROM_FILE: u64 = u64::MAX;

/// Why a state folder could not be used.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    #[error("{}: {detail}", .path.display())]
    Io { path: PathBuf, detail: String },
    #[error("{}: not a usable correlator state ({reason}); remove it to start from a new reference", .path.display())]
    Corrupt { path: PathBuf, reason: Corruption },
    #[error("{} was written with other settings: {detail}; run with the same settings or another --state-dir", .path.display())]
    Mismatch { path: PathBuf, detail: String },
    #[error("saved reference refused: {0}")]
    Settings(SettingsError),
    /// A state file could not be written (a full disk, say); also the `source()`, so that
    /// `wire::exit::code_of` finds its exit code.
    #[error("{0}")]
    Write(#[source] wire::files::FileError),
}

/// Why the bytes of a state file (`reference.state`, `origin.state`) cannot be read back.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Corruption {
    #[error("{len_bytes} bytes, shorter than a header")]
    Short { len_bytes: usize },
    #[error("wrong magic bytes")]
    Magic,
    #[error("format version {version}, this build reads {expected}")]
    Version { version: u32, expected: u32 },
    #[error("{len_bytes} bytes but the header ({width_px}x{height_px} px, mesh {mesh_x}x{mesh_y}) needs {expected_bytes:?}")]
    ReferenceLength {
        len_bytes: usize,
        width_px: u32,
        height_px: u32,
        mesh_x: u32,
        mesh_y: u32,
        /// None when the header's sizes overflow.
        expected_bytes: Option<u64>,
    },
    #[error("{len_bytes} bytes, a {width_px}x{height_px} px origin needs {expected_bytes}")]
    OriginLength {
        len_bytes: usize,
        width_px: usize,
        height_px: usize,
        expected_bytes: usize,
    },
    #[error("checksum mismatch")]
    Checksum,
}

/// The settings and size a state file was written for, as stored in its header.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Layout {
    width_px: u32,
    height_px: u32,
    zoi_px: u32,
    step_px: u32,
    roi: [u32; 4],
    mesh: [u32; 2],
    reference_mode: u32,
    guess: u32,
    strain: u32,
    max_iterations: u32,
    strain_window_nodes: u32,
    auto: [f64; 2],
    /// 0 correli, 1 icgn1, 2 icgn2, 3 icgn.
    method: u32,
}

impl Layout {
    fn of(correlator: &Correlator) -> Layout {
        let s = correlator.settings();
        let (w, h) = correlator.image_size();
        let roi = correlator.roi();
        let (nx, ny) = correlator.mesh_size();
        let (reference_mode, auto) = match s.reference {
            ReferenceMode::Fixed => (0, [0.0, 0.0]),
            ReferenceMode::Incremental => (1, [0.0, 0.0]),
            ReferenceMode::Auto {
                max_deformation_px,
                min_mean_score,
            } => (2, [max_deformation_px, min_mean_score]),
        };
        Layout {
            width_px: w as u32,
            height_px: h as u32,
            zoi_px: s.zoi_px as u32,
            step_px: s.step_px as u32,
            roi: [roi.x_px, roi.y_px, roi.width_px, roi.height_px].map(|v| v as u32),
            mesh: [nx as u32, ny as u32],
            reference_mode,
            guess: match s.guess {
                GuessMode::Correli => 0,
                GuessMode::Predict => 1,
                GuessMode::Auto => 2,
            },
            strain: match s.strain {
                StrainMeasure::Small => 0,
                StrainMeasure::Green => 1,
                StrainMeasure::Nominal => 2,
                StrainMeasure::Log => 3,
            },
            max_iterations: s.max_iterations,
            strain_window_nodes: s.strain_window_nodes as u32,
            auto,
            method: match s.method {
                Method::Correli => 0,
                Method::Icgn1 => 1,
                Method::Icgn2 => 2,
                Method::Icgn => 3,
            },
        }
    }

    fn nodes(&self) -> usize {
        self.mesh[0] as usize * self.mesh[1] as usize
    }

    fn pixels(&self) -> usize {
        self.width_px as usize * self.height_px as usize
    }

    fn file_bytes(&self) -> usize {
        HEADER_BYTES + 2 * self.pixels() + 16 * self.nodes() + 8
    }

    /// The first difference to `wanted` that makes the state unusable, in words.
    fn difference(&self, wanted: &Layout) -> Option<String> {
        let pairs: [(&str, String, String); 10] = [
            (
                "method",
                method_name(self.method).into(),
                method_name(wanted.method).into(),
            ),
            (
                "ZOI",
                format!("{} px", self.zoi_px),
                format!("{} px", wanted.zoi_px),
            ),
            (
                "step",
                format!("{} px", self.step_px),
                format!("{} px", wanted.step_px),
            ),
            (
                "ROI",
                format!("{:?}", self.roi),
                format!("{:?}", wanted.roi),
            ),
            (
                "reference mode",
                mode_name(self.reference_mode, self.auto),
                mode_name(wanted.reference_mode, wanted.auto),
            ),
            (
                "guess",
                guess_name(self.guess).into(),
                guess_name(wanted.guess).into(),
            ),
            (
                "strain",
                strain_name(self.strain).into(),
                strain_name(wanted.strain).into(),
            ),
            (
                "max iterations",
                self.max_iterations.to_string(),
                wanted.max_iterations.to_string(),
            ),
            (
                "strain window",
                self.strain_window_nodes.to_string(),
                wanted.strain_window_nodes.to_string(),
            ),
            (
                "mesh",
                format!("{:?}", self.mesh),
                format!("{:?}", wanted.mesh),
            ),
        ];
        pairs
            .into_iter()
            .find(|(_, a, b)| a != b)
            .map(|(what, saved, asked)| format!("{what} {saved} there, {asked} now"))
    }
}

fn mode_name(code: u32, auto: [f64; 2]) -> String {
    match code {
        0 => "fixed".into(),
        1 => "incremental".into(),
        2 => format!("auto (deformation {} px, score {})", auto[0], auto[1]),
        other => format!("code {other}"),
    }
}

fn method_name(code: u32) -> &'static str {
    Method::ALL
        .get(code as usize)
        .map(|m| m.name())
        .unwrap_or("?")
}

fn guess_name(code: u32) -> &'static str {
    match code {
        0 => "correli",
        1 => "predict",
        2 => "auto",
        _ => "?",
    }
}

fn strain_name(code: u32) -> &'static str {
    ["small", "green", "nominal", "log"]
        .get(code as usize)
        .copied()
        .unwrap_or("?")
}

/// Which frames a saved reference stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceIds {
    /// The frame correlated against ([`REFERENCE_FROM_FILE`] for an image file).
    pub reference_frame_id: u64,
    /// The frame the mesh is defined in (displacements count from it).
    pub origin_frame_id: u64,
    /// The frame sequence (`FrameHeader::sequence_id`) the reference belongs to.
    pub sequence_id: u32,
}

impl ReferenceIds {
    /// A reference read from an image file.
    pub const FROM_FILE: ReferenceIds = ReferenceIds {
        reference_frame_id: REFERENCE_FROM_FILE,
        origin_frame_id: REFERENCE_FROM_FILE,
        sequence_id: 0,
    };
}

/// A reference read back from a state folder.
#[derive(Clone, Debug)]
pub struct SavedReference {
    pub width_px: usize,
    pub height_px: usize,
    pub reference_frame_id: u64,
    pub origin_frame_id: u64,
    pub sequence_id: u32,
    pub pixels: Vec<u16>,
    pub base_px: Vec<(f64, f64)>,
    /// The frame the mesh is defined in, when `origin.state` holds it (same origin frame id
    /// and size).
    pub origin_pixels: Option<Vec<u16>>,
    layout: Layout,
}

impl SavedReference {
    /// Makes the correlator for these settings at the saved image size and restores the
    /// reference. Refuses a state written with other settings (a clear message naming the
    /// first difference).
    pub fn restore(
        &self,
        settings: CorrelatorSettings,
        path: &Path,
    ) -> Result<Correlator, StateError> {
        let mut correlator = Correlator::new(settings, self.width_px, self.height_px)
            .map_err(StateError::Settings)?;
        let wanted = Layout::of(&correlator);
        if let Some(detail) = self.layout.difference(&wanted) {
            return Err(StateError::Mismatch {
                path: path.to_path_buf(),
                detail,
            });
        }
        correlator
            .restore_reference(&self.pixels, &self.base_px)
            .map_err(StateError::Settings)?;
        if let Some(origin) = &self.origin_pixels {
            correlator
                .restore_origin(origin)
                .map_err(StateError::Settings)?;
        }
        Ok(correlator)
    }
}

/// A state folder: reads the saved reference, writes new ones atomically.
pub struct StateDir {
    dir: PathBuf,
    path: PathBuf,
    /// The same paths, written atomically (temporary siblings named once).
    file: wire::files::AtomicFile,
    summary_file: wire::files::AtomicFile,
    origin_file: wire::files::AtomicFile,
    /// Reused encoding buffers (sized on the first save).
    bytes: Vec<u8>,
    summary: String,
    pub saves: u64,
    origin_path: PathBuf,
    origin_bytes: Vec<u8>,
    /// `Correlator::origin_generation` of the origin last written.
    saved_origin: Option<u64>,
}

impl StateDir {
    /// Opens (creating it if needed) the folder.
    pub fn open(dir: &Path) -> Result<StateDir, StateError> {
        std::fs::create_dir_all(dir).map_err(|e| StateError::Io {
            path: dir.to_path_buf(),
            detail: format!("cannot create the state folder: {e}"),
        })?;
        Ok(StateDir {
            dir: dir.to_path_buf(),
            path: dir.join(STATE_FILE),
            file: wire::files::AtomicFile::new(&dir.join(STATE_FILE)),
            summary_file: wire::files::AtomicFile::new(&dir.join(SUMMARY_FILE)),
            origin_file: wire::files::AtomicFile::new(&dir.join(ORIGIN_FILE)),
            bytes: Vec::new(),
            summary: String::with_capacity(4096),
            saves: 0,
            origin_path: dir.join(ORIGIN_FILE),
            origin_bytes: Vec::new(),
            saved_origin: None,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The path of the binary state file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The saved reference, or None when the folder holds none yet.
    pub fn load(&self) -> Result<Option<SavedReference>, StateError> {
        let Some(bytes) = read_if_present(&self.path)? else {
            return Ok(None);
        };
        let mut saved = decode(&bytes).map_err(|reason| StateError::Corrupt {
            path: self.path.clone(),
            reason,
        })?;
        saved.origin_pixels = self.load_origin(&saved)?;
        Ok(Some(saved))
    }

    /// The origin of `saved` from `origin.state`, None when the file is missing or holds
    /// another origin.
    fn load_origin(&self, saved: &SavedReference) -> Result<Option<Vec<u16>>, StateError> {
        let Some(bytes) = read_if_present(&self.origin_path)? else {
            return Ok(None);
        };
        let origin = origin::decode(&bytes).map_err(|reason| StateError::Corrupt {
            path: self.origin_path.clone(),
            reason,
        })?;
        let same = origin.origin_frame_id == saved.origin_frame_id
            && (origin.width_px, origin.height_px) == (saved.width_px, saved.height_px);
        Ok(same.then_some(origin.pixels))
    }

    /// Writes the correlator's current reference with its frame id, atomically, then the
    /// human-readable summary. No allocation after the first call.
    pub fn save(&mut self, correlator: &Correlator, ids: ReferenceIds) -> Result<(), StateError> {
        let pixels = correlator
            .reference_pixels()
            .expect("save is called once a reference is set");
        let origin = correlator
            .origin_pixels()
            .map(|origin| (origin, correlator.origin_generation()));
        let layout = Layout::of(correlator);
        self.save_parts(&layout, ids, pixels, correlator.reference_base_px(), origin)
    }

    /// [`StateDir::save`] from the parts of a correlator's reference: its layout, pixels, bases
    /// and origin with its generation (what [`writer::StateWriter`] copies off the frame path).
    fn save_parts(
        &mut self,
        layout: &Layout,
        ids: ReferenceIds,
        pixels: &[u16],
        base_px: impl ExactSizeIterator<Item = (f64, f64)>,
        origin: Option<(&[u16], u64)>,
    ) -> Result<(), StateError> {
        let reference_frame_id = ids.reference_frame_id;
        // The origin first: a reference state on disk never names an origin that is not.
        if let Some((origin, generation)) = origin {
            if self.saved_origin != Some(generation) {
                origin::encode(
                    (layout.width_px as usize, layout.height_px as usize),
                    ids.origin_frame_id,
                    origin,
                    &mut self.origin_bytes,
                );
                self.origin_file
                    .write(&self.origin_bytes)
                    .map_err(StateError::Write)?;
                self.saved_origin = Some(generation);
            }
        }
        encode(layout, ids, pixels, base_px, &mut self.bytes);
        self.file.write(&self.bytes).map_err(StateError::Write)?;
        self.summary.clear();
        summary_json(
            layout,
            reference_frame_id,
            self.saves + 1,
            &mut self.summary,
        );
        self.summary_file
            .write(self.summary.as_bytes())
            .map_err(StateError::Write)?;
        self.saves += 1;
        Ok(())
    }
}

/// The file's bytes, None when it does not exist.
fn read_if_present(path: &Path) -> Result<Option<Vec<u8>>, StateError> {
    match std::fs::read(path) {
        Ok(bytes) => Ok(Some(bytes)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(StateError::Io {
            path: path.to_path_buf(),
            detail: format!("cannot read: {e}"),
        }),
    }
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn encode(
    layout: &Layout,
    ids: ReferenceIds,
    pixels: &[u16],
    base_px: impl ExactSizeIterator<Item = (f64, f64)>,
    out: &mut Vec<u8>,
) {
    assert_eq!(pixels.len(), layout.pixels());
    assert_eq!(base_px.len(), layout.nodes());
    out.clear();
    out.reserve(layout.file_bytes());
    out.extend_from_slice(MAGIC);
    put_u32(out, FORMAT_VERSION);
    for v in [
        layout.width_px,
        layout.height_px,
        layout.zoi_px,
        layout.step_px,
    ] {
        put_u32(out, v);
    }
    for v in layout.roi.into_iter().chain(layout.mesh) {
        put_u32(out, v);
    }
    for v in [
        layout.reference_mode,
        layout.guess,
        layout.strain,
        layout.max_iterations,
        layout.strain_window_nodes,
    ] {
        put_u32(out, v);
    }
    for v in layout.auto {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&ids.reference_frame_id.to_le_bytes());
    out.extend_from_slice(&ids.origin_frame_id.to_le_bytes());
    put_u32(out, ids.sequence_id);
    put_u32(out, layout.method);
    debug_assert_eq!(out.len(), HEADER_BYTES);
    for &p in pixels {
        out.extend_from_slice(&p.to_le_bytes());
    }
    for (u, v) in base_px {
        out.extend_from_slice(&u.to_le_bytes());
        out.extend_from_slice(&v.to_le_bytes());
    }
    let sum = wire::frame::byte_checksum(out);
    out.extend_from_slice(&sum.to_le_bytes());
    assert_eq!(out.len(), layout.file_bytes());
}

fn decode(bytes: &[u8]) -> Result<SavedReference, Corruption> {
    if bytes.len() < HEADER_BYTES + 8 {
        return Err(Corruption::Short {
            len_bytes: bytes.len(),
        });
    }
    if &bytes[..8] != MAGIC {
        return Err(Corruption::Magic);
    }
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().expect("8 bytes"));
    let f64_at = |o: usize| f64::from_le_bytes(bytes[o..o + 8].try_into().expect("8 bytes"));
    let version = u32_at(8);
    if version != FORMAT_VERSION {
        return Err(Corruption::Version {
            version,
            expected: FORMAT_VERSION,
        });
    }
    let layout = Layout {
        width_px: u32_at(12),
        height_px: u32_at(16),
        zoi_px: u32_at(20),
        step_px: u32_at(24),
        roi: [u32_at(28), u32_at(32), u32_at(36), u32_at(40)],
        mesh: [u32_at(44), u32_at(48)],
        reference_mode: u32_at(52),
        guess: u32_at(56),
        strain: u32_at(60),
        max_iterations: u32_at(64),
        strain_window_nodes: u32_at(68),
        auto: [f64_at(72), f64_at(80)],
        method: u32_at(108),
    };
    let reference_frame_id = u64_at(88);
    let origin_frame_id = u64_at(96);
    let sequence_id = u32_at(104);
    let expected = (layout.width_px as u64 * layout.height_px as u64)
        .checked_mul(2)
        .and_then(|p| p.checked_add(16 * layout.mesh[0] as u64 * layout.mesh[1] as u64))
        .and_then(|p| p.checked_add(HEADER_BYTES as u64 + 8));
    if expected != Some(bytes.len() as u64) {
        return Err(Corruption::ReferenceLength {
            len_bytes: bytes.len(),
            width_px: layout.width_px,
            height_px: layout.height_px,
            mesh_x: layout.mesh[0],
            mesh_y: layout.mesh[1],
            expected_bytes: expected,
        });
    }
    let body = bytes.len() - 8;
    if wire::frame::byte_checksum(&bytes[..body]) != u64_at(body) {
        return Err(Corruption::Checksum);
    }
    let pixel_end = HEADER_BYTES + 2 * layout.pixels();
    let pixels = bytes[HEADER_BYTES..pixel_end]
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    let base_px = bytes[pixel_end..body]
        .chunks_exact(16)
        .map(|b| {
            (
                f64::from_le_bytes(b[..8].try_into().expect("8 bytes")),
                f64::from_le_bytes(b[8..].try_into().expect("8 bytes")),
            )
        })
        .collect();
    Ok(SavedReference {
        width_px: layout.width_px as usize,
        height_px: layout.height_px as usize,
        reference_frame_id,
        origin_frame_id,
        sequence_id,
        pixels,
        base_px,
        origin_pixels: None,
        layout,
    })
}

fn summary_json(layout: &Layout, reference_frame_id: u64, saves: u64, out: &mut String) {
    // Written with `write!` into a reused String: no allocation once it has grown.
    let _ = write!(
        out,
        "{{\n  \"file\": \"{STATE_FILE}\",\n  \"format_version\": {FORMAT_VERSION},\n"
    );
    if reference_frame_id == REFERENCE_FROM_FILE {
        let _ = writeln!(
            out,
            "  \"reference_frame_id\": null,\n  \"reference_from_file\": true,"
        );
    } else {
        let _ = writeln!(
            out,
            "  \"reference_frame_id\": {reference_frame_id},\n  \"reference_from_file\": false,"
        );
    }
    let mode = match layout.reference_mode {
        0 => "fixed",
        1 => "incremental",
        2 => "auto",
        _ => "?",
    };
    let _ = write!(
        out,
        "  \"saves_by_this_process\": {saves},\n  \"image\": [{}, {}],\n  \"zoi\": {},\n  \"step\": {},\n  \"roi\": [{}, {}, {}, {}],\n  \"mesh\": [{}, {}],\n  \"reference_mode\": \"{mode}\",\n  \"auto_max_deformation_px\": {},\n  \"auto_min_mean_score\": {},\n  \"method\": \"{}\",\n  \"guess\": \"{}\",\n  \"strain\": \"{}\",\n  \"max_iterations\": {},\n  \"strain_window_nodes\": {}\n}}\n",
        layout.width_px,
        layout.height_px,
        layout.zoi_px,
        layout.step_px,
        layout.roi[0],
        layout.roi[1],
        layout.roi[2],
        layout.roi[3],
        layout.mesh[0],
        layout.mesh[1],
        layout.auto[0],
        layout.auto[1],
        method_name(layout.method),
        guess_name(layout.guess),
        strain_name(layout.strain),
        layout.max_iterations,
        layout.strain_window_nodes,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn speckle(w: usize, h: usize) -> Vec<u16> {
        // A deterministic texture (not a real speckle; enough contrast for every ZOI).
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                (30000.0 + 12000.0 * (0.7 * x).sin() * (0.45 * y + 0.3 * x).cos()) as u16
            })
            .collect()
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("dicstream_state_{name}_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn round_trip_and_refusals() {
        let dir = temp_dir("round_trip");
        let (w, h) = (96, 80);
        let pixels = speckle(w, h);
        let settings = CorrelatorSettings {
            threads: 1,
            reference: ReferenceMode::Incremental,
            ..CorrelatorSettings::default()
        };
        let mut correlator = Correlator::new(settings.clone(), w, h).unwrap();
        correlator.set_reference(&pixels).unwrap();
        let mut state = StateDir::open(&dir).unwrap();
        assert!(state.load().unwrap().is_none());
        let ids = ReferenceIds {
            reference_frame_id: 42,
            origin_frame_id: 40,
            sequence_id: 3,
        };
        state.save(&correlator, ids).unwrap();
        let saved = state.load().unwrap().unwrap();
        assert_eq!((saved.width_px, saved.height_px), (w, h));
        assert_eq!(saved.reference_frame_id, 42);
        assert_eq!((saved.origin_frame_id, saved.sequence_id), (40, 3));
        assert_eq!(saved.pixels, pixels);
        assert_eq!(saved.origin_pixels.as_deref(), Some(&pixels[..]));
        let restored = saved.restore(settings.clone(), state.path()).unwrap();
        assert_eq!(restored.reference_pixels().unwrap(), &pixels[..]);
        assert_eq!(restored.origin_pixels(), Some(&pixels[..]));
        // An origin file of another origin frame is no origin for this reference.
        let other = ReferenceIds {
            origin_frame_id: 7,
            ..ids
        };
        let mut other_dir = StateDir::open(&dir.join("other")).unwrap();
        other_dir.save(&correlator, other).unwrap();
        std::fs::copy(dir.join("other").join(ORIGIN_FILE), dir.join(ORIGIN_FILE)).unwrap();
        assert_eq!(state.load().unwrap().unwrap().origin_pixels, None);
        std::fs::remove_dir_all(dir.join("other")).unwrap();
        let summary = std::fs::read_to_string(dir.join(SUMMARY_FILE)).unwrap();
        assert!(summary.contains("\"reference_frame_id\": 42"), "{summary}");
        assert!(
            summary.contains("\"reference_mode\": \"incremental\""),
            "{summary}"
        );
        // Other settings: refused with the first difference named.
        let error = saved
            .restore(
                CorrelatorSettings {
                    step_px: 8,
                    ..settings.clone()
                },
                state.path(),
            )
            .err()
            .unwrap()
            .to_string();
        assert!(error.contains("step 16 px there, 8 px now"), "{error}");
        // Another sub-pixel method: refused, named.
        let error = saved
            .restore(
                CorrelatorSettings {
                    method: Method::Icgn1,
                    zoi_px: 33,
                    ..settings.clone()
                },
                state.path(),
            )
            .err()
            .unwrap()
            .to_string();
        assert!(error.contains("method correli there, icgn1 now"), "{error}");
        assert!(summary.contains("\"method\": \"correli\""), "{summary}");
        // A damaged file: refused, not misread.
        let mut bytes = std::fs::read(state.path()).unwrap();
        bytes[HEADER_BYTES + 7] ^= 0x40;
        std::fs::write(state.path(), &bytes).unwrap();
        let error = state.load().unwrap_err().to_string();
        assert!(error.contains("checksum"), "{error}");
        std::fs::write(state.path(), &bytes[..200]).unwrap();
        let error = state.load().unwrap_err().to_string();
        assert!(error.contains("needs"), "{error}");
        // No temporary file is left behind.
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
