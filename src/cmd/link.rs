//! `dicstream link --config FILE`: carries the services of this host's instance that the
//! configuration's `[link]` names to the peers over Zenoh, and the peers' into it (the
//! `link` feature; `src/link_zenoh.rs`). Stops on SIGINT/SIGTERM with one line per service (one JSON
//! object with `--json`): what was sent, held back, received, and the ids lost by the link.
//! `dicstream run` starts it with `--settings FILE` (`link::LinkSettings`) when `[link]` says
//! `start_with_run = true`.

use std::path::PathBuf;

/// Options of `dicstream link`.
#[derive(Debug, clap::Args)]
pub struct LinkArgs {
    /// The run's configuration, whose `[link]` section says what is carried, which way, and
    /// where this host listens and connects
    #[arg(
        long,
        required_unless_present = "settings",
        conflicts_with = "settings"
    )]
    pub config: Option<PathBuf>,
    /// The link's settings as JSON (what `dicstream run` writes: instance, `[link]`, counts
    /// file), in place of --config, --instance and --counts-json
    #[arg(long)]
    pub settings: Option<PathBuf>,
    /// Instance name (shared-memory prefix); the same on both hosts
    #[arg(long, default_value_t = wire::Instance::default_name())]
    pub instance: String,
    /// Keep the counts (sent, received, lost by the link) in this JSON file as the link goes,
    /// and go on from them when it exists (a link started again)
    #[arg(long)]
    pub counts_json: Option<PathBuf>,
    /// Print one JSON object at exit on stdout (the log lines go to stderr)
    #[arg(long)]
    pub json: bool,
}

/// The message of a build without the `link` feature.
pub const NO_LINK: &str = "this dicstream was built without the `link` feature, so it cannot \
    link two hosts: build with `cargo build --release --features link`";

/// The link's settings, from `--settings` or from `--config` and the flags.
fn settings(args: &LinkArgs) -> anyhow::Result<(link::LinkSettings, PathBuf)> {
    if let Some(file) = &args.settings {
        let text = std::fs::read_to_string(file)
            .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        let settings = serde_json::from_str(&text)
            .map_err(|e| config_error(file, format!("not the link's settings: {e}")))?;
        return Ok((settings, file.clone()));
    }
    let file = args
        .config
        .as_ref()
        .expect("clap requires --config or --settings");
    let config = live::RunConfig::read(Some(file))?;
    let link = config.link.ok_or_else(|| {
        anyhow::anyhow!(
            "{}: no [link] section: say what is carried and where (docs/link.md)",
            file.display()
        )
    })?;
    let settings = link::LinkSettings {
        instance: args.instance.clone(),
        link,
        counts_json: args.counts_json.clone(),
    };
    Ok((settings, file.clone()))
}

/// A configuration a restart cannot fix: exit code 78 (`dicstream run` does not restart it).
fn config_error(file: &std::path::Path, message: impl std::fmt::Display) -> anyhow::Error {
    wire::exit::ExitWith {
        code: wire::exit::CONFIG,
        message: format!("{}: {message}", file.display()),
    }
    .into()
}

/// The link's settings and its checked `[link]`.
pub fn plan(args: &LinkArgs) -> anyhow::Result<(link::LinkSettings, link::LinkPlan)> {
    let (settings, file) = settings(args)?;
    let plan = settings.link.plan().map_err(|e| config_error(&file, e))?;
    Ok((settings, plan))
}

#[cfg(not(feature = "link"))]
pub fn run(args: LinkArgs) -> anyhow::Result<()> {
    plan(&args)?;
    anyhow::bail!(NO_LINK)
}

#[cfg(feature = "link")]
pub fn run(args: LinkArgs) -> anyhow::Result<()> {
    let (settings, plan) = plan(&args)?;
    let counts =
        crate::link_zenoh::run(&plan, &settings.instance, settings.counts_json.as_deref())?;
    if args.json {
        println!("{}", counts.to_json());
    } else {
        for line in counts.lines() {
            println!("{line}");
        }
    }
    Ok(())
}
