//! `dicstream monitor --instance NAME [--dashboard ADDR:PORT] [--config FILE]`: the live
//! dashboard attached, read-only, to any running instance: a node of its own subscribing to
//! frames, fields, rig/state and identification (several monitors may attach to one
//! instance). With the run's configuration it also charts the user's named gauges
//! (`live::monitor_gauges`); their shapes are not on the wire, so without it it says so.
//! Prints the URL on stderr, serves until Ctrl-C (SIGINT, SIGTERM, SIGHUP).

use anyhow::Context;
use dashboard::{address, Dashboard, Mode, UserGauges};
use live::monitor_gauges::MonitorGauges;
use live::RunConfig;
use std::path::PathBuf;
use wire::Instance;

/// Options of `dicstream monitor`.
#[derive(Debug, clap::Args)]
pub struct MonitorArgs {
    /// Instance name (shared-memory prefix) of the run to watch
    #[arg(long, default_value_t = Instance::default_name())]
    pub instance: String,
    /// Address of the dashboard (ADDR:PORT; port 0 takes any free port). A non-loopback
    /// address serves other machines too, with a warning
    #[arg(long, default_value = address::DEFAULT)]
    pub dashboard: String,
    /// Serve even though no process runs on the instance yet (a run about to start)
    #[arg(long)]
    pub wait: bool,
    /// The run's configuration (TOML, as given to `dicstream run --config`): its named gauges
    /// (`[correlator] gauges`) are charted, read from every field as the run reads them
    #[arg(long)]
    pub config: Option<PathBuf>,
}

/// The gauges of `--config`, checked as `run` checks its configuration; without it, none
/// (said on stderr: the gauges' shapes are the run's configuration, not on the wire).
fn user_gauges(config: Option<&std::path::Path>) -> anyhow::Result<Option<Box<dyn UserGauges>>> {
    let Some(path) = config else {
        eprintln!(
            "monitor: no named gauges shown: their shapes are the run's configuration, not on \
             the wire; add --config FILE (the run's) to chart them"
        );
        return Ok(None);
    };
    let config = RunConfig::read(Some(path))?;
    config
        .validate()
        .with_context(|| format!("--config {}: configuration refused", path.display()))?;
    let gauges = MonitorGauges::of(&config);
    eprintln!("monitor: {}", gauges.describe());
    Ok((!gauges.is_empty()).then(|| Box::new(gauges) as Box<dyn UserGauges>))
}

/// Refuses an instance on which no process runs (unless waiting for one), naming the
/// instances that have some.
fn check_running(instance: &str, wait: bool) -> anyhow::Result<()> {
    let held = wire::owner::held();
    if held.iter().any(|h| h.instance == instance) {
        return Ok(());
    }
    let mut running: Vec<String> = Vec::new();
    for h in &held {
        match running.last_mut() {
            Some(last) if last.starts_with(&format!("{} (", h.instance)) => {
                last.truncate(last.len() - 1);
                last.push_str(&format!(", {})", h.role));
            }
            _ => running.push(format!("{} ({})", h.instance, h.role)),
        }
    }
    let others = match running.is_empty() {
        true => "no instance runs on this machine".to_string(),
        false => format!("running: {}", running.join("; ")),
    };
    if wait {
        eprintln!(
            "monitor: no process runs on instance {instance} yet ({others}); waiting for one"
        );
        return Ok(());
    }
    anyhow::bail!(
        "no process runs on instance {instance} ({others}); `dicstream run` prints its instance \
         at start, or add --wait to watch one about to start"
    )
}

pub fn run(args: MonitorArgs) -> anyhow::Result<()> {
    let addr = address::parse(&args.dashboard)?;
    let gauges = user_gauges(args.config.as_deref())?;
    check_running(&args.instance, args.wait)?;
    if let Some(warning) = address::exposure_warning(&addr) {
        eprintln!("{warning}");
    }
    // The default port falls back to the next free one; an address given is taken as is.
    let fallback = args.dashboard == address::DEFAULT;
    let dashboard = Dashboard::start(&args.instance, Mode::Monitor, addr, fallback, gauges)?;
    eprintln!(
        "monitor: dashboard of instance {} at {} (read-only; Ctrl-C to stop)",
        args.instance,
        dashboard.url()
    );
    Ok(dashboard.wait()?)
}
