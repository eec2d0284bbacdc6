//! The field route offline (issue 25 deliverable 4, `dicstream identify --fields DIR`): a run's
//! saved fields (`fields/field_<frame>.csv`, the correlator's CSV contract with each node's
//! gradient), its `frames.csv` (each frame's test and grip forces, or its rig time) and,
//! optionally, the rig's log (`rig.csv`: the forces by time instead), fed in frame order to
//! the live route's own feed ([`crate::process::FieldFeed`]: same px-to-mm mapping, same
//! layout, same kept frames, same fit). Every file is read by [`Table`]; what the route cannot
//! use is an error naming the file, the line and what is missing, never a frame quietly left
//! out: a field without gradient columns, a frame without its forces or without a row in
//! `frames.csv`, a rig time outside the rig's log.

use crate::data::DataError;
use crate::field_stress::Mat2;
use crate::table::{Row, Table, TableOptions};
use std::path::{Path, PathBuf};

/// One saved field: its frame and its nodes in the camera's px, each node's F (None: not `ok`).
#[derive(Clone, Debug, PartialEq)]
pub struct SavedField {
    pub path: PathBuf,
    pub frame_id: u64,
    /// The first node (its origin image's px), the nodes' pitch (px) and the grid's size.
    pub first_px: [f64; 2],
    pub step_px: f64,
    pub cols: usize,
    pub rows: usize,
    /// F = I + ∇u of every `ok` node, row-major; None for the others.
    pub gradients: Vec<Option<Mat2>>,
    /// The displacement (u, v) of every `ok` node, px, row-major; None for the others.
    pub displacements_px: Vec<Option<[f64; 2]>>,
}

/// Why saved fields cannot be identified.
#[derive(Debug, thiserror::Error)]
pub enum SavedFieldsError {
    #[error(transparent)]
    Data(#[from] DataError),
    #[error("{dir}: {message}")]
    Folder { dir: String, message: String },
    #[error("{file}: {error}")]
    Layout {
        file: String,
        error: crate::field_layout::LayoutError,
    },
    #[error("the field route's specimen: {0}")]
    Geometry(String),
    #[error(
        "{dir}: {kept} frame(s) kept of {read} field file(s), {needed} needed for a fit \
         (not loading: {not_loading}, grips at rest: {grips_unloaded}, without gradients: \
         {without_gradients}): too few distinct states of the test"
    )]
    TooFewFrames {
        dir: String,
        read: usize,
        kept: usize,
        needed: usize,
        not_loading: u64,
        grips_unloaded: u64,
        without_gradients: u64,
    },
}

/// The route's fits of a run's saved fields and what happened to its frames.
#[derive(Debug)]
pub struct SavedFit {
    pub fits: crate::field_route::FieldFits,
    pub counters: crate::field_route::FieldCounters,
    pub last_dropped: Option<String>,
    pub fields_read: usize,
    /// The forces were each grip's (false: an older `frames.csv`'s axis means).
    pub per_grip: bool,
    /// The kept frames' force balance per grip under the first ranked fit.
    pub force_balance: Vec<crate::field_route::GripBalance>,
    /// The kept frames' measured displacements (mm, on the reference grid) and grip forces:
    /// what finite-element model updating fits (`crate::femu`).
    pub kept_frames: Vec<crate::femu::FemuFrame>,
    /// Wall time of the fit of every model to the kept frames, s (reading excluded).
    pub fit_s: f64,
    /// Each state of the kept frames with its contribution to the best ranked fit (None: no
    /// fit is ranked).
    pub states: Option<
        Result<
            crate::state_contributions::StateContributions,
            crate::state_contributions::ContributionError,
        >,
    >,
}

/// Fits the saved fields of results folder `dir` with the live route's feed: each field file
/// in frame order, its test and forces from `frames.csv` (or, with `rig_log`, from the rig's
/// log at the frame's rig time).
#[cfg(feature = "process")]
pub fn fit_saved(
    dir: &Path,
    settings: &crate::process::FieldRouteSettings,
    models: &[crate::models::Model],
    rig_log: Option<&Path>,
) -> Result<SavedFit, SavedFieldsError> {
    let files = field_files(dir)?;
    let frames = read_frames(&dir.join("frames.csv"))?;
    let source = match rig_log {
        Some(path) => ForceSource::RigLog(read_rig_forces(path)?),
        None => ForceSource::Frames,
    };
    let mut feed = crate::process::FieldFeed::new(settings, models)
        .map_err(|e| SavedFieldsError::Geometry(e.to_string()))?;
    let mut displacements = std::collections::BTreeMap::new();
    for (frame_id, path) in &files {
        let mut field = read_field(path, *frame_id)?;
        let (sequence, forces) = frame_forces(&frames, &source, &field)?;
        let measured = std::mem::take(&mut field.displacements_px);
        displacements.insert(
            *frame_id,
            feed.displacement_grid(
                field.first_px,
                field.step_px,
                (field.cols, field.rows),
                measured,
            ),
        );
        let grid = feed.grid(
            field.first_px,
            field.step_px,
            (field.cols, field.rows),
            field.gradients,
        );
        feed.offer(*frame_id, sequence, Some(grid), Some(forces))
            .map_err(|error| SavedFieldsError::Layout {
                file: path.display().to_string(),
                error,
            })?;
    }
    let route = &feed.route;
    let c = route.counters;
    let started = std::time::Instant::now();
    let fitted = route.fit();
    let fit_s = started.elapsed().as_secs_f64();
    let Some(fits) = fitted else {
        return Err(SavedFieldsError::TooFewFrames {
            dir: dir.display().to_string(),
            read: files.len(),
            kept: route.frames().len(),
            needed: crate::process::FieldFeed::MIN_FRAMES_TO_FIT,
            not_loading: c.not_loading,
            grips_unloaded: c.grips_unloaded,
            without_gradients: c.without_gradients,
        });
    };
    let kept_frames = route
        .frames()
        .iter()
        .filter_map(|kept| {
            Some(crate::femu::FemuFrame {
                frame_id: kept.frame_id,
                field: displacements.remove(&kept.frame_id)?,
                forces_n: kept.forces_n,
            })
        })
        .collect();
    Ok(SavedFit {
        kept_frames,
        fit_s,
        states: crate::state_contributions::of_best_fit(route, &fits),
        force_balance: crate::process::force_balance(route, &fits),
        fits,
        counters: c,
        last_dropped: route.last_dropped.clone(),
        fields_read: files.len(),
        per_grip: frames.per_grip || matches!(source, ForceSource::RigLog(_)),
    })
}

/// The gradient columns a field file must carry.
const GRADIENT_COLUMNS: [&str; 4] = ["du_dx", "du_dy", "dv_dx", "dv_dy"];

fn column(table: &Table, name: &str, why: &str) -> Result<usize, DataError> {
    table.find(|c| c == name)?.ok_or_else(|| {
        table.error(format!(
            "line {}: no `{name}` column ({why})",
            table.header_line
        ))
    })
}

/// Reads one field file, `frame_id` its frame (from its name).
pub fn read_field(path: &Path, frame_id: u64) -> Result<SavedField, DataError> {
    let table = Table::read(path, TableOptions::default())?;
    let missing: Vec<&str> = GRADIENT_COLUMNS
        .iter()
        .copied()
        .filter(|name| !matches!(table.find(|c| c == *name), Ok(Some(_))))
        .collect();
    if !missing.is_empty() {
        return Err(table.error(format!(
            "line {}: no displacement gradient columns ({} missing): the field route needs \
             each node's gradient (a field file of a run before they were written, or of \
             another program)",
            table.header_line,
            missing.join(", ")
        )));
    }
    let [x, y, u, v, status] =
        ["x", "y", "u", "v", "status"].map(|n| column(&table, n, "the field CSV contract"));
    let (x, y, u, v, status) = (x?, y?, u?, v?, status?);
    let g: Vec<usize> = GRADIENT_COLUMNS
        .iter()
        .map(|n| column(&table, n, "a gradient"))
        .collect::<Result<_, _>>()?;
    let Some(first) = table.rows.first() else {
        return Err(table.error("no node: the file ends at its header".into()));
    };
    let at = |row: &Row| -> Result<[f64; 2], DataError> {
        Ok([table.number(row, x)?, table.number(row, y)?])
    };
    let first_px = at(first)?;
    // Row-major: the first row of nodes is every node at the first node's y.
    let cols = table
        .rows
        .iter()
        .take_while(|r| at(r).is_ok_and(|p| p[1] == first_px[1]))
        .count();
    let rows = table.rows.len() / cols;
    let step_px = match table.rows.get(1).filter(|_| cols > 1) {
        Some(second) => at(second)?[0] - first_px[0],
        None => match table.rows.get(cols) {
            Some(below) => at(below)?[1] - first_px[1],
            None => 1.0,
        },
    };
    let mut gradients = Vec::with_capacity(table.rows.len());
    let mut displacements_px = Vec::with_capacity(table.rows.len());
    for (k, row) in table.rows.iter().enumerate() {
        let p = at(row)?;
        let want = [
            first_px[0] + (k % cols) as f64 * step_px,
            first_px[1] + (k / cols) as f64 * step_px,
        ];
        if rows * cols != table.rows.len()
            || (p[0] - want[0]).abs() > 1e-3 * step_px.abs().max(1.0)
            || (p[1] - want[1]).abs() > 1e-3 * step_px.abs().max(1.0)
        {
            return Err(table.error(format!(
                "line {}: node at ({}, {}) px where a regular grid of {cols} columns, {step_px} px \
                 apart from ({}, {}), has ({}, {}) ({} nodes)",
                row.line,
                p[0],
                p[1],
                first_px[0],
                first_px[1],
                want[0],
                want[1],
                table.rows.len()
            )));
        }
        let ok = row.cells[status] == "ok";
        let mut f = [[1.0, 0.0], [0.0, 1.0]];
        if ok {
            for (i, &c) in g.iter().enumerate() {
                f[i / 2][i % 2] += table.number(row, c)?;
            }
        }
        gradients.push(ok.then_some(f));
        displacements_px.push(if ok {
            Some([table.number(row, u)?, table.number(row, v)?])
        } else {
            None
        });
    }
    Ok(SavedField {
        path: path.to_path_buf(),
        frame_id,
        first_px,
        step_px,
        cols,
        rows,
        gradients,
        displacements_px,
    })
}

/// The field files of a results folder (`fields/field_<frame>.csv`), by frame.
pub fn field_files(dir: &Path) -> Result<Vec<(u64, PathBuf)>, SavedFieldsError> {
    let folder = dir.join("fields");
    let error = |message: String| SavedFieldsError::Folder {
        dir: folder.display().to_string(),
        message,
    };
    let entries = std::fs::read_dir(&folder)
        .map_err(|e| error(format!("cannot read the run's fields folder: {e}")))?;
    let mut files = vec![];
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let frame = name
            .strip_prefix("field_")
            .and_then(|n| n.strip_suffix(".csv"))
            .and_then(|n| n.parse::<u64>().ok());
        if let Some(frame) = frame {
            files.push((frame, entry.path()));
        }
    }
    if files.is_empty() {
        return Err(error("no field file (field_<frame>.csv)".into()));
    }
    files.sort();
    Ok(files)
}

/// What `frames.csv` says of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameInfo {
    pub line: usize,
    /// The frame's test (0 in a `frames.csv` written before the column was).
    pub sequence: u32,
    /// The test's kind at the frame's rig sample (`RigState::load_case`; 0 when unknown).
    pub load_case: u32,
    /// The rig's simulated time at the frame's sample, s (None: no rig sample).
    pub t_rig_s: Option<f64>,
    /// Each grip's force, N, X+, X-, Y+, Y- (None: empty cells, no rig sample).
    pub forces_n: Option<[f64; 4]>,
}

/// The grips' force columns of `frames.csv`, and the axes' (mean of the two grips) of an older
/// one.
const GRIP_COLUMNS: [&str; 4] = ["force_x+_n", "force_x-_n", "force_y+_n", "force_y-_n"];
const AXIS_COLUMNS: [&str; 2] = ["force_x_n", "force_y_n"];

/// The run's frames: frame id → what `frames.csv` says of it, and whether its forces are each
/// grip's (false: an older `frames.csv`, each axis's mean force for both its grips).
pub struct Frames {
    pub source: String,
    pub frames: std::collections::BTreeMap<u64, FrameInfo>,
    pub per_grip: bool,
}

/// Reads `frames.csv`.
pub fn read_frames(path: &Path) -> Result<Frames, DataError> {
    let table = Table::read(path, TableOptions::default())?;
    let id = column(&table, "frame_id", "each row's frame")?;
    let find = |name: &str| table.find(|c| c == name);
    let sequence = find("sequence_id")?;
    let load_case = find("load_case")?;
    let t_sim = find("t_sim_s")?;
    let grips = GRIP_COLUMNS
        .iter()
        .map(|n| find(n))
        .collect::<Result<Option<Vec<usize>>, _>>()?;
    let axes = AXIS_COLUMNS
        .iter()
        .map(|n| find(n))
        .collect::<Result<Option<Vec<usize>>, _>>()?;
    let per_grip = grips.is_some();
    let forces_columns: Option<Vec<usize>> =
        grips.or_else(|| axes.map(|a| vec![a[0], a[0], a[1], a[1]]));
    let mut frames = std::collections::BTreeMap::new();
    for row in &table.rows {
        let frame = table.number(row, id)? as u64;
        let optional = |c: Option<usize>| -> Result<Option<f64>, DataError> {
            match c {
                Some(c) if !row.cells[c].is_empty() => Ok(Some(table.number(row, c)?)),
                _ => Ok(None),
            }
        };
        let forces = match &forces_columns {
            Some(c) if c.iter().all(|&c| !row.cells[c].is_empty()) => {
                let mut f = [0.0; 4];
                for (f, &c) in f.iter_mut().zip(c) {
                    *f = table.number(row, c)?;
                }
                Some(f)
            }
            _ => None,
        };
        frames.insert(
            frame,
            FrameInfo {
                line: row.line,
                sequence: optional(sequence)?.map_or(0, |s| s as u32),
                load_case: optional(load_case)?.map_or(0, |c| c as u32),
                t_rig_s: optional(t_sim)?,
                forces_n: forces,
            },
        );
    }
    Ok(Frames {
        source: table.source,
        frames,
        per_grip,
    })
}

/// The rig's log: each grip's force against the rig's time.
pub struct RigForces {
    source: String,
    rows: Vec<(f64, [f64; 4])>,
}

/// The rig log's columns: its time and each grip's force.
const RIG_TIME: &str = "t_s";
const RIG_GRIPS: [&str; 4] = ["x+_force_n", "x-_force_n", "y+_force_n", "y-_force_n"];

/// Reads the rig's log (`rig.csv`: `t_s` and `X+_force_n` ... `Y-_force_n`).
pub fn read_rig_forces(path: &Path) -> Result<RigForces, DataError> {
    let table = Table::read(path, TableOptions::default())?;
    let t = column(&table, RIG_TIME, "the rig's time, s")?;
    let grips: Vec<usize> = RIG_GRIPS
        .iter()
        .map(|n| column(&table, n, "a grip's force, N"))
        .collect::<Result<_, _>>()?;
    let mut rows = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let mut f = [0.0; 4];
        for (f, &c) in f.iter_mut().zip(&grips) {
            *f = table.number(row, c)?;
        }
        let time = table.number(row, t)?;
        if rows.last().is_some_and(|&(last, _)| time <= last) {
            return Err(table.error(format!(
                "line {}: time {time} s does not follow the row before's",
                row.line
            )));
        }
        rows.push((time, f));
    }
    if rows.is_empty() {
        return Err(table.error("no row under the header".into()));
    }
    Ok(RigForces {
        source: table.source,
        rows,
    })
}

impl RigForces {
    /// The grips' forces at rig time `t_s`, linear between the two rows around it; within
    /// less than one logging interval (the first two rows' or the last two's) before the
    /// first row or after the last, that row's (a run's origin frame is captured before the
    /// log's first row: 0.04 s against 0.05 s at 20 rows/s); None farther outside the log.
    pub fn at(&self, t_s: f64) -> Option<[f64; 4]> {
        let n = self.rows.len();
        let within_interval = |end: usize, other: usize| {
            n >= 2 && (t_s - self.rows[end].0).abs() < (self.rows[other].0 - self.rows[end].0).abs()
        };
        if t_s < self.rows[0].0 {
            return within_interval(0, 1).then_some(self.rows[0].1);
        }
        if t_s > self.rows[n - 1].0 {
            return within_interval(n - 1, n.saturating_sub(2)).then_some(self.rows[n - 1].1);
        }
        // rows[0] ≤ t_s ≤ the last row's time: `after` is a row, and 0 only at rows[0]'s time.
        let after = self.rows.partition_point(|&(t, _)| t < t_s);
        let (t1, f1) = self.rows[after];
        if t1 == t_s {
            return Some(f1);
        }
        let (t0, f0) = self.rows[after - 1];
        let w = (t_s - t0) / (t1 - t0);
        Some(std::array::from_fn(|k| f0[k] + w * (f1[k] - f0[k])))
    }

    /// The log's time span, s.
    pub fn span_s(&self) -> [f64; 2] {
        [self.rows[0].0, self.rows[self.rows.len() - 1].0]
    }
}

/// Where the forces come from.
pub enum ForceSource {
    /// `frames.csv`'s forces at each frame's rig sample.
    Frames,
    /// The rig's log, at each frame's rig time (`frames.csv`'s `t_sim_s`).
    RigLog(RigForces),
}

/// The frame's test and grip forces: an error names `frames.csv`'s line (or the field file
/// without a row) and what is missing.
pub fn frame_forces(
    frames: &Frames,
    source: &ForceSource,
    field: &SavedField,
) -> Result<(u32, [f64; 4]), SavedFieldsError> {
    let Some(info) = frames.frames.get(&field.frame_id) else {
        return Err(DataError::new(
            &field.path.display().to_string(),
            format!(
                "frame {} has no row in {}: its forces are unknown",
                field.frame_id, frames.source
            ),
        )
        .into());
    };
    let at_line = |message: String| -> SavedFieldsError {
        DataError::new(&frames.source, format!("line {}: {message}", info.line)).into()
    };
    let forces = match source {
        ForceSource::Frames => info.forces_n.ok_or_else(|| {
            at_line(format!(
                "frame {}: no grip forces (empty cells: the frame names no rig sample); \
                 give the rig's log with --forces to pair it by time",
                field.frame_id
            ))
        })?,
        ForceSource::RigLog(rig) => {
            let t = info.t_rig_s.ok_or_else(|| {
                at_line(format!(
                    "frame {}: no rig time (`t_sim_s` empty): it cannot be paired with {}",
                    field.frame_id, rig.source
                ))
            })?;
            rig.at(t).ok_or_else(|| {
                let [from, to] = rig.span_s();
                at_line(format!(
                    "frame {}: rig time {t} s is outside {} ({from} to {to} s): no forces to \
                     pair with it",
                    field.frame_id, rig.source
                ))
            })?
        }
    };
    Ok((
        info.sequence,
        crate::grip_forces::on_specimen(info.load_case, forces),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("saved_fields_{name}_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_field_file_gives_its_grid_and_each_ok_nodes_f() {
        let dir = scratch("grid");
        let mut text =
            String::from("x,y,u,v,exx,eyy,exy,score,iterations,status,du_dx,du_dy,dv_dx,dv_dy\n");
        for (k, (x, y)) in [(10, 20), (14, 20), (10, 24), (14, 24)].iter().enumerate() {
            let status = if k == 2 { "low_contrast" } else { "ok" };
            text += &format!("{x},{y},0,0,0,0,0,1,3,{status},0.1,0.02,-0.01,0.05\n");
        }
        let field = read_field(&write(&dir, "field_000010.csv", &text), 10).unwrap();
        assert_eq!((field.cols, field.rows, field.step_px), (2, 2, 4.0));
        assert_eq!(field.first_px, [10.0, 20.0]);
        assert_eq!(field.gradients[0], Some([[1.1, 0.02], [-0.01, 1.05]]));
        assert_eq!(field.gradients[2], None);
        assert_eq!(field.displacements_px[1], Some([0.0, 0.0]));
        assert_eq!(field.displacements_px[2], None);
        // Without the gradient columns: the file, its header's line and the columns named.
        let old = "x,y,u,v,exx,eyy,exy,score,iterations,status\n10,20,0,0,0,0,0,1,3,ok\n";
        let e = read_field(&write(&dir, "old.csv", old), 1)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("old.csv: line 1: no displacement gradient columns (du_dx, du_dy, dv_dx, dv_dy missing)"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn forces_by_time_are_interpolated_and_a_time_outside_the_log_is_named() {
        let dir = scratch("rig");
        let rig = "t_s,X+_force_n,X-_force_n,Y+_force_n,Y-_force_n\n0.0,0,0,0,0\n1.0,10,20,30,40\n";
        let rig = read_rig_forces(&write(&dir, "rig.csv", rig)).unwrap();
        assert_eq!(rig.at(0.5), Some([5.0, 10.0, 15.0, 20.0]));
        assert_eq!(rig.at(1.0), Some([10.0, 20.0, 30.0, 40.0]));
        // Less than one logging interval (1 s) beyond an end: that end's row; farther, none.
        assert_eq!(rig.at(1.5), Some([10.0, 20.0, 30.0, 40.0]));
        assert_eq!(rig.at(-0.5), Some([0.0; 4]));
        assert_eq!(rig.at(2.0), None);
        assert_eq!(rig.at(-1.0), None);
        let frames = "frame_id,t_sim_s,sequence_id\n10,0.25,1\n20,2.5,1\n30,,1\n";
        let frames = read_frames(&write(&dir, "frames.csv", frames)).unwrap();
        let field = |frame_id| SavedField {
            path: dir.join(format!("field_{frame_id}.csv")),
            frame_id,
            first_px: [0.0; 2],
            step_px: 1.0,
            cols: 0,
            rows: 0,
            gradients: vec![],
            displacements_px: vec![],
        };
        let source = ForceSource::RigLog(rig);
        assert_eq!(
            frame_forces(&frames, &source, &field(10)).unwrap(),
            (1, [2.5, 5.0, 7.5, 10.0])
        );
        let e = frame_forces(&frames, &source, &field(20))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("frames.csv: line 3: frame 20: rig time 2.5 s is outside")
                && e.contains("rig.csv (0 to 1 s)"),
            "{e}"
        );
        let e = frame_forces(&frames, &source, &field(30))
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 4: frame 30: no rig time"), "{e}");
        let e = frame_forces(&frames, &source, &field(40))
            .unwrap_err()
            .to_string();
        assert!(e.contains("field_40.csv: frame 40 has no row in"), "{e}");
        // Forces from frames.csv: an older one without the grip columns has none here.
        let e = frame_forces(&frames, &ForceSource::Frames, &field(10))
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2: frame 10: no grip forces"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
