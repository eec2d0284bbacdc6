//! `dicstream correlate REF DEF... --out DIR`: offline CORRELI-GD on image files.
//!
//! Writes `DIR/field_NNNN.csv` per deformed image (NNNN from 0001 in argument order),
//! `DIR/summary.json` (rewritten after every frame), and with `--vtk` / `--png` a legacy VTK
//! structured grid and colour maps of |u| and exx over the reference image. Every file is
//! written atomically (temporary sibling, then rename). Images are read by `producer::read_image`.

use anyhow::{bail, Context, Result};
use correlator::{
    Correlator, CorrelatorSettings, Field, GaugeStrains, GuessMode, NodeStatus, ReferenceMode, Roi,
    StrainMeasure,
};
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum StrainArg {
    Log,
    Green,
    Nominal,
    Small,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum ReferenceArg {
    Fixed,
    Incremental,
    Auto,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum GuessArg {
    Correli,
    Predict,
}

#[derive(clap::Args, Debug)]
pub struct CorrelateArgs {
    /// Reference image (PNG, TIFF or BMP, 8 or 16 bit).
    pub reference: PathBuf,
    /// Deformed images, in order.
    #[arg(required = true)]
    pub deformed: Vec<PathBuf>,
    /// ZOI side in px, a power of two (2^s).
    #[arg(long, default_value_t = 32)]
    pub zoi: usize,
    /// Distance between ZOI centres in px (1 ..= ZOI).
    #[arg(long, default_value_t = 16)]
    pub step: usize,
    /// Region of interest x,y,w,h in px (default: the largest centred 2^p square).
    #[arg(long, value_parser = parse_roi)]
    pub roi: Option<Roi>,
    /// Strain measure of the per-node strains in the CSV.
    #[arg(long, value_enum, default_value = "log")]
    pub strain: StrainArg,
    /// Reference mode: fixed, incremental (consecutive images) or auto update.
    #[arg(long = "reference", value_enum, default_value = "fixed")]
    pub reference_mode: ReferenceArg,
    /// Initial guess per ZOI: the paper's global (U0, V0), or predicted from neighbours/previous field.
    #[arg(long, value_enum, default_value = "predict")]
    pub guess: GuessArg,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Cap of the sub-pixel iterations per ZOI.
    #[arg(long, default_value_t = 10)]
    pub max_iterations: u32,
    /// Output folder (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write legacy VTK structured grids (field_NNNN.vtk) for ParaView.
    #[arg(long)]
    pub vtk: bool,
    /// Also write colour maps of |u| and exx over the reference image (u_NNNN.png, exx_NNNN.png).
    #[arg(long)]
    pub png: bool,
}

pub(crate) fn parse_roi(text: &str) -> Result<Roi, String> {
    let values: Vec<usize> = text
        .split(',')
        .map(|v| v.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("ROI '{text}': expected four non-negative integers x,y,w,h"))?;
    match values[..] {
        [x_px, y_px, width_px, height_px] => Ok(Roi {
            x_px,
            y_px,
            width_px,
            height_px,
        }),
        _ => Err(format!(
            "ROI '{text}': expected four values x,y,w,h, got {}",
            values.len()
        )),
    }
}

impl CorrelateArgs {
    fn settings(&self) -> CorrelatorSettings {
        CorrelatorSettings {
            zoi_px: self.zoi,
            step_px: self.step,
            roi: self.roi,
            strain: match self.strain {
                StrainArg::Log => StrainMeasure::Log,
                StrainArg::Green => StrainMeasure::Green,
                StrainArg::Nominal => StrainMeasure::Nominal,
                StrainArg::Small => StrainMeasure::Small,
            },
            reference: match self.reference_mode {
                ReferenceArg::Fixed => ReferenceMode::Fixed,
                ReferenceArg::Incremental => ReferenceMode::Incremental,
                ReferenceArg::Auto => ReferenceMode::AUTO_DEFAULT,
            },
            guess: match self.guess {
                GuessArg::Correli => GuessMode::Correli,
                GuessArg::Predict => GuessMode::Predict,
            },
            threads: self.threads,
            max_iterations: self.max_iterations,
            ..CorrelatorSettings::default()
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
    let progress = if std::io::stderr().is_terminal() {
        let bar = indicatif::ProgressBar::new(args.deformed.len() as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} frames, {elapsed} elapsed, eta {eta} {msg}",
            )
            .expect("valid progress template"),
        );
        Some(bar)
    } else {
        None
    };
    let settings_value = settings_json(&args, &correlator);
    let mut frames = Vec::new();
    let mut text = String::new();
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
        field_csv(field, &mut text);
        write(
            &args.out.join(format!("field_{index:04}.csv")),
            text.as_bytes(),
        )?;
        if args.vtk {
            field_vtk(field, index, &mut text);
            write(
                &args.out.join(format!("field_{index:04}.vtk")),
                text.as_bytes(),
            )?;
        }
        if args.png {
            let magnitude = |n: &correlator::Node| n.u_px.hypot(n.v_px);
            write(
                &args.out.join(format!("u_{index:04}.png")),
                &colour_map(&reference, field, magnitude)?,
            )?;
            write(
                &args.out.join(format!("exx_{index:04}.png")),
                &colour_map(&reference, field, |n| n.exx)?,
            )?;
        }
        frames.push(serde_json::json!({
            "index": index,
            "file": path.display().to_string(),
            "nodes": field.nodes.len(),
            "valid": field.valid,
            "u_mean": field.u_mean_px,
            "v_mean": field.v_mean_px,
            "gauge": gauge_json(&field.gauge),
            "elapsed_ms": elapsed_ms,
            "reference_updated": field.reference_updated,
        }));
        let summary = serde_json::json!({ "frames": frames, "settings": settings_value });
        write(
            &args.out.join("summary.json"),
            serde_json::to_string_pretty(&summary)?.as_bytes(),
        )?;
        if let Some(bar) = &progress {
            bar.set_message(format!("{} valid of {}", field.valid, field.nodes.len()));
            bar.inc(1);
        }
    }
    if let Some(bar) = progress {
        bar.finish();
    }
    Ok(())
}

fn gauge_json(g: &GaugeStrains) -> serde_json::Value {
    let one =
        |s: correlator::Strain2| serde_json::json!({ "exx": s.exx, "eyy": s.eyy, "exy": s.exy });
    serde_json::json!({ "small": one(g.small), "green": one(g.green), "nominal": one(g.nominal), "log": one(g.log) })
}

fn settings_json(args: &CorrelateArgs, correlator: &Correlator) -> serde_json::Value {
    let roi = correlator.roi();
    let (nx, ny) = correlator.mesh_size();
    serde_json::json!({
        "reference": args.reference.display().to_string(),
        "zoi": args.zoi,
        "step": args.step,
        "roi": [roi.x_px, roi.y_px, roi.width_px, roi.height_px],
        "mesh": [nx, ny],
        "strain": correlator.settings().strain.name(),
        "reference_mode": format!("{:?}", args.reference_mode).to_lowercase(),
        "guess": format!("{:?}", args.guess).to_lowercase(),
        "threads": args.threads,
        "max_iterations": args.max_iterations,
        "strain_window_nodes": correlator.settings().strain_window_nodes,
    })
}

/// The CSV contract of issue 3: header `x,y,u,v,exx,eyy,exy,score,iterations,status`.
fn field_csv(field: &Field, text: &mut String) {
    text.clear();
    text.push_str("x,y,u,v,exx,eyy,exy,score,iterations,status\n");
    for n in &field.nodes {
        let _ = writeln!(
            text,
            "{},{},{:.6},{:.6},{:.7},{:.7},{:.7},{:.5},{},{}",
            n.x_px,
            n.y_px,
            n.u_px,
            n.v_px,
            n.exx,
            n.eyy,
            n.exy,
            n.score,
            n.iterations,
            n.status.word()
        );
    }
}

/// Legacy VTK structured grid at the reference node positions (z = 0).
fn field_vtk(field: &Field, index: usize, text: &mut String) {
    text.clear();
    let count = field.nodes.len();
    let _ = write!(
        text,
        "# vtk DataFile Version 3.0\ndicstream correlate field {index:04}\nASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS {} {} 1\nPOINTS {count} double\n",
        field.nx, field.ny
    );
    for n in &field.nodes {
        let _ = writeln!(text, "{} {} 0", n.x_px, n.y_px);
    }
    let _ = writeln!(text, "POINT_DATA {count}\nVECTORS displacement_px double");
    for n in &field.nodes {
        let _ = writeln!(text, "{} {} 0", n.u_px, n.v_px);
    }
    type Get = fn(&correlator::Node) -> f64;
    let scalars: [(&str, Get); 6] = [
        ("exx", |n| n.exx),
        ("eyy", |n| n.eyy),
        ("exy", |n| n.exy),
        ("score", |n| n.score),
        ("iterations", |n| n.iterations as f64),
        ("valid", |n| f64::from(u8::from(n.status == NodeStatus::Ok))),
    ];
    for (name, get) in scalars {
        let _ = writeln!(text, "SCALARS {name} double 1\nLOOKUP_TABLE default");
        for n in &field.nodes {
            let _ = writeln!(text, "{}", get(n));
        }
    }
}

/// RGB PNG: the reference in grey, overlaid inside the mesh with a blue-to-red map of `value`
/// (bilinear between valid nodes, range = min..max over valid nodes).
fn colour_map(
    reference: &producer::Image16,
    field: &Field,
    value: impl Fn(&correlator::Node) -> f64,
) -> Result<Vec<u8>> {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let max_grey = reference.pixels.iter().copied().max().unwrap_or(1).max(1) as f64;
    let valid: Vec<f64> = field
        .nodes
        .iter()
        .filter(|n| n.status == NodeStatus::Ok)
        .map(&value)
        .collect();
    let (lo, hi) = valid
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    let mut rgb = vec![0u8; w * h * 3];
    for (k, &p) in reference.pixels.iter().enumerate() {
        let g = (255.0 * p as f64 / max_grey) as u8;
        rgb[3 * k..3 * k + 3].copy_from_slice(&[g, g, g]);
    }
    if field.nx >= 2 && field.ny >= 2 && !valid.is_empty() {
        let first = field.node(0, 0);
        let last = field.node(field.nx - 1, field.ny - 1);
        let (sx, sy) = (
            (last.x_px - first.x_px) / (field.nx - 1) as f64,
            (last.y_px - first.y_px) / (field.ny - 1) as f64,
        );
        for y in first.y_px.ceil() as usize..=(last.y_px.floor() as usize).min(h - 1) {
            for x in first.x_px.ceil() as usize..=(last.x_px.floor() as usize).min(w - 1) {
                let fx = (x as f64 - first.x_px) / sx;
                let fy = (y as f64 - first.y_px) / sy;
                let (i, j) = (
                    (fx as usize).min(field.nx - 2),
                    (fy as usize).min(field.ny - 2),
                );
                let (tx, ty) = (fx - i as f64, fy - j as f64);
                let corners = [
                    (i, j, (1.0 - tx) * (1.0 - ty)),
                    (i + 1, j, tx * (1.0 - ty)),
                    (i, j + 1, (1.0 - tx) * ty),
                    (i + 1, j + 1, tx * ty),
                ];
                let (mut sum, mut weight) = (0.0, 0.0);
                for (ci, cj, wgt) in corners {
                    let node = field.node(ci, cj);
                    if node.status == NodeStatus::Ok {
                        sum += wgt * value(node);
                        weight += wgt;
                    }
                }
                if weight <= 1e-9 {
                    continue;
                }
                let t = ((sum / weight - lo) / span).clamp(0.0, 1.0);
                let colour = [
                    255.0 * t,
                    255.0 * (1.0 - (2.0 * t - 1.0).abs()),
                    255.0 * (1.0 - t),
                ];
                let px = &mut rgb[3 * (y * w + x)..3 * (y * w + x) + 3];
                for (c, &col) in px.iter_mut().zip(&colour) {
                    *c = (0.35 * *c as f64 + 0.65 * col) as u8;
                }
            }
        }
    }
    let mut bytes = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut bytes),
        &rgb,
        w as u32,
        h as u32,
        image::ExtendedColorType::Rgb8,
    )
    .context("PNG encoding of the colour map")?;
    Ok(bytes)
}
