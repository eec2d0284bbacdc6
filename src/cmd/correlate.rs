//! `dicstream correlate REF DEF... --out DIR`: offline correlation (IC-GN or CORRELI-GD) on
//! image files.
//!
//! Writes `DIR/field_NNNN.csv` per deformed image (NNNN from 0001 in argument order),
//! `DIR/summary.json` (rewritten after every frame), and with `--vtk` / `--png` a legacy VTK
//! structured grid and figures of u, v, exx, eyy, exy over the reference image. Every file is
//! written atomically (temporary sibling, then rename). Images are read by `producer::read_image`.

use super::gauge_report::reading_line;
use super::named_arg::named;
use anyhow::{anyhow, bail, Context, Result};
use correlator::settings::{Method, ReferenceKind};
use correlator::{
    ControlGauge, Correlator, CorrelatorSettings, Field, Gauge, GuessMode, Polygon, ReferenceMode,
    Region, RoiChoice, StrainMeasure,
};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;
use wire::colour_range::RangeChoice;
use wire::scale::MmPerPx;

/// The library's defaults, the command line's defaults.
fn defaults() -> CorrelatorSettings {
    CorrelatorSettings::default()
}

/// The correlation settings of both `correlate` and `correlator` (their reference-mode flags
/// differ: `--reference` here, `--reference-mode` live, where `--reference` names a file).
#[derive(clap::Args, Debug)]
pub struct CorrelationArgs {
    /// Sub-pixel method. correli: CORRELI-GD as published (rigid 2^s ZOIs, Fourier-shift
    /// iterations; the default: several times faster, robust on low-contrast noisy images);
    /// icgn1: inverse compositional Gauss-Newton, first-order (affine) shape function, ZNSSD,
    /// quintic B-spline (about 1.5 times less noise, any subset size from 9 px); icgn2: the same
    /// with a second-order shape function; icgn: the order chosen per node (second order where
    /// the field's curvature biases the first, icgn1 elsewhere). See the README.
    #[arg(long, value_parser = named::<Method>(), default_value_t = defaults().method)]
    pub method: Method,
    /// ZOI (subset) side in px: any size from 9 px for the IC-GN methods (odd or even), a power of
    /// two (2^s) for correli.
    #[arg(long, default_value_t = defaults().zoi_px)]
    pub zoi: usize,
    /// Distance between ZOI centres in px (1 ..= ZOI).
    #[arg(long, default_value_t = defaults().step_px)]
    pub step: usize,
    /// The rectangle measured: margin (the whole image less half a ZOI on each side, so that a
    /// border node can move by the integer search's reach before its ZOI leaves the image),
    /// centred-pow2 (the paper's largest centred 2^p square) or x,y,w,h in px.
    #[arg(long, default_value_t = RoiChoice::Margin)]
    pub roi: RoiChoice,
    /// A polygon in image px, "x,y x,y x,y ..." (at least 3 vertices, not crossing itself,
    /// inside the image); repeat for several (their union). A node is measured only when its
    /// whole ZOI lies inside the region; the others are outside_region.
    #[arg(long = "polygon", value_name = "X,Y X,Y X,Y...")]
    pub polygons: Vec<Polygon>,
    /// A mask image the size of the images (PNG, TIFF or BMP): non-zero pixels are measured.
    #[arg(long)]
    pub mask: Option<PathBuf>,
    /// A virtual strain gauge or extensometer placed in the reference image (px), read on
    /// every frame: NAME=rect:X,Y,W,H, NAME=polygon:x,y x,y x,y ... (the mean strain of the
    /// valid nodes inside) or NAME=extensometer:x,y x,y (the two points followed, their
    /// elongation); repeat for several.
    #[arg(long = "gauge", value_name = "NAME=KIND:POINTS")]
    pub gauges: Vec<Gauge>,
    /// The gauge whose strains are the field's `gauge` (a live field's header; what strain
    /// control closes its loop on): centre (the mesh's central half), all (every valid node)
    /// or the name of a --gauge rect or polygon.
    #[arg(long, default_value_t = defaults().control_gauge)]
    pub control_gauge: ControlGauge,
    /// Strain measure of the node strains (the gauge is given in all four).
    #[arg(long, value_parser = named::<StrainMeasure>(), default_value_t = defaults().strain)]
    pub strain: StrainMeasure,
    /// Initial guess per ZOI. auto: the cheapest guess that passes the final check (previous
    /// field, significant global (U0, V0)), failed nodes grown from verified neighbours,
    /// keypoints (rotation- and scale-invariant) when too few verify. correli: the paper's
    /// global (U0, V0). predict: previous field, or grown from the centre.
    #[arg(long, value_parser = named::<GuessMode>(), default_value_t = defaults().guess)]
    pub guess: GuessMode,
    /// A node is ok only when the ZNCC of its reference ZOI with the deformed image, sampled
    /// at its displacement and local gradient, reaches this (0 < value < 1).
    #[arg(long, default_value_t = defaults().min_zncc)]
    pub min_zncc: f64,
    /// Remove, to first order, the rigid ZOI's bias under a displacement gradient (beyond the
    /// paper; false = CORRELI-GD as published).
    #[arg(long, default_value_t = defaults().gradient_correction, action = clap::ArgAction::Set)]
    pub gradient_correction: bool,
    /// Worker threads.
    #[arg(long, default_value_t = defaults().threads)]
    pub threads: usize,
    /// Cap of the sub-pixel iterations per ZOI (Gauss-Newton for IC-GN, Fourier-shift for
    /// correli); an IC-GN node that has not converged at the cap is not_converged.
    #[arg(long, default_value_t = defaults().max_iterations)]
    pub max_iterations: u32,
}

impl CorrelationArgs {
    pub fn settings(&self, reference: ReferenceKind) -> CorrelatorSettings {
        CorrelatorSettings {
            zoi_px: self.zoi,
            method: self.method,
            step_px: self.step,
            region: Region {
                roi: self.roi,
                polygons: self.polygons.clone(),
                mask: self.mask.clone(),
            },
            strain: self.strain,
            reference: ReferenceMode::of_kind(reference, self.method),
            guess: self.guess,
            min_zncc: self.min_zncc,
            gradient_correction: self.gradient_correction,
            threads: self.threads,
            max_iterations: self.max_iterations,
            gauges: self.gauges.clone(),
            control_gauge: self.control_gauge.clone(),
            ..CorrelatorSettings::default()
        }
    }
}

#[derive(clap::Args, Debug)]
pub struct CorrelateArgs {
    /// Reference image (PNG, TIFF or BMP, 8 or 16 bit).
    pub reference: PathBuf,
    /// Deformed images, in order.
    #[arg(required = true)]
    pub deformed: Vec<PathBuf>,
    /// Reference mode: fixed, incremental (consecutive images) or auto update.
    #[arg(long = "reference", value_parser = named::<ReferenceKind>(), default_value_t = ReferenceKind::Fixed)]
    pub reference_mode: ReferenceKind,
    #[command(flatten)]
    pub correlation: CorrelationArgs,
    /// Output folder (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// The image's scale, mm per px: the field files get x_mm,y_mm,u_mm,v_mm beside the px
    /// columns (without a scale, or --known-length, px only).
    #[arg(long, value_name = "MM_PER_PX", conflicts_with = "known_length")]
    pub mm_per_px: Option<wire::scale::MmPerPx>,
    /// The scale from a known length: two points of the reference image (px) and the distance
    /// between them on the specimen (mm), "X1,Y1 X2,Y2 MM".
    #[arg(long, value_name = "X1,Y1 X2,Y2 MM")]
    pub known_length: Option<wire::scale::KnownLength>,
    /// Also write the fields for ParaView: legacy VTK structured grids (field_NNNN.vtk), VTK
    /// XML ones (field_NNNN.vts) and fields.pvd, their collection (time step = image index).
    #[arg(long)]
    pub vtk: bool,
    /// Also write figures of u, v, exx, eyy and exy over the reference image
    /// (u_NNNN.png, v_NNNN.png, exx_NNNN.png, ...), each with its title and colour bar.
    #[arg(long)]
    pub png: bool,
    /// The figures' colour range: auto (the 2nd to 98th percentile of the valid nodes, at
    /// least 30 times the field's own noise wide, so that a uniform field shows one colour),
    /// symmetric (about zero) or LO:HI (in the quantity's unit: px, or strain as a fraction,
    /// e.g. -0.01:0.01). A signed quantity across zero takes a blue-white-red map centred on
    /// zero, any other viridis.
    #[arg(
        long,
        default_value_t = RangeChoice::Auto,
        value_name = "auto|symmetric|LO:HI",
        allow_hyphen_values = true
    )]
    pub range: RangeChoice,
}

impl CorrelateArgs {
    fn settings(&self) -> CorrelatorSettings {
        self.correlation.settings(self.reference_mode)
    }

    /// The scale given, directly or from a known length (None: px only).
    fn scale(&self) -> Option<MmPerPx> {
        self.mm_per_px
            .or_else(|| self.known_length.map(|k| k.scale()))
    }

    /// How the scale was given, for `summary.json`.
    fn scale_from(&self) -> Option<String> {
        match (&self.mm_per_px, &self.known_length) {
            (Some(_), _) => Some("--mm-per-px".to_string()),
            (None, Some(k)) => Some(format!(
                "--known-length {k} ({:.3} px apart)",
                k.distance_px()
            )),
            (None, None) => None,
        }
    }
}

pub(crate) fn load(path: &Path) -> Result<producer::Image16> {
    // producer's errors already name the file, what was expected and their cause: keep the
    // message only (as a chain, the cause would be printed twice).
    producer::read_image(path).map_err(|e| anyhow::Error::msg(e.to_string()))
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    producer::write_atomic(path, bytes).with_context(|| format!("cannot write {}", path.display()))
}

pub fn run(args: CorrelateArgs) -> Result<()> {
    let settings = args.settings();
    let reference = load(&args.reference)?;
    let (width, height) = (reference.width as usize, reference.height as usize);
    let mut correlator = Correlator::new(settings.clone(), width, height).with_context(|| {
        format!(
            "settings refused for the {width}x{height} px reference {}",
            args.reference.display()
        )
    })?;
    correlator.set_reference(&reference.pixels)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create output folder {}", args.out.display()))?;
    write_units(&args, settings.strain)?;
    let mut pvd = correlator::pvd::Pvd::new();
    let progress = progress_bar(args.deformed.len());
    let settings_value = settings_json(&args, &correlator);
    let mut frames = Vec::new();
    let mut frames_with_valid_nodes = 0usize;
    let mut valid = Vec::with_capacity(args.deformed.len());
    for (i, path) in args.deformed.iter().enumerate() {
        let index = i + 1;
        let image = load(path)?;
        if (image.width, image.height) != (reference.width, reference.height) {
            bail!(
                "image {} is {}x{} px, expected {width}x{height} px like the reference {}",
                path.display(),
                image.width,
                image.height,
                args.reference.display()
            );
        }
        let t = Instant::now();
        let field = correlator.correlate(&image.pixels)?;
        let elapsed_ms = t.elapsed().as_secs_f64() * 1e3;
        frames_with_valid_nodes += usize::from(field.valid > 0);
        valid.push(field.valid);
        warn_if_few_valid(path, field, progress.as_ref());
        write_field_files(&args, &reference, field, index, &mut pvd)?;
        frames.push(frame_json(
            index,
            path,
            field,
            &args.correlation.gauges,
            elapsed_ms,
        ));
        let summary = serde_json::json!({ "frames": frames, "settings": settings_value });
        write(
            &args.out.join("summary.json"),
            serde_json::to_string_pretty(&summary)?.as_bytes(),
        )?;
        if let Some(bar) = &progress {
            bar.set_message(format!("{} valid of {}", field.valid, field.in_region()));
            bar.inc(1);
        }
    }
    if let Some(bar) = progress {
        bar.finish();
    }
    eprintln!("{}", summary_line(&correlator, &valid));
    let settings = correlator.settings();
    for (gauge, reading) in settings.gauges.iter().zip(&correlator.field().gauges) {
        eprintln!("{}", reading_line(gauge, reading));
    }
    if frames_with_valid_nodes == 0 {
        return Err(nothing_measured(&args));
    }
    Ok(())
}

/// The line after the run: where it measured and how much of it is valid, e.g.
/// `correlate: ROI x 16-2032 y 16-573 (polygon 5 vertices), 3906 nodes, 3890 valid`
/// (x and y the mesh rectangle's first pixel and one past its last; with several frames the
/// last frame's valid count and the fewest).
fn summary_line(correlator: &Correlator, valid: &[usize]) -> String {
    let region = &correlator.settings().region;
    let shape = region
        .shape_description()
        .map_or(format!(" ({})", region.roi), |shape| format!(" ({shape})"));
    let valid_text = match valid {
        [] => String::new(),
        [one] => format!(", {one} valid"),
        [.., last] => format!(
            ", {last} valid in the last of {} frames (fewest {})",
            valid.len(),
            valid.iter().min().copied().unwrap_or(0)
        ),
    };
    format!(
        "correlate: ROI {}{shape}, {} nodes{valid_text}",
        correlator.roi().extent(),
        correlator.nodes_in_region(),
    )
}

/// A progress bar over `frames` frames, on a terminal only.
fn progress_bar(frames: usize) -> Option<indicatif::ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(frames as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} frames, {elapsed} elapsed, eta {eta} {msg}",
        )
        .expect("valid progress template"),
    );
    Some(bar)
}

/// A warning (above the progress bar, if any) when fewer than half of the nodes are valid.
fn warn_if_few_valid(path: &Path, field: &Field, progress: Option<&indicatif::ProgressBar>) {
    if 2 * field.valid < field.in_region() {
        let warning = format!(
            "warning: {}: only {} of {} nodes valid ({})",
            path.display(),
            field.valid,
            field.in_region(),
            field.refusals()
        );
        match progress {
            Some(bar) => bar.println(warning),
            None => eprintln!("{warning}"),
        }
    }
}

/// The files of frame `index`: its field as CSV, and as VTK and colour maps if asked for.
fn write_field_files(
    args: &CorrelateArgs,
    reference: &producer::Image16,
    field: &Field,
    index: usize,
    pvd: &mut correlator::pvd::Pvd,
) -> Result<()> {
    let mut text = String::new();
    correlator::output::field_csv_scaled(field, args.scale(), &mut text);
    write(
        &args.out.join(format!("field_{index:04}.csv")),
        text.as_bytes(),
    )?;
    if args.vtk {
        correlator::output::field_vtk(
            field,
            &format!("dicstream correlate field {index:04}"),
            &mut text,
        );
        write(
            &args.out.join(format!("field_{index:04}.vtk")),
            text.as_bytes(),
        )?;
        let vts = format!("field_{index:04}.vts");
        correlator::vts::field_vts(field, args.scale(), &mut text);
        write(&args.out.join(&vts), text.as_bytes())?;
        pvd.push(vts, index as f64);
        write(&args.out.join(PVD), pvd.to_xml().as_bytes())?;
    }
    if args.png {
        write_figures(args, reference, field, index)?;
    }
    Ok(())
}

/// The ParaView collection of the `.vts` fields, in the output folder.
const PVD: &str = "fields.pvd";

/// `units.json`: the unit of each column of the field files, their strain measure and scale.
fn write_units(args: &CorrelateArgs, strain: StrainMeasure) -> Result<()> {
    let fields = correlator::output::field_csv_units("field_*.csv", strain, args.scale());
    let units = serde_json::json!({
        "about": "units of the columns of this folder's CSV files (dicstream correlate)",
        "files": { "field_*.csv": fields },
    });
    write(
        &args.out.join(wire::column_units::SIDECAR),
        serde_json::to_string_pretty(&units)?.as_bytes(),
    )
}

/// Frame `index`'s entry of `summary.json`: the frame's summary (`correlator::summary`), its
/// index, file and time.
fn frame_json(
    index: usize,
    path: &Path,
    field: &Field,
    gauges: &[Gauge],
    elapsed_ms: f64,
) -> serde_json::Value {
    let mut entry = correlator::summary::frame_summary(field, gauges);
    entry["index"] = index.into();
    entry["file"] = path.display().to_string().into();
    entry["elapsed_ms"] = elapsed_ms.into();
    entry
}

/// The error when no node of any frame passed the final check, with a hint at why.
fn nothing_measured(args: &CorrelateArgs) -> anyhow::Error {
    let hint = match args.correlation.guess {
        GuessMode::Auto => "unrelated or flat images?",
        GuessMode::Correli | GuessMode::Predict => {
            "unrelated or flat images, or a motion beyond this guess (--guess auto also tries keypoints)?"
        }
    };
    anyhow!(
        "no node of any of the {} deformed images passed the final check against {}: \
         nothing was measured ({hint} the fields in {} say why per node)",
        args.deformed.len(),
        args.reference.display(),
        args.out.display()
    )
}

fn settings_json(args: &CorrelateArgs, correlator: &Correlator) -> serde_json::Value {
    let roi = correlator.roi();
    let (nx, ny) = correlator.mesh_size();
    serde_json::json!({
        "reference": args.reference.display().to_string(),
        "method": correlator.settings().method.name(),
        "zoi": args.correlation.zoi,
        "step": args.correlation.step,
        "roi": [roi.x_px, roi.y_px, roi.width_px, roi.height_px],
        "region": correlator.settings().region,
        "mesh": [nx, ny],
        "nodes_in_region": correlator.nodes_in_region(),
        "strain": correlator.settings().strain.name(),
        "reference_mode": args.reference_mode.name(),
        "guess": format!("{:?}", args.correlation.guess).to_lowercase(),
        "gradient_correction": args.correlation.gradient_correction,
        "min_zncc": args.correlation.min_zncc,
        "threads": args.correlation.threads,
        "max_iterations": args.correlation.max_iterations,
        "strain_window_nodes": correlator.settings().strain_window_nodes,
        "mm_per_px": args.scale().map(MmPerPx::get),
        "scale_from": args.scale_from(),
        "figure_range": args.range.to_string(),
    })
}

/// The quantities `--png` draws: file prefix, value, unit (px or strain) and what they are.
type Quantity = (
    &'static str,
    fn(&correlator::Node) -> f64,
    bool,
    &'static str,
);
const FIGURES: [Quantity; 5] = [
    ("u", |n| n.u_px, false, "displacement along x"),
    ("v", |n| n.v_px, false, "displacement along y"),
    ("exx", |n| n.exx, true, "strain xx"),
    ("eyy", |n| n.eyy, true, "strain yy"),
    ("exy", |n| n.exy, true, "strain xy (tensor)"),
];

/// Frame `index`'s figures of [`FIGURES`] over the reference image, each with its title and
/// colour bar (`correlator::output::colour_map_rgb`, `identifier::map_figure`).
fn write_figures(
    args: &CorrelateArgs,
    reference: &producer::Image16,
    field: &Field,
    index: usize,
) -> Result<()> {
    let settings = args.settings();
    let strain_lag = wire::colour_range::strain_noise_lag_nodes(settings.strain_window_nodes);
    let scale_note = args
        .scale()
        .map(|s| format!("; {s} mm per px"))
        .unwrap_or_default();
    for (name, value, strain, what) in FIGURES {
        let lag = if strain { strain_lag } else { 1 };
        let scale = correlator::output::field_colour_scale(field, value, true, lag, args.range);
        let rgb = correlator::output::colour_map_rgb(
            &reference.pixels,
            reference.width as usize,
            field,
            value,
            &scale,
        );
        let title = if strain {
            format!(
                "{name}, {what} ({} strain, %), image {index:04}",
                settings.strain.name()
            )
        } else {
            format!("{name}, {what} (px{scale_note}), image {index:04}")
        };
        let label = |v: f64| match strain {
            true => format!("{:+.3} %", 100.0 * v),
            false => format!("{v:+.3} px"),
        };
        let path = args.out.join(format!("{name}_{index:04}.png"));
        identifier::map_figure::write(
            &path,
            &identifier::map_figure::MapFigure {
                rgb: &rgb,
                width_px: reference.width as usize,
                height_px: reference.height as usize,
                title: &title,
                scale,
                label: &label,
                bar_title: None,
            },
        )
        .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}
