//! `dicstream monitor --instance NAME [--dashboard ADDR:PORT]`: the live dashboard attached,
//! read-only, to any running instance: a node of its own subscribing to frames, fields,
//! rig/state and identification (several monitors may attach to one instance). Prints the URL
//! on stderr, serves until Ctrl-C (SIGINT, SIGTERM, SIGHUP).

use dashboard::{address, Dashboard, Mode};
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
}

pub fn run(args: MonitorArgs) -> anyhow::Result<()> {
    let addr = address::parse(&args.dashboard)?;
    if let Some(warning) = address::exposure_warning(&addr) {
        eprintln!("{warning}");
    }
    // The default port falls back to the next free one; an address given is taken as is.
    let fallback = args.dashboard == address::DEFAULT;
    let dashboard = Dashboard::start(&args.instance, Mode::Monitor, addr, fallback)?;
    eprintln!(
        "monitor: dashboard of instance {} at {} (read-only; Ctrl-C to stop)",
        args.instance,
        dashboard.url()
    );
    Ok(dashboard.wait()?)
}
