//! The field route in the identifier process: each field's nodes to the reference grid in mm
//! (through the producer's `View::centred`, the one mapping of the camera's px to specimen mm),
//! the grips' forces of the rig sample the frame names, the pure [`FieldRoute`] fed, and refitted
//! on a thread of its own (at most every [`REFIT_INTERVAL`], and at the end) so that neither
//! the gauge route nor the reception of fields ever waits for a fit; its report published
//! beside the gauge route's.
//!
//! Restart: the field route journals nothing. A restarted identifier refits from the fields it
//! receives after the restart (the frames before it are not re-sent): it says so on stderr and
//! its `identification.json` counts only what it saw.

use super::ProcessError;
use crate::field_layout::{ArmLayout, LayoutError};
use crate::field_route::{
    FieldFits, FieldRoute, FieldRouteConfig, FitJob, FrameOutcome, GripBalance,
};
use crate::field_stress::Mat2;
use crate::grip_forces::{ForceHistory, GripForces};
use crate::models::Model;
use crate::section_cut::FieldGrid;
use membrane::specimens::cruciform::CruciformGeometry;
use producer::View;
use serde_json::{json, Value};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use wire::identification::{RankedModel, ReportRoute, MAX_COEFFICIENTS, MAX_RANKED};
use wire::{FieldHeader, FieldNode, IdentificationReport, NodeStatus, RigState};

/// Shortest time between the starts of two fits of all frames.
pub const REFIT_INTERVAL: Duration = Duration::from_secs(2);

/// What the field route needs of the run: the camera's view and the specimen filmed.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldRouteSettings {
    /// The camera's scale and image size: the view is `View::centred` of them.
    pub mm_per_px: f64,
    pub width_px: u32,
    pub height_px: u32,
    /// The cruciform filmed (its outline, arms and thickness).
    pub cruciform: CruciformGeometry,
    /// A frame is kept when the mean stretching of its measured nodes grew by this since the
    /// last one.
    #[serde(default = "default_level_increment")]
    pub min_level_increment: f64,
    #[serde(default = "default_max_frames")]
    pub max_frames: usize,
}

impl FieldRouteSettings {
    pub const DEFAULT_LEVEL_INCREMENT: f64 = 0.0015;
    /// Frames kept (spread over the loading: `FieldRoute` thins them at the limit).
    pub const DEFAULT_MAX_FRAMES: usize = 24;
}

fn default_level_increment() -> f64 {
    FieldRouteSettings::DEFAULT_LEVEL_INCREMENT
}

fn default_max_frames() -> usize {
    FieldRouteSettings::DEFAULT_MAX_FRAMES
}

/// Cost of the route, ns.
#[derive(Debug, Default)]
struct Cost {
    prepare_ns: Vec<u64>,
    fit_ns: Vec<u64>,
    correlate_ns: Vec<u64>,
}

fn ms(ns: &[u64]) -> Value {
    if ns.is_empty() {
        return Value::Null;
    }
    let mean = ns.iter().sum::<u64>() as f64 / ns.len() as f64 * 1e-6;
    let max = *ns.iter().max().unwrap_or(&0) as f64 * 1e-6;
    json!({"count": ns.len(), "mean": mean, "max": max})
}

/// The field route fed with frames as the camera saw them: node px mapped to specimen mm
/// through the camera's view, the specimen's outline, each frame's loading level. The one
/// feed of the route, live (the identifier process) and offline (`identify --fields`:
/// `crate::saved_fields`).
pub struct FieldFeed {
    pub route: FieldRoute,
    view: View,
    mesh: membrane::Mesh,
    elements: membrane::ElementGrid,
}

impl FieldFeed {
    /// Kept frames before the first fit.
    pub const MIN_FRAMES_TO_FIT: usize = 3;

    pub fn new(
        settings: &FieldRouteSettings,
        models: &[Model],
    ) -> Result<Self, membrane::GeometryError> {
        let specimen = settings.cruciform.mesh()?;
        let elements = membrane::ElementGrid::new(&specimen.mesh);
        let c = &settings.cruciform;
        Ok(Self {
            route: FieldRoute::new(FieldRouteConfig {
                layout: ArmLayout {
                    arm_width_mm: c.arm_width_mm,
                    fillet_radius_mm: c.fillet_radius_mm,
                },
                thickness_mm: c.thickness_mm,
                models: models.to_vec(),
                min_level_increment: settings.min_level_increment,
                max_frames: settings.max_frames,
                min_frames_to_fit: Self::MIN_FRAMES_TO_FIT,
                central_ramps: true,
            }),
            view: View::centred(settings.mm_per_px, settings.width_px, settings.height_px),
            mesh: specimen.mesh,
            elements,
        })
    }

    /// A grid of `cols` x `rows` nodes `step_px` apart from `first_px` (the first node, in its
    /// origin image) in specimen mm, each node's F (None: not measured).
    pub fn grid(
        &self,
        first_px: [f64; 2],
        step_px: f64,
        (cols, rows): (usize, usize),
        gradients: Vec<Option<Mat2>>,
    ) -> FieldGrid {
        let (origin, step_mm) = self.placement(first_px, step_px);
        FieldGrid {
            cols,
            rows,
            x0_mm: origin[0],
            y0_mm: origin[1],
            step_mm,
            gradients,
        }
    }

    /// The first node in specimen mm and the nodes' pitch, mm.
    fn placement(&self, first_px: [f64; 2], step_px: f64) -> ([f64; 2], f64) {
        let origin = self.view.to_mm(first_px);
        let next = self.view.to_mm([first_px[0] + step_px, first_px[1]]);
        (origin, next[0] - origin[0])
    }

    /// The measured displacements (px) of the same grid as [`Self::grid`] in specimen mm.
    pub fn displacement_grid(
        &self,
        first_px: [f64; 2],
        step_px: f64,
        (cols, rows): (usize, usize),
        displacements_px: Vec<Option<[f64; 2]>>,
    ) -> crate::measured_displacement::DisplacementGrid {
        let (origin, step_mm) = self.placement(first_px, step_px);
        let to_mm = |u: [f64; 2]| {
            let moved = self.view.to_mm([first_px[0] + u[0], first_px[1] + u[1]]);
            [moved[0] - origin[0], moved[1] - origin[1]]
        };
        crate::measured_displacement::DisplacementGrid {
            cols,
            rows,
            x0_mm: origin[0],
            y0_mm: origin[1],
            step_mm,
            displacements_mm: displacements_px.into_iter().map(|u| u.map(to_mm)).collect(),
        }
    }

    /// Offers frame `frame_id` of test `sequence` to the route (its loading level the mean
    /// stretching of its measured nodes, its material the specimen's outline).
    pub fn offer(
        &mut self,
        frame_id: u64,
        sequence: u32,
        grid: Option<FieldGrid>,
        forces_n: Option<[f64; 4]>,
    ) -> Result<FrameOutcome, LayoutError> {
        let level = grid.as_ref().map_or(0.0, mean_stretching);
        let (mesh, elements) = (&self.mesh, &self.elements);
        let material = |x: [f64; 2]| elements.locate(mesh, x).is_some();
        self.route.set_sequence(sequence);
        self.route.push(frame_id, grid, forces_n, level, &material)
    }
}

pub(super) struct FieldShell {
    feed: FieldFeed,
    history: ForceHistory,
    /// Why the route stopped (a view that crosses no arm), said once.
    error: Option<String>,
    fits: Option<FieldFits>,
    /// Frames kept since the last fit started.
    dirty: bool,
    last_fit: Option<Instant>,
    /// The fit running on its own thread (its result and duration, ns), and the last frame
    /// it fits.
    running: Option<RunningFit>,
    cost: Cost,
}

impl FieldShell {
    pub fn new(settings: &FieldRouteSettings, models: &[Model]) -> Result<Self, ProcessError> {
        Ok(Self {
            feed: FieldFeed::new(settings, models)?,
            history: ForceHistory::default(),
            error: None,
            fits: None,
            dirty: false,
            last_fit: None,
            running: None,
            cost: Cost::default(),
        })
    }

    pub fn on_rig(&mut self, state: &RigState) {
        let a = &state.actuators;
        self.history.push(GripForces {
            sample_id: state.sample_id,
            t_ns: state.t_published_ns,
            forces_n: crate::grip_forces::on_specimen(
                state.load_case,
                std::array::from_fn(|i| 1e3 * a[i].force_kn),
            ),
        });
    }

    /// The field's nodes on the reference grid in mm: F = I + ∇u of every `ok` node, None for
    /// the others; None for a field of another layout (no gradients to read).
    fn grid(&self, header: &FieldHeader, nodes: &[FieldNode]) -> Option<FieldGrid> {
        let (cols, rows) = (header.mesh_cols as usize, header.mesh_rows as usize);
        if header.validate(nodes.len()).is_err() || cols == 0 {
            return None;
        }
        let first = [f64::from(nodes[0].x_px), f64::from(nodes[0].y_px)];
        let gradients = nodes
            .iter()
            .map(|n| {
                (n.status == NodeStatus::Ok as u32).then(|| {
                    [
                        [1.0 + f64::from(n.du_dx), f64::from(n.du_dy)],
                        [f64::from(n.dv_dx), 1.0 + f64::from(n.dv_dy)],
                    ]
                })
            })
            .collect();
        Some(
            self.feed
                .grid(first, f64::from(header.step_px), (cols, rows), gradients),
        )
    }

    pub fn on_field(&mut self, header: &FieldHeader, nodes: &[FieldNode]) {
        if self.error.is_some() {
            return;
        }
        let started = Instant::now();
        self.cost.correlate_ns.push(header.correlate_ns);
        let grid = self.grid(header, nodes);
        let sample = (header.rig_sample_id != wire::NO_RIG_SAMPLE).then_some(header.rig_sample_id);
        let forces = self.history.find(sample, header.t_capture_ns);
        match self
            .feed
            .offer(header.frame_id, header.sequence_id, grid, forces)
        {
            Ok(FrameOutcome::Kept) => self.dirty = true,
            Ok(_) => {}
            Err(e) => {
                eprintln!("identifier: field route stopped: {e}");
                self.error = Some(e.to_string());
            }
        }
        self.cost
            .prepare_ns
            .push(started.elapsed().as_nanos() as u64);
    }

    /// The report of a fit that has finished, if any; starts the next one when new frames
    /// came and [`REFIT_INTERVAL`] has passed since the last start. With `now` (the end), waits
    /// for the running fit and fits the frames kept since, here.
    pub fn refit(&mut self, now: bool) -> Option<IdentificationReport> {
        let mut report = None;
        if self
            .running
            .as_ref()
            .is_some_and(|(running, _)| now || running.is_finished())
        {
            report = self.take_running();
        }
        if now {
            if self.dirty {
                // Started where the last fit ended, as on line: the end's fit must finish
                // within the run's stop timeout.
                if let Some(job) = self.warm_job() {
                    self.dirty = false;
                    report = Some(self.finished(run_timed(&job), job.last_frame_id));
                }
            }
            return report;
        }
        let due = self.last_fit.is_none_or(|t| t.elapsed() >= REFIT_INTERVAL);
        if self.running.is_none() && self.dirty && due {
            if let Some(job) = self.warm_job() {
                self.dirty = false;
                self.last_fit = Some(Instant::now());
                let frame_id = job.last_frame_id;
                let spawned = std::thread::Builder::new()
                    .name("field-fit".into())
                    .spawn(move || run_timed(&job));
                match spawned {
                    Ok(handle) => self.running = Some((handle, frame_id)),
                    // No thread to be had: fit here, once, rather than never.
                    Err(e) => {
                        eprintln!("identifier: field route: no thread for the fit ({e}): fitting in the loop");
                        let job = self.feed.route.fit_job()?;
                        return Some(self.finished(run_timed(&job), job.last_frame_id));
                    }
                }
            }
        }
        report
    }

    /// A fit of all kept frames whose nonlinear models start where the last fit ended.
    fn warm_job(&self) -> Option<FitJob> {
        let mut job = self.feed.route.fit_job()?;
        job.warm_starts = self.fits.as_ref().map_or(vec![], |fits| {
            fits.fits
                .iter()
                .map(|f| (f.model.clone(), f.fit.params.clone()))
                .collect()
        });
        Some(job)
    }

    /// The running fit's report (None if its thread panicked, which is said).
    fn take_running(&mut self) -> Option<IdentificationReport> {
        let (handle, frame_id) = self.running.take()?;
        match handle.join() {
            Ok(result) => Some(self.finished(result, frame_id)),
            Err(_) => {
                eprintln!("identifier: field route: the fit's thread panicked");
                None
            }
        }
    }

    fn finished(
        &mut self,
        (fits, ns): (FieldFits, u64),
        frame_id: Option<u64>,
    ) -> IdentificationReport {
        self.cost.fit_ns.push(ns);
        let report = report(&fits, frame_id);
        self.fits = Some(fits);
        report
    }

    /// `states.csv` of the last fit: each state of the kept frames with its contribution to
    /// the best ranked fit (None: no ranked fit).
    pub fn states_csv(
        &self,
    ) -> Option<Result<String, crate::state_contributions::ContributionError>> {
        let fits = self.fits.as_ref()?;
        let contributions = crate::state_contributions::of_best_fit(&self.feed.route, fits)?;
        Some(contributions.map(|c| crate::state_contributions::states_csv(&c)))
    }

    /// The route's part of `identification.json`.
    pub fn json(&self) -> Value {
        let fits = self.fits.as_ref();
        let mut out = json!({
            "error": self.error,
            "counters": self.feed.route.counters,
            "last_dropped": self.feed.route.last_dropped,
            "cost_ms": {
                "prepare_per_field": ms(&self.cost.prepare_ns),
                "fit_all_frames": ms(&self.cost.fit_ns),
                "correlator_per_field": ms(&self.cost.correlate_ns),
            },
        });
        let fitted = fits.map_or(
            json!({"frames": null, "reach": null, "fits": null, "refused": null, "not_told_apart": null}),
            fits_json,
        );
        if let (Some(out), Value::Object(fitted)) = (out.as_object_mut(), fitted) {
            out.extend(fitted);
        }
        out["force_balance"] = json!(fits.map_or(vec![], |f| force_balance(&self.feed.route, f)));
        out
    }
}

/// The fits' part of the field route's JSON: frames, the stretches reached (`reach`:
/// [`crate::reach::Reach`]), each fit
/// (parameters, σ, RMS force, equations, condition number, AIC, BIC; the first ranked first:
/// by BIC, the fewest parameters first among the models the forces do not tell apart, listed
/// in `not_told_apart` with their stresses' spread, null when one stands out) and the models
/// refused with why. `identification.json`'s `field_route` and `identify --fields --json`.
pub fn fits_json(fits: &FieldFits) -> Value {
    json!({
        "frames": fits.frames,
        "reach": fits.reach,
        "fits": fits.fits.iter().map(|fit| {
            let names = fit.model.param_names();
            json!({
                "model": fit.model.name(),
                "params": names.iter().cloned().zip(fit.fit.params.iter().map(|v| json!(v))).collect::<serde_json::Map<String, Value>>(),
                "sigma": names.iter().cloned().zip(fit.fit.sigma.iter().map(|s| json!(s.is_finite().then_some(*s)))).collect::<serde_json::Map<String, Value>>(),
                "rms_n": fit.fit.rms_n,
                "equations": fit.fit.equations,
                "condition": fit.fit.condition,
                "aic": fit.aic,
                "bic": fit.bic,
                "identifiable": fit.ranked(),
                "warning": fit.identifiability.warning(),
            })
        }).collect::<Vec<_>>(),
        "refused": fits.refused.iter().map(|(m, why)| json!({"model": m, "why": why})).collect::<Vec<_>>(),
        "not_told_apart": fits.window,
    })
}

/// The kept frames' force balance per grip under the first ranked fit (none when no fit is
/// identifiable): `identification.json`'s `field_route.force_balance`.
pub fn force_balance(route: &FieldRoute, fits: &FieldFits) -> Vec<GripBalance> {
    fits.fits
        .iter()
        .find(|fit| fit.ranked())
        .map_or(vec![], |best| {
            route.force_balance(&best.model, &best.fit.params)
        })
}

/// A fit on its own thread (its fits and duration, ns) and the last frame it fits.
type RunningFit = (JoinHandle<(FieldFits, u64)>, Option<u64>);

/// A fit and its duration, ns.
fn run_timed(job: &FitJob) -> (FieldFits, u64) {
    let started = Instant::now();
    let fits = job.run();
    (fits, started.elapsed().as_nanos() as u64)
}

/// The loading level of a field: the mean over its measured nodes of (F11 + F22)/2 − 1 (the
/// gauge's average would mix the specimen with the room behind it).
fn mean_stretching(grid: &FieldGrid) -> f64 {
    let (sum, n) = grid
        .gradients
        .iter()
        .flatten()
        .fold((0.0, 0usize), |(s, n), f| {
            (s + 0.5 * (f[0][0] + f[1][1]) - 1.0, n + 1)
        });
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// The wire report of the field route's fits (best BIC first, each with its AIC: the wire's
/// `RankedModel` carries one criterion, the gauge route's): their ranking and, when the
/// paper's law is among them, its a and b. `rms_mpa` is NaN: the route's residuals are forces.
fn report(fits: &FieldFits, frame_id: Option<u64>) -> IdentificationReport {
    let mut report = IdentificationReport {
        route: ReportRoute::Field as u32,
        rms_mpa: f64::NAN,
        frame_id: frame_id.unwrap_or(0),
        ..IdentificationReport::default()
    };
    if let Some(fit) = fits
        .fits
        .iter()
        .find(|f| matches!(f.model, Model::LambertDianiRey { .. }))
    {
        if let Model::LambertDianiRey { f_degree, .. } = fit.model {
            let p = &fit.fit.params;
            let (a, b) = p.split_at(f_degree + 1);
            for (i, v) in a.iter().take(MAX_COEFFICIENTS).enumerate() {
                report.a[i] = *v;
                report.a_stderr[i] = fit.fit.sigma[i];
            }
            for (i, v) in b.iter().take(MAX_COEFFICIENTS).enumerate() {
                report.b[i] = *v;
                report.b_stderr[i] = fit.fit.sigma[f_degree + 1 + i];
            }
            report.a_count = a.len().min(MAX_COEFFICIENTS) as u32;
            report.b_count = b.len().min(MAX_COEFFICIENTS) as u32;
        }
    }
    for (slot, fit) in report.ranking.iter_mut().zip(&fits.fits) {
        *slot = RankedModel {
            name: [0; 24],
            aic: fit.aic,
            rms_mpa: f64::NAN,
        };
        wire::text::write_fixed(&mut slot.name, &fit.model.name());
    }
    report.ranked_count = fits.fits.len().min(MAX_RANKED) as u32;
    report.t_published_ns = wire::monotonic_ns();
    report
}
