//! `dicstream correlator`: the live correlation process (subscribes to `frames`, publishes
//! `fields`, saves its reference to `--state-dir` to survive a restart).

use super::correlate::{parse_roi, GuessArg, ReferenceArg, StrainArg};
use anyhow::{bail, Context, Result};
use correlator::process::{run as run_process, ProcessConfig, ReferenceImage};
use correlator::{CorrelatorSettings, Roi};
use std::path::PathBuf;
use std::time::Duration;

#[derive(clap::Args, Debug)]
pub struct CorrelatorArgs {
    /// Instance name (shared-memory prefix); runs with different names never meet.
    #[arg(long, default_value_t = wire::Instance::default_name())]
    pub instance: String,
    /// Reference image file (PNG, TIFF or BMP); default: the first frame received.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// ZOI side in px, a power of two (2^s).
    #[arg(long, default_value_t = 32)]
    pub zoi: usize,
    /// Distance between ZOI centres in px (1 ..= ZOI).
    #[arg(long, default_value_t = 16)]
    pub step: usize,
    /// Region of interest x,y,w,h in px (default: the largest centred 2^p square).
    #[arg(long, value_parser = parse_roi)]
    pub roi: Option<Roi>,
    /// Strain measure of the node strains (the header carries the gauge in all four).
    #[arg(long, value_enum, default_value = "log")]
    pub strain: StrainArg,
    /// Reference mode: fixed, incremental (previous frame) or auto update.
    #[arg(long, value_enum, default_value = "fixed")]
    pub reference_mode: ReferenceArg,
    /// Initial guess per ZOI: the paper's global (U0, V0), or the previous frame's field.
    #[arg(long, value_enum, default_value = "predict")]
    pub guess: GuessArg,
    /// Remove, to first order, the rigid ZOI's bias under a displacement gradient (beyond the
    /// paper; false = CORRELI-GD as published).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub gradient_correction: bool,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Cap of the sub-pixel iterations per ZOI.
    #[arg(long, default_value_t = 10)]
    pub max_iterations: u32,
    /// Folder for the reference and what is needed to resume after a restart (created if
    /// missing); a process started on a folder holding a saved reference resumes against it.
    #[arg(long)]
    pub state_dir: Option<PathBuf>,
    /// Stop after publishing this many fields.
    #[arg(long)]
    pub max_frames: Option<u64>,
    /// Stop after this many seconds without a frame.
    #[arg(long)]
    pub idle_timeout_s: Option<f64>,
}

impl CorrelatorArgs {
    fn settings(&self) -> CorrelatorSettings {
        CorrelatorSettings {
            zoi_px: self.zoi,
            step_px: self.step,
            roi: self.roi,
            strain: self.strain.measure(),
            reference: self.reference_mode.mode(),
            guess: self.guess.mode(),
            gradient_correction: self.gradient_correction,
            threads: self.threads,
            max_iterations: self.max_iterations,
            ..CorrelatorSettings::default()
        }
    }
}

pub fn run(args: CorrelatorArgs) -> Result<()> {
    let settings = args.settings();
    settings.validate().context("correlator settings")?;
    let idle_timeout = match args.idle_timeout_s {
        Some(s) if s.is_finite() && s > 0.0 => Some(Duration::from_secs_f64(s)),
        Some(s) => bail!("--idle-timeout-s must be a positive number of seconds, got {s}"),
        None => None,
    };
    let reference = match &args.reference {
        Some(path) => {
            let image = super::correlate::load(path)?;
            Some(ReferenceImage {
                width_px: image.width as usize,
                height_px: image.height as usize,
                pixels: image.pixels,
                label: path.display().to_string(),
            })
        }
        None => None,
    };
    let config = ProcessConfig {
        reference,
        state_dir: args.state_dir.clone(),
        max_frames: args.max_frames,
        idle_timeout,
        ..ProcessConfig::new(&args.instance, settings)
    };
    let summary = run_process(config).map_err(|e| anyhow::anyhow!("correlator process: {e}"))?;
    eprintln!("{}", summary.final_line());
    Ok(())
}
