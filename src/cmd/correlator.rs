//! `dicstream correlator`: the live correlation process (subscribes to `frames`, publishes
//! `fields`, saves its reference to `--state-dir` to survive a restart).

use super::correlate::CorrelationArgs;
use super::named_arg::named;
use anyhow::{bail, Context, Result};
use correlator::process::{run as run_process, ProcessConfig, ReferenceImage};
use correlator::settings::ReferenceKind;
use correlator::CorrelatorSettings;
use std::path::PathBuf;
use std::time::Duration;

#[derive(clap::Args, Debug)]
pub struct CorrelatorArgs {
    /// Every setting from this JSON file (as `dicstream run` writes them in
    /// `<results>/settings/correlator.json`), instead of the other options.
    #[arg(long, exclusive = true)]
    pub settings: Option<PathBuf>,
    /// Instance name (shared-memory prefix); runs with different names never meet.
    #[arg(long, default_value_t = wire::Instance::default_name())]
    pub instance: String,
    /// Reference image file (PNG, TIFF or BMP); default: the first frame received.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Reference mode: fixed, incremental (previous frame) or auto update.
    #[arg(long, value_parser = named::<ReferenceKind>(), default_value_t = ReferenceKind::Fixed)]
    pub reference_mode: ReferenceKind,
    #[command(flatten)]
    pub correlation: CorrelationArgs,
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
        self.correlation.settings(self.reference_mode)
    }
}

pub fn run(args: CorrelatorArgs) -> Result<()> {
    let config = match &args.settings {
        Some(file) => super::settings_file::read(file)?,
        None => process_config(&args)?,
    };
    config.settings.validate().context("correlator settings")?;
    let summary =
        run_process(config).map_err(|e| wire::exit::in_context("correlator process", &e))?;
    eprintln!("{}", summary.final_line());
    Ok(())
}

/// The process's settings of the command line's flags.
fn process_config(args: &CorrelatorArgs) -> Result<ProcessConfig> {
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
    Ok(ProcessConfig {
        reference,
        state_dir: args.state_dir.clone(),
        max_frames: args.max_frames,
        idle_timeout,
        ..ProcessConfig::new(&args.instance, args.settings())
    })
}
