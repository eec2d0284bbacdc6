//! `dicstream run`: the whole bench. Checks the configuration, makes the results folder,
//! starts identifier, correlator, producer and rig as child processes on a fresh instance
//! (each waited for until ready), watches every service from the monitor, prints a status
//! line once a second, handles deaths (reported, restarted if configured), stops everything
//! in order on completion or Ctrl-C, then writes the latency histograms, figures and
//! `summary.json`, and leaves nothing in `/dev/shm`.

use crate::acceptance::{accept, Acceptance};
use crate::children::{Exit, Role, Supervisor};
use crate::config::{CameraSource, RigSource, RunConfig};
use crate::latency::Percentiles;
use crate::liveness::{Counts, Liveness};
use crate::recorder::{Recorder, RecorderSettings};
use crate::results::ResultsDir;
use crate::subscriptions::Subscriptions;
use anyhow::{anyhow, bail};
pub use child_args::child_args;
use iceoryx2::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

mod child_args;
pub mod start;
mod verdict;

/// What to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub config: RunConfig,
    /// The `dicstream` binary the children run.
    pub exe: PathBuf,
    /// Instance name; default `run_<pid>`.
    pub instance: Option<String>,
    /// Results folder; default `<results_dir>/<date-time>/`.
    pub results: Option<PathBuf>,
    /// Print the status line (otherwise only the start and the end are printed).
    pub status: bool,
    /// The long status line (every figure) instead of one that fits 100 columns.
    pub verbose: bool,
}

/// How the run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    /// The campaign ran to its end (`failure` then names what makes its results doubtful,
    /// if anything: acceptance not passed, frames lost to a fault, nothing identified).
    Completed,
    /// SIGINT, SIGTERM or SIGHUP (`failure` names it).
    Interrupted,
    /// A process died and could not be kept alive, a results file could not be written, or
    /// the bench could not start.
    Failed,
}

/// Exit codes of `dicstream run`, also written in `summary.json`.
pub mod exit_code {
    /// Completed, and the results are trustworthy.
    pub const PASSED: u8 = 0;
    /// Failed (see [`super::Ending::Failed`]).
    pub const FAILED: u8 = 1;
    /// Completed, but the acceptance was not passed, frames were lost to a fault, or nothing
    /// was identified.
    pub const DOUBTFUL: u8 = 2;
    /// Interrupted by signal N: 128 + N, as a shell reports it.
    pub const SIGNAL_BASE: u8 = 128;
}

/// What the run did, also written as `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    pub results: PathBuf,
    pub instance: String,
    pub ending: Ending,
    /// Start time, pid, configuration, the earlier run set aside (also in the summary written
    /// at the start, `ending` = `running`).
    #[serde(flatten)]
    pub start: start::RunStart,
    pub failure: Option<String>,
    pub wall_s: f64,
    pub frames_captured: u64,
    pub fields: u64,
    /// Frames captured that have no field: skipped by a correlator that fell behind, lost while
    /// it was dead or stopped, or still on their way when the run stopped.
    pub frames_not_correlated: u64,
    /// Of those, the frames lost while a process was dead or stale (not skipped by a running
    /// correlator): a fault cost them.
    pub frames_lost_to_faults: u64,
    /// Every death and stale process of the run, as noticed.
    pub faults: Vec<String>,
    pub identification_reports: u64,
    pub restarts: Vec<String>,
    /// CPU seconds used per process (user + system, all threads), and as a share of one core
    /// over the run's wall time (1.0 = one core busy all along).
    pub cpu_s: std::collections::BTreeMap<String, f64>,
    pub cpu_cores: std::collections::BTreeMap<String, f64>,
    pub latency_field_ms: Percentiles,
    pub latency_identification_ms: Percentiles,
    /// Mean over frames of the mean node displacement error against the truth (px), and the
    /// worst node error of the run.
    pub displacement_error_mean_px: Option<f64>,
    pub acceptance: Option<Acceptance>,
    /// Why there is no acceptance although a law was identified: a real camera or machine
    /// has no ground truth to compare with.
    pub acceptance_skipped: Option<String>,
    /// Where frames and rig samples came from ([camera] source, [rig] source).
    pub camera_source: CameraSource,
    pub rig_source: RigSource,
    /// With `[rig] source = "csv-follow"`: the machine CSV's rows read, malformed lines
    /// skipped and restarts (truncations, rotations), as the follower kept them in
    /// `machine_csv.json`.
    pub machine_csv: Option<rig::csv_follow::FollowCounters>,
    /// What `strain_map.png` shows.
    pub strain_map: Option<StrainMapInfo>,
    /// Files of the instance left once every process had stopped (named, then removed).
    pub leftover_shm_files: usize,
    /// The exit code of `dicstream run` (see [`exit_code`]).
    pub exit_code: u8,
}

/// The field drawn in `strain_map.png` (the most strained field of the last test) and the
/// exx range of its colours.
#[derive(Clone, Debug, Serialize)]
pub struct StrainMapInfo {
    pub frame_id: u64,
    pub origin_frame_id: u64,
    pub measure: &'static str,
    pub exx_blue_to_red: [f64; 2],
}

/// Seconds a process gets to say it is ready.
const READY_TIMEOUT: Duration = Duration::from_secs(120);
/// Longest wait for the correlator and identifier to finish the last frames.
const DRAIN_TIMEOUT: Duration = Duration::from_secs(10);
const WAIT_SLICE: Duration = Duration::from_millis(200);
/// How often the latency histograms are rewritten during the run.
const HISTOGRAM_EVERY: Duration = Duration::from_secs(10);

/// Shared memory the run's services need (bytes), checked against `/dev/shm` at start.
pub fn shm_needed_bytes(config: &RunConfig) -> anyhow::Result<u64> {
    let frames =
        producer::stream::frames_shm_bytes(config.camera.width_px, config.camera.height_px);
    let settings = config.correlator_settings()?;
    let roi = settings.resolve_roi(
        config.camera.width_px as usize,
        config.camera.height_px as usize,
    )?;
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

fn start_order() -> [Role; 4] {
    // Consumers first, so that nothing the rig and the camera publish is missed.
    [
        Role::Identifier,
        Role::Correlator,
        Role::Producer,
        Role::Rig,
    ]
}

/// Stops in the order data flows: the source first, each consumer after.
const STOP_ORDER: [Role; 4] = [
    Role::Rig,
    Role::Producer,
    Role::Correlator,
    Role::Identifier,
];

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

pub fn run(options: RunOptions) -> anyhow::Result<RunReport> {
    let config = &options.config;
    config.validate()?;
    let cleaned = remove_dead_runs();
    if cleaned > 0 {
        eprintln!(
            "run: removed the shared memory of {cleaned} earlier run(s) that did not end cleanly"
        );
    }
    let instance_name = options
        .instance
        .clone()
        .unwrap_or_else(|| format!("run_{}", std::process::id()));
    let instance = wire::Instance::new(&instance_name)?;
    // Before anything is written or started: a second run on this instance is refused.
    let _owner = instance.claim("run")?;
    wire::shm::ensure_free(wire::shm::SHM_PATH, shm_needed_bytes(config)?)?;
    // A folder given again: the earlier run's files are moved aside, never mixed with these.
    let mut previous_run_moved_to = None;
    let results = match &options.results {
        Some(root) => {
            previous_run_moved_to = crate::results::previous::set_aside(root)?;
            if let Some(aside) = &previous_run_moved_to {
                eprintln!(
                    "run: {} held an earlier run: its files were moved into {}",
                    root.display(),
                    aside.display()
                );
            }
            ResultsDir::at(root)?
        }
        None => ResultsDir::create_dated(Path::new(&config.run.results_dir))?,
    };
    let run_start = start::RunStart::now(&results, previous_run_moved_to);
    wire::files::write_atomic(
        &results.config(),
        format!(
            "# The configuration of this run (dicstream run --config {} reruns it).\n{}",
            results.config().display(),
            config.to_toml()
        )
        .as_bytes(),
    )?;
    match config.rig.source {
        RigSource::Simulated => eprintln!(
            "run: results in {}, instance {instance_name}, campaign {} (about {:.0} s), camera {}",
            results.root.display(),
            config.campaign_spec(),
            config.campaign_wall_s()?,
            config.camera.source
        ),
        RigSource::CsvFollow => eprintln!(
            "run: results in {}, instance {instance_name}, camera {}, forces from {} (the test \
             ends {} s after its last row)",
            results.root.display(),
            config.camera.source,
            config.rig.csv.file.display(),
            config.rig.csv.idle_timeout_s
        ),
    }
    let started = Instant::now();
    let monitor_cpu_at_start_s = crate::children::own_cpu_s();
    let t0_ns = wire::monotonic_ns();
    let mut supervisor = Supervisor::new(&options.exe, &results.logs())?;
    let outcome = {
        let (node, _) = instance.create_node("monitor")?;
        let subscriptions = Subscriptions::new(&node)?;
        let mut recorder = Recorder::new(
            &results,
            RecorderSettings {
                fields_every: config.run.fields_every,
                vtk: config.run.vtk,
                truth: config.camera.source.has_truth(),
            },
            t0_ns,
        )?;
        let mut state = LoopState {
            dashboard: crate::dashboard_view::start(config, &instance_name)?,
            verbose: options.verbose,
            ..LoopState::default()
        };
        // From here on the run ends through `finish`, which replaces it.
        start::write_running(
            &results,
            &instance_name,
            &run_start,
            &config.camera.source,
            &config.rig.source,
        )?;
        let result = start_children(&mut supervisor, config, &instance_name, &results).and_then(
            |all_ready| match all_ready {
                false => Ok(Ending::Interrupted),
                true => event_loop(
                    &subscriptions,
                    &mut recorder,
                    &mut supervisor,
                    config,
                    &instance_name,
                    &results,
                    options.status,
                    started,
                    &mut state,
                ),
            },
        );
        supervisor.sample_cpu();
        let cpu_s = Role::ALL.map(|role| (role.name(), supervisor.cpu_seconds(role)));
        let stopped = supervisor.stop_all(
            &STOP_ORDER,
            Duration::from_secs_f64(config.run.stop_timeout_s),
        );
        for (role, how) in stopped {
            eprintln!("run: stopped {} ({how})", role.name());
        }
        // Samples published while stopping (last fields, last report).
        let _ = subscriptions.drain(&mut recorder);
        (result, recorder, state, cpu_s)
    };
    let (result, recorder, mut state, cpu_s) = outcome;
    state.cpu_s = cpu_s.into_iter().map(|(n, s)| (n.to_string(), s)).collect();
    state.signal = wire::signals::requested();
    state.cpu_s.insert(
        "monitor".to_string(),
        crate::children::own_cpu_s() - monitor_cpu_at_start_s,
    );
    drop(supervisor);
    drop(state.dashboard.take());
    let leftover_shm_files = crate::leftovers::report_and_remove(&instance);
    let (ending, failure) = match result {
        Ok(ending) => (ending, None),
        // The whole chain: what failed, and why.
        Err(e) => (Ending::Failed, Some(format!("{e:#}"))),
    };
    finish(
        config,
        &results,
        &instance_name,
        run_start,
        recorder,
        state,
        ending,
        failure,
        started,
        leftover_shm_files,
    )
}

/// Starts every child, each waited for until ready. False when a termination signal came
/// first (the children started so far are stopped by the caller).
fn start_children(
    supervisor: &mut Supervisor,
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
) -> anyhow::Result<bool> {
    for role in start_order() {
        if wire::signals::requested().is_some() {
            return Ok(false);
        }
        supervisor.spawn(role, child_args(role, config, instance, results, 0))?;
        if !waits_for_ready(role, config) {
            eprintln!(
                "run: {} started (pid {}); ready at its first image",
                role.name(),
                supervisor.pid(role).unwrap_or(0)
            );
            continue;
        }
        let ready = supervisor.wait_ready(role, READY_TIMEOUT);
        let ready = match (role, config.camera.source) {
            (Role::Producer, CameraSource::Genicam) => ready.map_err(|e| {
                e.context(
                    "[camera] source = \"genicam\": the camera could not be opened (a \
                     dicstream built without `--features genicam` says so above)",
                )
            }),
            _ => ready,
        };
        if !ready? {
            return Ok(false);
        }
        eprintln!(
            "run: {} ready (pid {})",
            role.name(),
            supervisor.pid(role).unwrap_or(0)
        );
    }
    // An exit while a later child was starting is kept by the supervisor: handled first thing
    // by the event loop.
    Ok(true)
}

/// Whether the run waits for `role` to say it is ready before going on: a watched folder's
/// camera is ready only at its first image (which sets the frame size), which may come long
/// after the start; the run goes on at once and handles its exit like any other.
fn waits_for_ready(role: Role, config: &RunConfig) -> bool {
    !(role == Role::Producer && config.camera.source == CameraSource::Watch)
}

/// What the loop learnt that the end of the run reports.
#[derive(Default)]
struct LoopState {
    restarts: Vec<String>,
    restart_counts: [u32; 4],
    /// Deaths and stale processes, as noticed (`<role> <how>`).
    faults: Vec<String>,
    /// The termination signal that interrupted the run.
    signal: Option<i32>,
    /// CPU seconds per process (children by role, and this monitor).
    cpu_s: std::collections::BTreeMap<String, f64>,
    dashboard: Option<dashboard::Dashboard>,
    verbose: bool,
    /// A real camera reported lost and not yet back (the status line says so).
    camera_away: bool,
}

enum Phase {
    Running,
    /// The campaign is over and the camera stopped: the correlator and the identifier finish.
    Draining {
        since: Instant,
        last_frame: Option<u64>,
    },
}

/// How the loop ends when a termination signal has arrived.
fn interrupted(signal: i32) -> Ending {
    eprintln!(
        "run: {} received, stopping the processes",
        wire::signals::name(signal)
    );
    Ending::Interrupted
}

/// The samples seen so far per service, for the liveness watch.
fn counts(recorder: &Recorder, supervisor: &mut Supervisor) -> Counts {
    Counts {
        rig_states: recorder.rig_samples_seen,
        frames: recorder.frames_seen,
        fields: recorder.fields_seen,
        identifier_heard_fields: supervisor.heard_input(Role::Identifier),
    }
}

#[allow(clippy::too_many_arguments)]
fn event_loop(
    subscriptions: &Subscriptions,
    recorder: &mut Recorder,
    supervisor: &mut Supervisor,
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
    status: bool,
    started: Instant,
    state: &mut LoopState,
) -> anyhow::Result<Ending> {
    let waitset = wire::signals::waitset().map_err(|e| anyhow!("monitor WaitSet: {e:?}"))?;
    let mut guards = Vec::new();
    for listener in subscriptions.listeners() {
        guards.push(
            waitset
                .attach_notification(listener)
                .map_err(|e| anyhow!("monitor WaitSet: {e:?}"))?,
        );
    }
    let status_every = Duration::from_secs_f64(config.run.status_interval_s);
    let mut next_status = Instant::now() + status_every;
    let mut next_histograms = Instant::now() + HISTOGRAM_EVERY;
    let mut phase = Phase::Running;
    let stop_timeout = Duration::from_secs_f64(config.run.stop_timeout_s);
    let mut liveness = Liveness::new(Duration::from_secs_f64(config.run.stale_after_s));
    // A real camera publishes when images come, a machine's log when rows come: their
    // silence is the test's pace, not a hang (a stopped process is still caught).
    if config.camera.source != CameraSource::Simulated {
        liveness.ignore_silence(Role::Producer);
    }
    if config.rig.source == RigSource::CsvFollow {
        liveness.ignore_silence(Role::Rig);
    }
    for role in Role::ALL {
        liveness.reset(role, &counts(recorder, supervisor), Instant::now());
    }
    loop {
        // Woken by a sample, a signal, or SIGCONT after this monitor was stopped (Ctrl-Z, fg):
        // only a termination request stops the run.
        waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, WAIT_SLICE)
            .map_err(|e| anyhow!("monitor WaitSet: {e:?}"))?;
        if let Some(signal) = wire::signals::requested() {
            return Ok(interrupted(signal));
        }
        subscriptions.drain(recorder)?;
        if let Some(error) = &recorder.write_error {
            bail!("{error}; the run stops (every earlier row is whole)");
        }

        if matches!(phase, Phase::Running) {
            let now_counts = counts(recorder, supervisor);
            let stopped = |role| {
                supervisor
                    .pid(role)
                    .is_some_and(crate::children::process_stopped)
            };
            for (role, why) in liveness.check(&now_counts, stopped, Instant::now()) {
                // Handled below like a death (reported, restarted if configured).
                supervisor.kill(role, &format!("stale: {why}"));
            }
        }

        for (event, line) in supervisor.take_camera_events() {
            eprintln!("run: {line}");
            state.camera_away = event.away();
        }

        for exit in supervisor.take_exits() {
            let campaign_done = exit.role == Role::Rig && exit.success;
            if campaign_done && matches!(phase, Phase::Running) {
                eprintln!("run: campaign finished; stopping the camera, finishing the last frames");
                supervisor.stop(Role::Producer, stop_timeout);
                subscriptions.drain(recorder)?;
                phase = Phase::Draining {
                    since: Instant::now(),
                    last_frame: recorder.last_frame_id,
                };
                continue;
            }
            if matches!(phase, Phase::Draining { .. }) && exit.role == Role::Producer {
                // Stopped on purpose above.
                continue;
            }
            if exit.role == Role::Producer
                && exit.success
                && config.camera.source != CameraSource::Simulated
            {
                // A replay at its last image, a watched folder idle for its timeout.
                eprintln!(
                    "run: the camera ({}) has no more images; waiting for the rig to finish",
                    config.camera.source
                );
                continue;
            }
            subscriptions.drain(recorder)?;
            if exit.role == Role::Correlator {
                recorder.correlator_ended();
            }
            let next_frame_id = recorder.last_frame_id.map_or(0, |id| id + 1);
            handle_death(
                exit,
                supervisor,
                config,
                instance,
                results,
                next_frame_id,
                state,
            )?;
            if let Some(signal) = wire::signals::requested() {
                return Ok(interrupted(signal));
            }
            // The restarted child is watched afresh (the others too: the restart paused them).
            for role in Role::ALL {
                liveness.reset(role, &counts(recorder, supervisor), Instant::now());
            }
        }

        if let Phase::Draining { since, last_frame } = phase {
            let caught_up = match (last_frame, recorder.last_field) {
                (Some(frame), Some(field)) => field.frame_id >= frame,
                (None, _) => true,
                _ => false,
            };
            if caught_up || since.elapsed() > DRAIN_TIMEOUT {
                if !caught_up {
                    eprintln!("run: the correlator did not finish the last frames in time");
                }
                supervisor.stop(Role::Correlator, stop_timeout);
                // The identifier refits on the last points, then writes its final fits.
                let quiet_since = Instant::now();
                while quiet_since.elapsed() < Duration::from_millis(500) {
                    std::thread::sleep(Duration::from_millis(50));
                    subscriptions.drain(recorder)?;
                }
                supervisor.stop(Role::Identifier, stop_timeout);
                subscriptions.drain(recorder)?;
                return Ok(Ending::Completed);
            }
        }

        if Instant::now() >= next_status {
            supervisor.sample_cpu();
            crate::dashboard_view::update(
                &state.dashboard,
                supervisor,
                &state.faults,
                &state.restarts,
                &state.restart_counts,
                started,
            );
            if next_histograms <= Instant::now() {
                // Kept up to date, so a run killed outright still leaves its latencies (a
                // write error is reported once at the end, when they are written again).
                let _ = write_histograms(results, recorder);
                next_histograms = Instant::now() + HISTOGRAM_EVERY;
            }
            if status {
                let line =
                    crate::status::line(recorder, started.elapsed().as_secs_f64(), state.verbose);
                match state.camera_away {
                    true => println!("{line} | CAMERA LOST, reconnecting"),
                    false => println!("{line}"),
                }
            }
            next_status += status_every;
            if next_status < Instant::now() {
                next_status = Instant::now() + status_every;
            }
        }
    }
}

fn handle_death(
    exit: Exit,
    supervisor: &mut Supervisor,
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
    next_frame_id: u64,
    state: &mut LoopState,
) -> anyhow::Result<()> {
    let role = exit.role;
    let report = format!(
        "{} (pid {}) died: {}{}",
        role.name(),
        exit.pid,
        exit.how,
        if exit.last_lines.is_empty() {
            String::new()
        } else {
            format!("; its last lines:\n    {}", exit.last_lines.join("\n    "))
        }
    );
    eprintln!("run: {report}");
    state.faults.push(format!("{} {}", role.name(), exit.how));
    // A child that could not write its results (a full disk) or refused to resume is not
    // restarted: it would fail the same way, or start its test over.
    match exit.code {
        Some(code) if code == i32::from(wire::exit::OUTPUT_FAILED) => {
            bail!("{report}\n(a results file could not be written)");
        }
        Some(code) if code == i32::from(wire::exit::CANNOT_RESUME) => {
            bail!("{report}\n(it could not resume its test safely)");
        }
        Some(code) if code == i32::from(wire::exit::RESOURCES) => {
            bail!("{report}\n(it could not get a system resource it needs: not restarted)");
        }
        Some(code) if code == i32::from(wire::exit::CONFIG) => {
            bail!("{report}\n(its configuration does not fit its input: not restarted)");
        }
        _ => {}
    }
    let count = &mut state.restart_counts[role as usize];
    if !config.run.restart || *count >= config.run.max_restarts {
        bail!(
            "{report}\n(restart {}; {} of {} restarts used)",
            if config.run.restart { "on" } else { "off" },
            count,
            config.run.max_restarts
        );
    }
    *count += 1;
    let args = child_args(role, config, instance, results, next_frame_id);
    let pid = supervisor.restart(role, Some(args))?;
    if waits_for_ready(role, config) && !supervisor.wait_ready(role, READY_TIMEOUT)? {
        return Ok(());
    }
    let note = format!(
        "{} restarted (pid {pid}, restart {} of {}) after: {}",
        role.name(),
        count,
        config.run.max_restarts,
        exit.how
    );
    eprintln!("run: {note}");
    state.restarts.push(note);
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn finish(
    config: &RunConfig,
    results: &ResultsDir,
    instance: &str,
    start: start::RunStart,
    recorder: Recorder,
    state: LoopState,
    ending: Ending,
    failure: Option<String>,
    started: Instant,
    leftover_shm_files: usize,
) -> anyhow::Result<RunReport> {
    let mut notes = Vec::new();
    let mut keep = |what: &str, result: anyhow::Result<()>| {
        if let Err(e) = result {
            notes.push(format!("{what}: {e:#}"));
        }
    };
    keep(
        "latency.hgrm",
        wire::files::write_atomic(
            &results.path("latency.hgrm"),
            recorder.latency_field.hgrm().as_bytes(),
        )
        .map_err(anyhow::Error::from),
    );
    keep(
        "latency_identification.hgrm",
        wire::files::write_atomic(
            &results.path("latency_identification.hgrm"),
            recorder.latency_identification.hgrm().as_bytes(),
        )
        .map_err(anyhow::Error::from),
    );
    keep(
        "latency.png",
        crate::figures::latency_png(
            &results.path("latency.png"),
            &[
                ("capture to field", &recorder.latency_field),
                (
                    "capture to identification",
                    &recorder.latency_identification,
                ),
            ],
        ),
    );
    keep(
        "identification figures",
        crate::figures::identification_figures(
            &results.root,
            &results.journal(),
            &config.identifier.models.0,
        )
        .map(|_| ()),
    );
    let mut strain_map = None;
    if let (Some((frame, pixels)), Some((field, nodes))) =
        (&recorder.sequence_first_frame, &recorder.peak_field)
    {
        // The most strained field of the last test over the image its mesh is defined in.
        if field.origin_frame_id == frame.frame_id {
            let header = *field;
            let field = crate::recorder::to_correlator_field(field, nodes);
            match crate::figures::strain_map(
                &results.path("strain_map.png"),
                pixels,
                frame.width_px as usize,
                &field,
            ) {
                Ok(range) => {
                    strain_map = Some(StrainMapInfo {
                        frame_id: header.frame_id,
                        origin_frame_id: header.origin_frame_id,
                        measure: wire::StrainMeasure::from_code(header.strain_measure)
                            .map_or("?", |m| m.name()),
                        exx_blue_to_red: range,
                    })
                }
                Err(e) => keep("strain_map.png", Err(e)),
            }
        }
    }
    let has_truth = config.camera.source.has_truth() && config.rig.source == RigSource::Simulated;
    let acceptance_skipped = (!has_truth && recorder.last_report.is_some()).then(|| {
        format!(
            "no ground truth with [camera] source = {:?} and [rig] source = {:?}: the \
             identified law is not compared with [specimen]",
            config.camera.source, config.rig.source
        )
    });
    // A strain-controlled path off the uniaxial and equibiaxial curves (pure shear, any ρ but
    // 1) is compared along its own path, up to the larger stretch the gauge zone reached.
    let off_path = config
        .strain_test()
        .ok()
        .flatten()
        .filter(|t| t.kind != rig::strain::StrainKind::Equibiaxial);
    if let Some(why) = &acceptance_skipped {
        eprintln!("run: acceptance skipped: {why}");
    }
    let acceptance = recorder.last_report.filter(|_| has_truth).map(|report| {
        let truth = config.law().expect("validated law");
        let tested =
            |case: usize| (recorder.max_stretch[case] > 1.01).then_some(recorder.max_stretch[case]);
        if let Some(test) = &off_path {
            return crate::acceptance::accept_path(
                &truth,
                &report.a[..report.a_count as usize],
                &report.b[..report.b_count as usize],
                test.kind.name(),
                test.ratio,
                recorder.max_stretch[2],
            );
        }
        accept(
            &truth,
            &report.a[..report.a_count as usize],
            &report.b[..report.b_count as usize],
            tested(1),
            tested(2),
        )
    });
    let displacement_error_mean_px = mean_displacement_error(&results.frames_csv());
    let machine_csv = machine_csv_counts(config, results);
    let wall_s = started.elapsed().as_secs_f64();
    let frames_captured = recorder.last_frame_id.map_or(0, |id| id + 1);
    let frames_not_correlated = frames_captured.saturating_sub(recorder.fields_seen);
    // Frames no correlator skipped yet none measured: lost while one was dead or stale.
    let frames_lost_to_faults = if state.faults.is_empty() {
        0
    } else {
        frames_not_correlated.saturating_sub(recorder.frames_dropped_by_correlators())
    };
    let (mut failure, mut exit_code) = verdict::verdict(
        ending,
        failure,
        acceptance.as_ref(),
        acceptance_skipped.is_some(),
        frames_lost_to_faults,
        state.signal,
        &state.faults,
    );
    let mut ending = ending;
    if !notes.is_empty() && ending != Ending::Interrupted {
        // Results that could not be written (a full disk): the run did not deliver them.
        let missing = format!("results not written: {}", notes.join("; "));
        failure = Some(match failure {
            Some(f) if ending == Ending::Failed => format!("{f}; {missing}"),
            _ => missing,
        });
        ending = Ending::Failed;
        exit_code = exit_code::FAILED;
    }
    let cpu_cores = state
        .cpu_s
        .iter()
        .map(|(name, s)| (name.clone(), s / wall_s.max(1e-9)))
        .collect();
    let report = RunReport {
        results: results.root.clone(),
        instance: instance.to_string(),
        ending,
        start,
        failure,
        wall_s,
        frames_captured,
        fields: recorder.fields_seen,
        frames_not_correlated,
        frames_lost_to_faults,
        faults: state.faults,
        identification_reports: recorder.latency_identification.count(),
        restarts: state.restarts,
        cpu_s: state.cpu_s,
        cpu_cores,
        latency_field_ms: recorder.latency_field.percentiles(),
        latency_identification_ms: recorder.latency_identification.percentiles(),
        displacement_error_mean_px,
        acceptance,
        acceptance_skipped,
        camera_source: config.camera.source,
        rig_source: config.rig.source,
        machine_csv,
        strain_map,
        leftover_shm_files,
        exit_code,
    };
    let mut json = serde_json::to_value(&report)?;
    if !notes.is_empty() {
        json["notes"] = serde_json::json!(notes);
        for note in &notes {
            eprintln!("run: {note}");
        }
    }
    wire::files::write_atomic(
        &results.summary_json(),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    Ok(report)
}

/// `latency.hgrm` (capture to field) and `latency_identification.hgrm`.
fn write_histograms(
    results: &ResultsDir,
    recorder: &Recorder,
) -> Result<(), wire::files::FileError> {
    wire::files::write_atomic(
        &results.path("latency.hgrm"),
        recorder.latency_field.hgrm().as_bytes(),
    )?;
    wire::files::write_atomic(
        &results.path("latency_identification.hgrm"),
        recorder.latency_identification.hgrm().as_bytes(),
    )
}

/// A followed machine CSV's counts, from the follower's `machine_csv.json` (none when the
/// follower never started following); skipped lines are said on stderr.
fn machine_csv_counts(
    config: &RunConfig,
    results: &ResultsDir,
) -> Option<rig::csv_follow::FollowCounters> {
    use rig::csv_follow::counts_file::{read, CountsReadError};
    if config.rig.source != RigSource::CsvFollow {
        return None;
    }
    match read(&results.machine_csv_json()) {
        Ok(counts) => {
            if counts.malformed_lines > 0 {
                eprintln!(
                    "run: {} malformed line(s) of the machine's CSV skipped (logs/rig.log names \
                     them)",
                    counts.malformed_lines
                );
            }
            Some(counts)
        }
        Err(CountsReadError::Read { reason, .. })
            if reason.kind() == std::io::ErrorKind::NotFound =>
        {
            None
        }
        Err(e) => {
            eprintln!("run: {e}");
            None
        }
    }
}

/// Mean of the `disp_error_mean_px` column of `frames.csv`, if any frame has it.
fn mean_displacement_error(frames_csv: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(frames_csv).ok()?;
    let mut lines = text.lines();
    let column = lines
        .next()?
        .split(',')
        .position(|c| c == "disp_error_mean_px")?;
    let values: Vec<f64> = lines
        .filter_map(|l| l.split(',').nth(column)?.parse().ok())
        .collect();
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}
