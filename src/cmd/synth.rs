//! `dicstream synth`: writes simulated speckle images with their exact ground truth.
//!
//! Output folder: `frame_00000.png` ... (or `.tif`), `truth.csv` (one row per frame: the imposed
//! homogeneous part x = c + F (X - c) + t) and `scenario.txt` (the full scenario spec). For a
//! heterogeneous scenario (`homogeneous` = false: chirp, bulge) F and t are the gradient and the
//! displacement at the centre; the displacement at any reference point X comes from the library:
//! `producer::Scenario::parse(spec, width, height)?.motion_at(frame, frames).displacement(X)`.

use super::named_arg::named;
use super::sim_args::SimArgs;
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context;
use producer::{write_atomic, write_frame, FrameSource, ImageFormatOut};

/// Options of `dicstream synth`.
#[derive(Debug, clap::Args)]
pub struct SynthArgs {
    #[command(flatten)]
    pub sim: SimArgs,
    /// Number of frames; frame 0 is the reference, the motion ramps to its final value
    #[arg(long, default_value_t = 5)]
    pub frames: u64,
    /// Output folder (created if missing)
    #[arg(long)]
    pub out: PathBuf,
    /// Image format [default: png8 for 8-bit cameras, png16 otherwise]
    #[arg(long, value_parser = named::<ImageFormatOut>())]
    pub format: Option<ImageFormatOut>,
}

/// Maximum number of frames written by one call.
const MAX_FRAMES: u64 = 100_000;

pub fn run(args: SynthArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        (1..=MAX_FRAMES).contains(&args.frames),
        "--frames {}: expected 1 to {MAX_FRAMES}",
        args.frames
    );
    let spec = args.sim.scenario_spec();
    let mut camera = args
        .sim
        .build(args.frames)
        .context("building the simulated camera")?;
    let dims = camera.dims();
    let format = args
        .format
        .unwrap_or(ImageFormatOut::for_bit_depth(dims.bit_depth));
    anyhow::ensure!(
        !(format == ImageFormatOut::Png8 && dims.bit_depth > 8),
        "--format png8 cannot hold a {}-bit camera: use png16 or tiff",
        dims.bit_depth
    );
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating output folder {}", args.out.display()))?;
    let scenario = args.sim.scenario()?;
    let info = format!(
        "spec={spec}\nwidth={}\nheight={}\nframes={}\nbit_depth={}\n\
         # displacement at reference point X of frame k:\n\
         # producer::Scenario::parse(spec, width, height)?.motion_at(k, frames).displacement(X)\n",
        dims.width, dims.height, args.frames, dims.bit_depth
    );
    write_atomic(&args.out.join("scenario.txt"), info.as_bytes())?;
    let mut csv =
        String::from("frame,F11,F12,F21,F22,tx_px,ty_px,cx_px,cy_px,scenario,homogeneous,file\n");
    let mut pixels = vec![0u16; dims.len_px()];
    let mut encoded = Vec::new();
    let started = std::time::Instant::now();
    while let Some(frame) = camera.next_frame(&mut pixels)? {
        let truth = frame.truth.expect("simulated frames carry their truth");
        let name = format!("frame_{:05}.{}", frame.index, format.extension());
        let path = args.out.join(&name);
        write_frame(&path, dims, &pixels, format, &mut encoded)?;
        // `+ 0.0` turns -0 into 0 in the file.
        let [[f11, f12], [f21, f22]] = truth.f.map(|row| row.map(|v| v + 0.0));
        writeln!(
            csv,
            "{},{f11:.17e},{f12:.17e},{f21:.17e},{f22:.17e},{:.17e},{:.17e},{},{},{},{},{name}",
            frame.index,
            truth.translation_px[0] + 0.0,
            truth.translation_px[1] + 0.0,
            truth.centre_px[0],
            truth.centre_px[1],
            scenario.kind.name(),
            truth.homogeneous,
        )?;
        // Flushed per frame, atomically: truth.csv always matches the images on disk.
        write_atomic(&args.out.join("truth.csv"), csv.as_bytes())?;
    }
    println!(
        "synth: {} frames of {}x{} at {} bit, scenario {spec}, written to {} in {:.2} s",
        args.frames,
        dims.width,
        dims.height,
        dims.bit_depth,
        args.out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
