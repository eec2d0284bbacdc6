//! Before a run holds anything: the shared memory of earlier runs that died is removed, the
//! instance claimed, the free space of `/dev/shm` checked, the dashboard started (its address
//! taken before anything is written), the results folder made (an earlier
//! run found in it set aside) with the configuration's copy, and the line saying where it all
//! goes printed.

use super::start::RunStart;
use super::RunOptions;
use crate::config::{RigSource, RunConfig};
use crate::results::ResultsDir;
use std::path::{Path, PathBuf};

/// What a run starts from: its instance, claimed, and its results folder.
pub(super) struct Prepared {
    pub(super) instance: wire::Instance,
    /// The claim on the instance, held to the end of the run.
    pub(super) _owner: wire::owner::Owner,
    pub(super) name: String,
    pub(super) results: ResultsDir,
    pub(super) start: RunStart,
    /// The dashboard, serving before the results folder is made: an address in use stops the
    /// run with nothing written.
    pub(super) dashboard: Option<dashboard::Dashboard>,
}

impl Prepared {
    /// Checks the configuration, claims the instance, makes the results folder.
    pub(super) fn new(options: &RunOptions) -> anyhow::Result<Prepared> {
        let config = &options.config;
        config.validate()?;
        let cleaned = remove_dead_runs();
        if cleaned > 0 {
            eprintln!(
                "run: removed the shared memory of {cleaned} earlier run(s) that did not end cleanly"
            );
        }
        let name = options
            .instance
            .clone()
            .unwrap_or_else(|| format!("run_{}", std::process::id()));
        let instance = wire::Instance::new(&name)?;
        // Before anything is written or started: a second run on this instance is refused.
        let owner = instance.claim("run")?;
        wire::shm::ensure_free(wire::shm::SHM_PATH, shm_needed_bytes(config)?)?;
        let dashboard = crate::dashboard_view::start(config, &name)?;
        let (results, previous_run_moved_to) = results_folder(options)?;
        let start = RunStart::now(&results, previous_run_moved_to);
        write_config(config, &results)?;
        say_start(config, &results, &name)?;
        Ok(Prepared {
            instance,
            _owner: owner,
            name,
            results,
            start,
            dashboard,
        })
    }
}

/// The results folder, and where an earlier run found in a folder given again was moved (its
/// files are never mixed with these).
fn results_folder(options: &RunOptions) -> anyhow::Result<(ResultsDir, Option<PathBuf>)> {
    let Some(root) = &options.results else {
        let dated = ResultsDir::create_dated(Path::new(&options.config.run.results_dir))?;
        return Ok((dated, None));
    };
    let previous_run_moved_to = crate::results::previous::set_aside(root)?;
    if let Some(aside) = &previous_run_moved_to {
        eprintln!(
            "run: {} held an earlier run: its files were moved into {}",
            root.display(),
            aside.display()
        );
    }
    Ok((ResultsDir::at(root)?, previous_run_moved_to))
}

/// The run's configuration beside its results, ready to be run again.
fn write_config(config: &RunConfig, results: &ResultsDir) -> anyhow::Result<()> {
    wire::files::write_atomic(
        &results.config(),
        format!(
            "# The configuration of this run (dicstream run --config {} reruns it).\n{}",
            results.config().display(),
            config.to_toml()
        )
        .as_bytes(),
    )?;
    Ok(())
}

/// The first line of the run: where its results go, its instance, what it runs.
fn say_start(config: &RunConfig, results: &ResultsDir, instance: &str) -> anyhow::Result<()> {
    match config.rig.source {
        RigSource::Simulated => eprintln!(
            "run: results in {}, instance {instance}, campaign {} (about {:.0} s), camera {}",
            results.root.display(),
            config.campaign_spec(),
            config.campaign_wall_s()?,
            config.camera.source
        ),
        RigSource::CsvFollow => eprintln!(
            "run: results in {}, instance {instance}, camera {}, forces from {} (the test \
             ends {} s after its last row)",
            results.root.display(),
            config.camera.source,
            config.rig.csv.file.display(),
            config.rig.csv.idle_timeout_s
        ),
    }
    Ok(())
}

/// Shared memory the run's services need (bytes), checked against `/dev/shm` at start.
pub fn shm_needed_bytes(config: &RunConfig) -> anyhow::Result<u64> {
    let frames =
        producer::stream::frames_shm_bytes(config.camera.width_px, config.camera.height_px);
    let settings = config.correlator_settings()?;
    let roi = settings
        .resolve_region(
            config.camera.width_px as usize,
            config.camera.height_px as usize,
        )?
        .mesh_rect;
    let nodes = (roi.width_px / settings.step_px + 1) * (roi.height_px / settings.step_px + 1);
    let fields = wire::services::FIELDS.shm_bytes(
        std::mem::size_of::<wire::FieldHeader>(),
        nodes * std::mem::size_of::<wire::FieldNode>(),
    );
    let small = wire::services::RIG_STATE.shm_bytes(0, std::mem::size_of::<wire::RigState>())
        + wire::services::IDENTIFICATION
            .shm_bytes(0, std::mem::size_of::<wire::IdentificationReport>());
    Ok(frames + fields + small)
}

/// Removes the shared-memory files of earlier default-named runs (`run_<pid>`) whose
/// supervisor is gone (killed with SIGKILL, or a power cut of the session); returns how many
/// runs were cleaned.
pub fn remove_dead_runs() -> usize {
    let Ok(entries) = std::fs::read_dir(wire::shm::SHM_PATH) else {
        return 0;
    };
    let mut dead: Vec<u32> = entries
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let pid: u32 = name.strip_prefix("run_")?.split('_').next()?.parse().ok()?;
            let alive = Path::new(&format!("/proc/{pid}")).exists();
            (!alive).then_some(pid)
        })
        .collect();
    dead.sort_unstable();
    dead.dedup();
    for pid in &dead {
        if let Ok(instance) = wire::Instance::new(&format!("run_{pid}")) {
            instance.cleanup_dead_nodes();
            instance.remove_leftover_files();
        }
    }
    dead.len()
}
