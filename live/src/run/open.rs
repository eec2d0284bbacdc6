//! The run while it goes on, [`Run`]: everything it holds, made once its instance is claimed
//! and its results folder ready, before any child starts.

use super::prepare::Prepared;
use super::{start, RunOptions};
use crate::children::{Role, Supervisor};
use crate::config::RunConfig;
use crate::liveness::Liveness;
use crate::recorder::{Recorder, RecorderSettings};
use crate::subscriptions::Subscriptions;
use iceoryx2::prelude::*;
use std::rc::Rc;
use std::time::{Duration, Instant};

/// Deaths, stale processes and restarts, as the run noticed them.
#[derive(Default)]
pub(super) struct Incidents {
    pub(super) restarts: Vec<String>,
    pub(super) restart_counts: [u32; Role::COUNT],
    /// Deaths and stale processes, as noticed (`<role> <how>`).
    pub(super) faults: Vec<String>,
    /// Without a rig here: the campaign halted on the other host, as this run saw it.
    pub(super) campaign_halted: Option<String>,
}

#[derive(Clone, Copy)]
pub(super) enum Phase {
    Running,
    /// The campaign is over and the camera stopped: the correlator and the identifier finish.
    Draining {
        since: Instant,
        last_frame: Option<u64>,
    },
}

/// A run from the start of its first child to the stop of its last. Fields drop in their
/// order: the monitor's ports before its node (iceoryx2 counts the node's users), both before
/// the instance.
pub(super) struct Run<'a> {
    pub(super) options: &'a RunOptions,
    /// The monitor's ports, shared with the event loop's WaitSet while it waits on them.
    pub(super) subscriptions: Rc<Subscriptions>,
    pub(super) node: Node<ipc::Service>,
    pub(super) supervisor: Supervisor,
    pub(super) recorder: Recorder,
    pub(super) dashboard: Option<dashboard::Dashboard>,
    /// The instance (claimed), its name, the results folder and the start of the run.
    pub(super) prepared: Prepared,
    pub(super) incidents: Incidents,
    pub(super) started: Instant,
    pub(super) monitor_cpu_at_start_s: f64,
    /// A real camera reported lost and not yet back (the status line says so).
    pub(super) camera_away: bool,
    pub(super) phase: Phase,
    pub(super) liveness: Liveness,
    /// Without a rig here: the rig samples seen so far and when the count last grew.
    pub(super) remote_rig: super::remote_rig::RemoteRig,
    /// The children the drain stopped only by killing them (their last results may be
    /// missing): the verdict says so as for those killed at the stop.
    pub(super) killed_in_drain: Vec<String>,
}

impl<'a> Run<'a> {
    /// Opens the run: the children's supervisor, the monitor's node and ports, the recorder
    /// and the dashboard; `summary.json` says `running` from here on (`finish` replaces it).
    pub(super) fn open(options: &'a RunOptions, mut prepared: Prepared) -> anyhow::Result<Run<'a>> {
        let dashboard = prepared.dashboard.take();
        let config = &options.config;
        let started = Instant::now();
        let monitor_cpu_at_start_s = crate::children::own_cpu_s();
        let t0_ns = wire::monotonic_ns();
        let supervisor = Supervisor::new(&options.exe, &prepared.results.logs())?;
        let (node, _) = prepared.instance.create_node("monitor")?;
        let subscriptions = Rc::new(Subscriptions::new(&node)?);
        let settings = RecorderSettings {
            fields_every: config.run.fields_every,
            vtk: config.run.vtk,
            truth: config.camera.source.has_truth(),
            framing: config.camera.framing(),
            gauges: config.correlator.gauges.clone(),
            control_gauge: config.correlator.control_gauge.clone(),
            scale: crate::field_scale::FieldScale::of(config),
        };
        let units = crate::units_file::units_json(
            &crate::frames::csv_header_with(
                settings.truth,
                &crate::gauge_columns::header(&settings.gauges, settings.scale.in_mm()),
            ),
            config.correlator.strain,
            &settings.scale,
        );
        let units_path = prepared.results.path(wire::column_units::SIDECAR);
        wire::files::write_atomic(&units_path, units.as_bytes())?;
        let recorder = Recorder::new(&prepared.results, settings, t0_ns)?;
        start::write_running(
            &prepared.results,
            &prepared.name,
            &prepared.start,
            &config.camera.source,
            &config.rig.source,
        )?;
        Ok(Run {
            options,
            subscriptions,
            node,
            supervisor,
            recorder,
            dashboard,
            prepared,
            incidents: Incidents::default(),
            started,
            monitor_cpu_at_start_s,
            camera_away: false,
            phase: Phase::Running,
            liveness: super::stale::liveness(config),
            remote_rig: super::remote_rig::RemoteRig::default(),
            killed_in_drain: vec![],
        })
    }

    pub(super) fn config(&self) -> &'a RunConfig {
        &self.options.config
    }

    /// How long a stopped child gets between SIGTERM and SIGKILL.
    pub(super) fn stop_timeout(&self) -> Duration {
        Duration::from_secs_f64(self.config().run.stop_timeout_s)
    }

    /// The arguments of `role` in this run after its settings file, if any, was written (see
    /// [`super::child_launch`]).
    pub(super) fn child_args(
        &self,
        role: Role,
        first_frame_id: u64,
    ) -> anyhow::Result<Vec<String>> {
        let prepared = &self.prepared;
        let launch = super::child_launch(
            role,
            self.config(),
            &prepared.name,
            &prepared.results,
            first_frame_id,
        )?;
        Ok(launch.into_args()?)
    }
}
