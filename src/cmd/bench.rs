//! `dicstream bench ...`: speed figures a user can reproduce on their machine. One subcommand
//! per benchmark (`BenchCommand`); `correlate` measures the correlator on rendered speckle.

mod correlate;
mod correlate_report;

use super::named_arg::named;
use anyhow::Result;
use correlator::settings::{GuessMode, Method};

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub command: BenchCommand,
}

/// The benchmarks.
#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Correlator throughput on rendered speckle (or two image files): ZOIs/s and frames/s per
    /// thread count, the time split (FFT, window, peak, shift, other; with IC-GN also the
    /// interpolation coefficients, the iterations and the check), the IC-GN cost against
    /// CORRELI-GD at 32 px in the same run, and a plain 2-D FFT timing for scale.
    Correlate(CorrelateBenchArgs),
    /// The live bench as processes on this machine: per-frame latency from capture to field
    /// and to identification, sustained rate, drops, CPU per process; `--fps max` finds the
    /// highest rate without drops.
    Pipeline(super::bench_pipeline::PipelineBenchArgs),
}

#[derive(clap::Args, Debug)]
pub struct CorrelateBenchArgs {
    /// Image width in px.
    #[arg(long, default_value_t = 1024)]
    pub width: usize,
    /// Image height in px.
    #[arg(long, default_value_t = 1024)]
    pub height: usize,
    /// Sub-pixel method: icgn1, icgn2, icgn or correli.
    #[arg(long, value_parser = named::<Method>(), default_value_t = Method::default())]
    pub method: Method,
    /// ZOI (subset) side in px (a power of two for correli).
    #[arg(long, default_value_t = 32)]
    pub zoi: usize,
    /// Correlate these two image files (reference, deformed) instead of rendered speckle, over
    /// the whole image (e.g. DIC Challenge sample 14).
    #[arg(long, value_delimiter = ',')]
    pub images: Option<Vec<std::path::PathBuf>>,
    /// Distance between ZOI centres in px.
    #[arg(long, default_value_t = 16)]
    pub step: usize,
    /// Thread counts to measure, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// Timed frames per thread count (the median is reported).
    #[arg(long, default_value_t = 9)]
    pub frames: usize,
    /// Initial guess: auto (the default), predict (the live path without growth or
    /// keypoints) or correli (the paper's).
    #[arg(long, value_parser = named::<GuessMode>(), default_value_t = GuessMode::default())]
    pub guess: GuessMode,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: BenchArgs) -> Result<()> {
    match args.command {
        BenchCommand::Correlate(args) => correlate::CorrelateBench::new(args)?.run(),
        BenchCommand::Pipeline(args) => super::bench_pipeline::run(args),
    }
}
