//! `dicstream identifier`: the live identification process (subscribes to `fields` and
//! `rig/state`, publishes `identification`, writes the final fits as JSON).

use super::named_arg::named;
use identifier::models::ModelList;
use identifier::online::OnlineConfig;
use identifier::process::{run as run_process, FieldRouteSettings, ProcessConfig};
use std::path::PathBuf;
use std::time::Duration;
use wire::identification::{IdentifierRoutes, ReportRoute};

#[derive(clap::Args, Debug)]
pub struct IdentifierArgs {
    /// Every setting from this JSON file (as `dicstream run` writes them in
    /// `<results>/settings/identifier.json`), instead of the other options.
    #[arg(long, exclusive = true)]
    pub settings: Option<PathBuf>,
    /// Instance name (shared-memory prefix); runs with different names never meet.
    #[arg(long, default_value_t = wire::Instance::default_name())]
    pub instance: String,
    /// Final fits, written atomically when the process stops.
    #[arg(long, default_value = "identification.json")]
    pub output: PathBuf,
    /// Journal of accepted load-path points: read back at start (a restarted identifier
    /// rebuilds its path from it), appended as points are accepted.
    #[arg(long)]
    pub journal: Option<PathBuf>,
    /// With the field route: write each state of its kept frames with its contribution to the
    /// best fit here at the end (`states.csv`'s columns).
    #[arg(long, value_name = "FILE")]
    pub states_csv: Option<PathBuf>,
    /// Models ranked at each refit: NAME[,NAME...] or `all` (slow: refits run per point).
    #[arg(long, default_value_t = ModelList(OnlineConfig::default().models))]
    pub model: ModelList,
    /// Stop after this many fields.
    #[arg(long)]
    pub max_fields: Option<u64>,
    /// Stop after this many seconds without data.
    #[arg(long)]
    pub idle_timeout_s: Option<f64>,
    /// The routes run: `gauge` (the gauge's averages), `field` (the whole field of a
    /// cruciform, by the virtual fields method) or `both`.
    #[arg(long, default_value = "gauge", value_parser = named::<IdentifierRoutes>())]
    pub route: IdentifierRoutes,
    /// The field route's camera view: the image's scale (mm per px), its centre on the
    /// specimen's (the default cruciform's; other geometries through `--settings`).
    #[arg(long, default_value_t = producer::DEFAULT_MM_PER_PX)]
    pub mm_per_px: f64,
    #[arg(long, default_value_t = 1024)]
    pub width_px: u32,
    #[arg(long, default_value_t = 1024)]
    pub height_px: u32,
}

pub fn run(args: IdentifierArgs) -> anyhow::Result<()> {
    let config = match &args.settings {
        Some(file) => super::settings_file::read(file)?,
        None => process_config(args)?,
    };
    // The fits are written at the end (and every second): a folder that is not there is
    // refused now, not after the whole test.
    let output = config.output_json.clone();
    let folder = output
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    if !folder.is_dir() {
        anyhow::bail!(
            "output {}: the folder {} does not exist",
            output.display(),
            folder.display()
        );
    }
    let summary =
        run_process(config).map_err(|e| wire::exit::in_context("identifier process", &e))?;
    eprintln!(
        "identifier: {} fields, {} rig samples, {} reports; points uniaxial/equibiaxial/pure shear = {:?}; best {}; wrote {}",
        summary.fields_received,
        summary.rig_samples_received,
        summary.reports_published,
        summary.points,
        summary.best_model.as_deref().unwrap_or("none"),
        output.display()
    );
    Ok(())
}

/// The process's settings of the command line's flags.
fn process_config(args: IdentifierArgs) -> anyhow::Result<ProcessConfig> {
    let models = args.model.0;
    let idle_timeout = match args.idle_timeout_s {
        Some(s) if s.is_finite() && s > 0.0 => Some(Duration::from_secs_f64(s)),
        Some(s) => anyhow::bail!("--idle-timeout-s must be a positive number of seconds, got {s}"),
        None => None,
    };
    Ok(ProcessConfig {
        instance: args.instance,
        output_json: args.output,
        journal: args.journal,
        states_csv: args.states_csv,
        max_fields: args.max_fields,
        idle_timeout,
        online: OnlineConfig {
            models,
            ..OnlineConfig::default()
        },
        routes: args.route,
        field: args
            .route
            .runs(ReportRoute::Field)
            .then(|| FieldRouteSettings {
                mm_per_px: args.mm_per_px,
                width_px: args.width_px,
                height_px: args.height_px,
                cruciform: Default::default(),
                min_level_increment: FieldRouteSettings::DEFAULT_LEVEL_INCREMENT,
                max_frames: FieldRouteSettings::DEFAULT_MAX_FRAMES,
            }),
    })
}
