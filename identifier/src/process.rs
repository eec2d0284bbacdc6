//! The live `identifier` process: subscribes to `fields` and `rig/state`, feeds the pure
//! [`OnlineIdentifier`], publishes an `identification` report after each refit, and writes
//! the final fits as JSON (atomically) when it stops. Sleeps in a WaitSet: no polling.

use crate::models::Model;
use crate::online::{FieldSample, OnlineConfig, OnlineIdentifier, RigSample};
use crate::report::fit_json;
use iceoryx2::prelude::*;
use std::path::PathBuf;
use std::time::Duration;
use wire::identification::{RankedModel, MAX_COEFFICIENTS, MAX_RANKED};
use wire::pubsub::{SliceSubscriber, ValuePublisher, ValueSubscriber};
use wire::{
    services, FieldHeader, FieldNode, IdentificationReport, Instance, RigState, StrainMeasure,
};

mod field;
mod shell;

pub use field::{fits_json, force_balance, FieldFeed, FieldRouteSettings};
use wire::identification::IdentifierRoutes;

/// Settings of the process: what `dicstream run` writes for its identifier (`--settings`),
/// and what the command line's flags make.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcessConfig {
    pub instance: String,
    /// The fits as JSON, written atomically at most once a second while points come in and
    /// at the end, so a killed process leaves its last fits.
    pub output_json: PathBuf,
    /// Journal of accepted points (see [`crate::journal`]): read back at start, appended as
    /// points are accepted. None: no journal.
    pub journal: Option<PathBuf>,
    /// Stop after this many fields (None: until SIGINT/SIGTERM or idle timeout).
    pub max_fields: Option<u64>,
    /// Stop after this long without any sample (None: never).
    #[serde(with = "wire::seconds::option", rename = "idle_timeout_s", default)]
    pub idle_timeout: Option<Duration>,
    #[serde(default)]
    pub online: OnlineConfig,
    /// The routes run: the gauge's (`online`), the whole field's (`field`), or both.
    #[serde(default = "gauge_route")]
    pub routes: IdentifierRoutes,
    /// The field route's view and specimen (needed when `routes` runs it).
    #[serde(default)]
    pub field: Option<FieldRouteSettings>,
    /// Where the field route writes, at the end, each state of its kept frames with its
    /// contribution to the best fit (`crate::state_contributions::states_csv`); None: not
    /// written. Nothing is written without a ranked fit.
    #[serde(default)]
    pub states_csv: Option<PathBuf>,
}

fn gauge_route() -> IdentifierRoutes {
    IdentifierRoutes::Gauge
}

/// What the run did.
#[derive(Clone, Debug, Default)]
pub struct ProcessSummary {
    pub fields_received: u64,
    pub rig_samples_received: u64,
    pub reports_published: u64,
    pub points: [usize; 3],
    pub best_model: Option<String>,
}

/// Why the identifier process could not start or stopped. A file that could not be written is
/// also the error's `source()`, so that `wire::exit::code_of` finds its exit code.
#[derive(Debug, thiserror::Error)]
pub enum ProcessError {
    /// Also the `source()`: a subscriber that cannot connect keeps its exit code.
    #[error("{0}")]
    Instance(#[from] wire::InstanceError),
    #[error(transparent)]
    Journal(#[from] crate::journal::JournalError),
    #[error("{0}")]
    File(#[from] wire::files::FileError),
    #[error("{0}")]
    WaitSetCreate(#[from] wire::resources::WaitSetError),
    #[error(transparent)]
    WaitSetAttach(#[from] iceoryx2::waitset::WaitSetAttachmentError),
    #[error(transparent)]
    WaitSetRun(#[from] iceoryx2::waitset::WaitSetRunError),
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    #[error(
        "the {routes} route needs the field route's settings (the camera's view and the cruciform)"
    )]
    NoFieldSettings { routes: IdentifierRoutes },
    #[error("the field route's specimen: {0}")]
    Geometry(#[from] membrane::GeometryError),
}

/// The line printed when the first field comes (`identifier: first field received (frame N)`):
/// `dicstream run` reads it to tell an identifier that hears its input from one that does not.
pub const FIRST_FIELD_LINE: &str = "identifier: first field received";

/// How long one WaitSet wait lasts before the idle clock is checked.
const WAIT_SLICE: Duration = Duration::from_millis(200);

fn rig_sample(state: &RigState) -> RigSample {
    let a = &state.actuators;
    RigSample {
        sample_id: state.sample_id,
        t_ns: state.t_published_ns,
        force_x_n: 500.0 * (a[0].force_kn + a[1].force_kn),
        force_y_n: 500.0 * (a[2].force_kn + a[3].force_kn),
        section_x_mm2: state.specimen_section_x_mm2,
        section_y_mm2: state.specimen_section_y_mm2,
    }
}

fn field_sample(header: &FieldHeader) -> Option<FieldSample> {
    wire::layouts::check_version("field", header.layout_version).ok()?;
    let gauge = header.gauge_of(StrainMeasure::Log);
    // A control gauge without a reading (NaN) gives no state.
    if !(gauge.exx.is_finite() && gauge.eyy.is_finite()) {
        return None;
    }
    Some(FieldSample {
        frame_id: header.frame_id,
        // A frame without a rig sample (a real camera's) is paired by time.
        rig_sample_id: match header.rig_sample_id {
            wire::NO_RIG_SAMPLE => crate::online::PAIR_BY_TIME,
            id => id,
        },
        t_capture_ns: header.t_capture_ns,
        log_strain_xx: gauge.exx,
        log_strain_yy: gauge.eyy,
    })
}

/// Builds the wire report from the ranked fits (best first).
pub fn build_report(
    fits: &[crate::fit::Fit],
    points: [usize; 3],
    frame: Option<(u64, u64)>,
) -> IdentificationReport {
    let mut report = IdentificationReport {
        points: points.map(|p| p as u32),
        ..IdentificationReport::default()
    };
    if let Some((frame_id, t_capture_ns)) = frame {
        report.frame_id = frame_id;
        report.t_capture_ns = t_capture_ns;
    }
    if let Some(ldr) = fits
        .iter()
        .find(|f| matches!(f.model, Model::LambertDianiRey { .. }))
    {
        if let Model::LambertDianiRey { f_degree, g_degree } = ldr.model {
            let (na, nb) = (
                (f_degree + 1).min(MAX_COEFFICIENTS),
                (g_degree + 1).min(MAX_COEFFICIENTS),
            );
            for i in 0..na {
                report.a[i] = ldr.params[i];
                report.a_stderr[i] = ldr.stderr[i].unwrap_or(f64::NAN);
            }
            for i in 0..nb {
                report.b[i] = ldr.params[f_degree + 1 + i];
                report.b_stderr[i] = ldr.stderr[f_degree + 1 + i].unwrap_or(f64::NAN);
            }
            report.a_count = na as u32;
            report.b_count = nb as u32;
            report.rms_mpa = ldr.rms_mpa;
        }
    }
    for (slot, fit) in report.ranking.iter_mut().zip(fits.iter().take(MAX_RANKED)) {
        let mut ranked = RankedModel {
            name: [0; 24],
            aic: fit.aic,
            rms_mpa: fit.rms_mpa,
        };
        wire::text::write_fixed(&mut ranked.name, &fit.model.name());
        *slot = ranked;
    }
    report.ranked_count = fits.len().min(MAX_RANKED) as u32;
    report
}

/// Runs the process until a termination signal, `max_fields`, or the idle timeout.
pub fn run(config: ProcessConfig) -> Result<ProcessSummary, ProcessError> {
    let instance = Instance::new(&config.instance)?;
    let _owner = instance.claim("identifier")?;
    let (node, cleaned) = instance.create_node("identifier")?;
    if cleaned > 0 {
        eprintln!(
            "identifier: cleaned {cleaned} dead node(s) of instance {}",
            instance.name()
        );
    }
    let fields: SliceSubscriber<FieldNode, FieldHeader> =
        SliceSubscriber::create(&node, &services::FIELDS)?;
    let rig: ValueSubscriber<RigState> = ValueSubscriber::create(&node, &services::RIG_STATE)?;
    let publisher: ValuePublisher<IdentificationReport> =
        ValuePublisher::create(&node, &services::IDENTIFICATION)?;
    let waitset = wire::signals::waitset()?;
    eprintln!("identifier: ready (instance {})", instance.name());
    let fields_guard = waitset.attach_notification(fields.listener())?;
    let rig_guard = waitset.attach_notification(rig.listener())?;
    let mut identifier = shell::Identifier::open(&config)?;
    loop {
        let mut accepted_any = false;
        let mut failure: Option<ProcessError> = None;
        waitset.wait_and_process_once_with_timeout(
            |id| {
                if id.has_event_from(&rig_guard) {
                    rig.clear_events();
                }
                if id.has_event_from(&fields_guard) {
                    fields.clear_events();
                }
                match identifier.take_samples(&rig, &fields) {
                    Ok(accepted) => {
                        accepted_any |= accepted;
                        CallbackProgression::Continue
                    }
                    Err(e) => {
                        failure = Some(e);
                        CallbackProgression::Stop
                    }
                }
            },
            WAIT_SLICE,
        )?;
        if let Some(e) = failure {
            return Err(e);
        }
        // An early wake-up (a signal, SIGCONT after SIGSTOP) is not a request to stop.
        let signalled = wire::signals::requested().is_some();
        if accepted_any {
            identifier.refit(&publisher)?;
        }
        identifier.refit_field(&publisher)?;
        if signalled || identifier.limit_reached() {
            break;
        }
    }
    identifier.finish()
}

/// The JSON of `identification.json`: points per case, pairing counters, ranked fits.
fn final_json(
    summary: &ProcessSummary,
    online: &OnlineIdentifier,
    fits: &[crate::fit::Fit],
    field_route: Option<serde_json::Value>,
) -> Result<String, ProcessError> {
    let points = online.point_counts();
    let mut json = serde_json::json!({
        "points": {"uniaxial": points[0], "equibiaxial": points[1], "pure_shear": points[2], "biaxial_general": online.general_count()},
        "paths": online.path_count(),
        "fields_received": summary.fields_received,
        "rig_samples_received": summary.rig_samples_received,
        "pairing": {"accepted": online.counters.accepted, "skipped": online.counters.skipped, "dropped": online.counters.dropped},
        "fits": fits.iter().map(fit_json).collect::<Vec<_>>(),
    });
    if let Some(field_route) = field_route {
        json["field_route"] = field_route;
    }
    Ok(serde_json::to_string_pretty(&json)?)
}
