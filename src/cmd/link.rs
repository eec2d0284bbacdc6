//! `dicstream link --config FILE`: carries the services of this host's instance that the
//! configuration's `[link]` names to the peers over Zenoh, and the peers' into it (the
//! `link` feature; `src/link_zenoh.rs`). Stops on SIGINT/SIGTERM with one line per service (one JSON
//! object with `--json`): what was sent, held back, received, and the ids lost by the link.

use std::path::PathBuf;

/// Options of `dicstream link`.
#[derive(Debug, clap::Args)]
pub struct LinkArgs {
    /// The run's configuration, whose `[link]` section says what is carried, which way, and
    /// where this host listens and connects
    #[arg(long)]
    pub config: PathBuf,
    /// Instance name (shared-memory prefix); the same on both hosts
    #[arg(long, default_value_t = wire::Instance::default_name())]
    pub instance: String,
    /// Print one JSON object at exit on stdout (the log lines go to stderr)
    #[arg(long)]
    pub json: bool,
}

/// The message of a build without the `link` feature.
#[cfg_attr(feature = "link", allow(dead_code))]
pub const NO_LINK: &str = "this dicstream was built without the `link` feature, so it cannot \
    link two hosts: build with `cargo build --release --features link`";

/// The checked `[link]` of `--config`.
pub fn plan(args: &LinkArgs) -> anyhow::Result<link::LinkPlan> {
    let config = live::RunConfig::read(Some(&args.config))?;
    let section = config.link.as_ref().ok_or_else(|| {
        anyhow::anyhow!(
            "{}: no [link] section: say what is carried and where (docs/link.md)",
            args.config.display()
        )
    })?;
    // A configuration a restart cannot fix: exit code 78 (`dicstream run` does not restart it).
    section.plan().map_err(|e| {
        wire::exit::ExitWith {
            code: wire::exit::CONFIG,
            message: format!("{}: {e}", args.config.display()),
        }
        .into()
    })
}

#[cfg(not(feature = "link"))]
pub fn run(args: LinkArgs) -> anyhow::Result<()> {
    plan(&args)?;
    anyhow::bail!(NO_LINK)
}

#[cfg(feature = "link")]
pub fn run(args: LinkArgs) -> anyhow::Result<()> {
    let plan = plan(&args)?;
    let report = crate::link_zenoh::run(&plan, &args.instance)?;
    if args.json {
        println!("{}", report.json(&args.instance));
    } else {
        for line in report.lines() {
            println!("{line}");
        }
    }
    Ok(())
}
