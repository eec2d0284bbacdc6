//! On-line identification, pure logic (no IPC): pair measured strains with rig forces by rig
//! sample id, keep every biaxial state of the loading path, refit.
//!
//! Inputs are plain structs so the logic is tested without shared memory; the process shell
//! (`process` module) converts wire samples into them.
//!
//! Pairing: a field names the rig sample its frame was taken at. Rig samples are kept in a
//! bounded ring ([`OnlineConfig::rig_history`]); a field whose sample has not arrived yet waits
//! in a bounded queue ([`OnlineConfig::pending_fields`]) and is dropped (counted) when the queue
//! is full or its sample has left the ring.
//!
//! States: a paired field gives one [`BiaxialState`] (λx, λy, Px, Py) with λ = exp(gauge log
//! strain) and P = F / (current section · λ) along each axis (the nominal stress, as the
//! current section is the reference one over λ). Every state is kept and fitted, both
//! directions at once ([`crate::fit::FitData`]; the membrane formulas are in
//! [`crate::data`]): the canonical cases are special paths, named for the counts only, by
//! the ratio ρ = ln λ_small / ln λ_large: uniaxial −1/2, pure shear 0, equibiaxial 1 within
//! [`OnlineConfig::classify_tolerance`].
//!
//! Loading branch only: states are grouped into paths by their direction in the log-strain
//! plane, θ = atan2(ln λy, ln λx), a state joining the nearest path within
//! [`OnlineConfig::path_tolerance_rad`] of the path's newest state (or opening a new one, at most
//! [`OnlineConfig::max_paths`]); a state whose largest |ln λ| is below
//! [`OnlineConfig::min_log_strain`] is not a loading point (`NotStretched`): its direction is
//! the gauge's noise, and such states at rest, before each test, used to open a path each
//! until no path was left for the next test's real one. A state is kept when its larger stretch exceeds the last kept one of
//! its path by [`OnlineConfig::min_stretch_increment`] (unloading and reloading below the
//! maximum reached are skipped, as the Mullins effect makes them another material).
//!
//! A field whose frame names no rig sample ([`PAIR_BY_TIME`]: a real camera, a watched folder,
//! beside a followed machine log) is paired by time: its capture instant against the samples'
//! instants ([`RigSample::t_ns`], one monotonic clock), forces interpolated between the two
//! samples around it; it waits until a sample at or after it has come. Such samples come
//! from a machine's log, which knows no specimen model: their sections are the initial ones
//! A0, and the current section normal to an axis is A0 / λ of that axis (incompressible).

use crate::data::{BiaxialState, LoadCase};
use crate::fit::{fit_data, Fit, FitData, FitOptions};
use crate::models::Model;
use std::collections::VecDeque;

/// `FieldSample::rig_sample_id` of a field paired by time (its frame names no rig sample).
pub const PAIR_BY_TIME: u64 = u64::MAX;

/// One rig sample as the identifier needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigSample {
    pub sample_id: u64,
    /// Its instant on the monotonic clock, ns (`rig/state`'s `t_published_ns`).
    pub t_ns: u64,
    /// Grip force along x and y (mean of the two opposed actuators), N, tension positive.
    pub force_x_n: f64,
    pub force_y_n: f64,
    /// Current sections normal to x and y, mm².
    pub section_x_mm2: f64,
    pub section_y_mm2: f64,
}

/// One measured field as the identifier needs it: the gauge (ROI mean) log strains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSample {
    pub frame_id: u64,
    pub rig_sample_id: u64,
    pub t_capture_ns: u64,
    pub log_strain_xx: f64,
    pub log_strain_yy: f64,
}

/// Settings.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OnlineConfig {
    pub rig_history: usize,
    pub pending_fields: usize,
    /// |ρ − ρ_case| below which a state counts as a canonical case (names, counts).
    pub classify_tolerance: f64,
    /// Largest angle between a state's direction in the (ln λx, ln λy) plane and its path's.
    pub path_tolerance_rad: f64,
    /// Paths kept at most (a state opening one more is refused, counted).
    pub max_paths: usize,
    /// Largest |ln λ| below which a state is not a loading point (its direction in the
    /// log-strain plane would be the gauge's noise).
    pub min_log_strain: f64,
    pub min_stretch_increment: f64,
    /// States per path kept at most (later ones are refused, counted).
    pub max_points_per_path: usize,
    /// Models ranked at each refit (keep them cheap: refits run at each new point).
    pub models: Vec<Model>,
    /// Points in total before the first refit.
    pub min_points_to_fit: usize,
}

impl Default for OnlineConfig {
    fn default() -> Self {
        OnlineConfig {
            rig_history: 4096,
            pending_fields: 64,
            classify_tolerance: 0.15,
            path_tolerance_rad: 0.05,
            max_paths: 8,
            min_log_strain: 5e-3,
            min_stretch_increment: 2e-3,
            max_points_per_path: 2000,
            models: vec![
                Model::LambertDianiRey {
                    f_degree: 2,
                    g_degree: 2,
                },
                Model::NeoHookean,
                Model::Mooney,
                Model::Yeoh,
                Model::Gent,
                Model::HartSmith,
            ],
            min_points_to_fit: 8,
        }
    }
}

/// What happened to one field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldOutcome {
    /// Paired and accepted as a new state (of canonical `case`, if it is one).
    Accepted {
        case: Option<LoadCase>,
        state: BiaxialState,
    },
    /// Waiting for its rig sample.
    Pending,
    /// Paired but not a new loading point (unloading, too close, unclassified, unloaded).
    Skipped(SkipReason),
    /// Its rig sample is gone (too old) or the pending queue overflowed.
    Dropped,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkipReason {
    NotStretched,
    NotIncreasing,
    PathFull,
    TooManyPaths,
    BadSection,
}

/// Counters of the pairing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OnlineCounters {
    pub accepted: u64,
    pub skipped: u64,
    pub dropped: u64,
}

/// The accumulating identifier.
#[derive(Debug)]
pub struct OnlineIdentifier {
    config: OnlineConfig,
    rig: VecDeque<RigSample>,
    pending: VecDeque<FieldSample>,
    /// Every kept state, in arrival order.
    states: Vec<BiaxialState>,
    paths: Vec<LoadPath>,
    pub counters: OnlineCounters,
    /// The last field accepted (frame id, capture time ns).
    pub last_accepted: Option<(u64, u64)>,
    /// Per configured model, its last fitted parameters (the next refit's start).
    warm: Vec<Option<Vec<f64>>>,
    refits: u64,
    /// Paths in the last refit (a new path calls for a full search).
    fitted_paths: usize,
}

/// One loading path: its direction θ in the log-strain plane (its newest state's) and how far
/// it went.
#[derive(Clone, Copy, Debug)]
struct LoadPath {
    angle_rad: f64,
    last_max_stretch: f64,
    states: usize,
}

/// The direction θ = atan2(ln λy, ln λx) of a state in the log-strain plane.
fn path_angle_rad(state: &BiaxialState) -> f64 {
    state.stretch2.ln().atan2(state.stretch1.ln())
}

/// Angle between two directions, in [0, π].
fn angle_between_rad(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

/// A full multi-start search every this many refits (the others start from the last fit).
pub const FULL_SEARCH_EVERY: u64 = 16;

impl OnlineIdentifier {
    pub fn new(config: OnlineConfig) -> Self {
        assert!(
            config.rig_history > 0 && config.pending_fields > 0,
            "buffers must be non-empty"
        );
        OnlineIdentifier {
            rig: VecDeque::with_capacity(config.rig_history),
            pending: VecDeque::with_capacity(config.pending_fields),
            states: Vec::new(),
            paths: Vec::new(),
            counters: OnlineCounters::default(),
            last_accepted: None,
            warm: vec![None; config.models.len()],
            refits: 0,
            fitted_paths: 0,
            config,
        }
    }

    /// Adds a rig sample (ids increase); resolves fields that waited for it.
    pub fn push_rig(&mut self, sample: RigSample) -> Vec<(FieldSample, FieldOutcome)> {
        if let Some(last) = self.rig.back() {
            if sample.sample_id <= last.sample_id {
                // A restarted rig: forget the old history.
                self.rig.clear();
            }
        }
        if self.rig.len() == self.config.rig_history {
            self.rig.pop_front();
        }
        self.rig.push_back(sample);
        let mut resolved = Vec::new();
        let waiting: Vec<FieldSample> = self.pending.drain(..).collect();
        for field in waiting {
            let due = match field.rig_sample_id {
                PAIR_BY_TIME => field.t_capture_ns <= sample.t_ns,
                id => id <= sample.sample_id,
            };
            if due {
                let outcome = self.push_field(field);
                resolved.push((field, outcome));
            } else {
                self.pending.push_back(field);
            }
        }
        resolved
    }

    fn queue(&mut self, field: FieldSample) -> FieldOutcome {
        if self.pending.len() == self.config.pending_fields {
            self.pending.pop_front();
            self.counters.dropped += 1;
        }
        self.pending.push_back(field);
        FieldOutcome::Pending
    }

    /// The rig state at the field's capture instant, interpolated between the samples around
    /// it, with the current sections from the initial ones (see the module's text); `Err` with
    /// the outcome when there is none (yet, or any more).
    fn at_time(&mut self, field: FieldSample) -> Result<RigSample, FieldOutcome> {
        let t = field.t_capture_ns;
        match self.rig.back() {
            Some(newest) if newest.t_ns >= t => {}
            _ => return Err(self.queue(field)),
        }
        let after = self.rig.partition_point(|s| s.t_ns < t);
        let b = self.rig[after];
        let a = if after == 0 {
            if b.t_ns != t {
                return Err(FieldOutcome::Dropped);
            }
            b
        } else {
            self.rig[after - 1]
        };
        let w = if b.t_ns > a.t_ns {
            (t - a.t_ns) as f64 / (b.t_ns - a.t_ns) as f64
        } else {
            1.0
        };
        let mix = |x: f64, y: f64| x + w * (y - x);
        Ok(RigSample {
            sample_id: b.sample_id,
            t_ns: t,
            force_x_n: mix(a.force_x_n, b.force_x_n),
            force_y_n: mix(a.force_y_n, b.force_y_n),
            section_x_mm2: mix(a.section_x_mm2, b.section_x_mm2) / field.log_strain_xx.exp(),
            section_y_mm2: mix(a.section_y_mm2, b.section_y_mm2) / field.log_strain_yy.exp(),
        })
    }

    /// Adds a measured field; pairs it with its rig sample if present.
    pub fn push_field(&mut self, field: FieldSample) -> FieldOutcome {
        if field.rig_sample_id == PAIR_BY_TIME {
            let outcome = match self.at_time(field) {
                Ok(rig) => self.accept(field, rig),
                Err(FieldOutcome::Pending) => return FieldOutcome::Pending,
                Err(other) => other,
            };
            match outcome {
                FieldOutcome::Accepted { .. } => self.counters.accepted += 1,
                FieldOutcome::Skipped(_) => self.counters.skipped += 1,
                FieldOutcome::Dropped => self.counters.dropped += 1,
                FieldOutcome::Pending => {}
            }
            return outcome;
        }
        let newest = self.rig.back().map(|s| s.sample_id);
        let found = self
            .rig
            .binary_search_by_key(&field.rig_sample_id, |s| s.sample_id)
            .ok()
            .map(|i| self.rig[i]);
        let outcome = match (found, newest) {
            (Some(rig), _) => self.accept(field, rig),
            (None, Some(newest)) if field.rig_sample_id > newest => {
                return self.queue(field);
            }
            (None, None) => {
                return self.queue(field);
            }
            (None, Some(_)) => FieldOutcome::Dropped,
        };
        match outcome {
            FieldOutcome::Accepted { .. } => self.counters.accepted += 1,
            FieldOutcome::Skipped(_) => self.counters.skipped += 1,
            FieldOutcome::Dropped => self.counters.dropped += 1,
            FieldOutcome::Pending => {}
        }
        outcome
    }

    fn accept(&mut self, field: FieldSample, rig: RigSample) -> FieldOutcome {
        let (sx, sy) = (field.log_strain_xx.exp(), field.log_strain_yy.exp());
        if sx.max(sy) <= 1.0 + 1e-6 {
            return FieldOutcome::Skipped(SkipReason::NotStretched);
        }
        let section_ok = |a: f64| a > 0.0 && a.is_finite();
        if !(section_ok(rig.section_x_mm2)
            && section_ok(rig.section_y_mm2)
            && rig.force_x_n.is_finite()
            && rig.force_y_n.is_finite())
        {
            return FieldOutcome::Skipped(SkipReason::BadSection);
        }
        let state = BiaxialState {
            stretch1: sx,
            stretch2: sy,
            nominal_stress1_mpa: rig.force_x_n / rig.section_x_mm2 / sx,
            nominal_stress2_mpa: rig.force_y_n / rig.section_y_mm2 / sy,
        };
        match self.keep(state) {
            Ok(case) => {
                self.last_accepted = Some((field.frame_id, field.t_capture_ns));
                FieldOutcome::Accepted { case, state }
            }
            Err(reason) => FieldOutcome::Skipped(reason),
        }
    }

    /// The loading-branch rule (module doc): keeps `state` or says why not.
    fn keep(&mut self, state: BiaxialState) -> Result<Option<LoadCase>, SkipReason> {
        if state.check().is_err() {
            return Err(SkipReason::BadSection);
        }
        let largest_log_strain = state.stretch1.ln().abs().max(state.stretch2.ln().abs());
        if largest_log_strain < self.config.min_log_strain {
            return Err(SkipReason::NotStretched);
        }
        let Some(ratio) = state.path_ratio() else {
            return Err(SkipReason::NotStretched);
        };
        let angle = path_angle_rad(&state);
        let nearest = self
            .paths
            .iter()
            .enumerate()
            .map(|(i, p)| (i, angle_between_rad(angle, p.angle_rad)))
            .filter(|&(_, d)| d <= self.config.path_tolerance_rad)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i);
        let stretch = state.max_stretch();
        match nearest {
            Some(i) => {
                let path = &mut self.paths[i];
                if path.states >= self.config.max_points_per_path {
                    return Err(SkipReason::PathFull);
                }
                if stretch < path.last_max_stretch + self.config.min_stretch_increment {
                    return Err(SkipReason::NotIncreasing);
                }
                path.last_max_stretch = stretch;
                // The newest (largest) state gives the direction best: follows the path.
                path.angle_rad = angle;
                path.states += 1;
            }
            None => {
                if self.paths.len() >= self.config.max_paths {
                    return Err(SkipReason::TooManyPaths);
                }
                self.paths.push(LoadPath {
                    angle_rad: angle,
                    last_max_stretch: stretch,
                    states: 1,
                });
            }
        }
        self.states.push(state);
        Ok(LoadCase::of_path_ratio(
            ratio,
            self.config.classify_tolerance,
        ))
    }

    /// Puts back a state accepted by an earlier run (from its journal), with the same
    /// loading-branch rule as live states; returns whether it was kept.
    pub fn restore(&mut self, state: BiaxialState) -> bool {
        self.keep(state).is_ok()
    }

    /// States kept per canonical case, in [`LoadCase::ALL`] order (the others are in
    /// [`OnlineIdentifier::general_count`]).
    pub fn point_counts(&self) -> [usize; 3] {
        let mut counts = [0; 3];
        for state in &self.states {
            let case = state
                .path_ratio()
                .and_then(|r| LoadCase::of_path_ratio(r, self.config.classify_tolerance));
            if let Some(case) = case {
                counts[LoadCase::ALL
                    .iter()
                    .position(|c| *c == case)
                    .expect("in ALL")] += 1;
            }
        }
        counts
    }

    /// States kept that are none of the canonical cases.
    pub fn general_count(&self) -> usize {
        self.states.len() - self.point_counts().iter().sum::<usize>()
    }

    /// Every state kept, in arrival order.
    pub fn states(&self) -> &[BiaxialState] {
        &self.states
    }

    /// Loading paths seen so far.
    pub fn path_count(&self) -> usize {
        self.paths.len()
    }

    /// Refits the configured models on every state so far; `None` before enough states. Each
    /// model starts from its last solution (a few Levenberg-Marquardt steps after a few more
    /// points); every [`FULL_SEARCH_EVERY`]th refit, when a path appears, or when the warm
    /// start fails, the full multi-start search runs instead.
    pub fn refit(&mut self) -> Option<Vec<Fit>> {
        if self.states.len() < self.config.min_points_to_fit {
            return None;
        }
        let paths = self.paths.len();
        let full = self.refits.is_multiple_of(FULL_SEARCH_EVERY) || paths != self.fitted_paths;
        self.refits += 1;
        self.fitted_paths = paths;
        let data = FitData {
            curves: &[],
            states: &self.states,
        };
        let mut fits = Vec::with_capacity(self.config.models.len());
        for (k, model) in self.config.models.iter().enumerate() {
            let options = FitOptions {
                warm_start: if full { None } else { self.warm[k].clone() },
                ..FitOptions::default()
            };
            match fit_data(model, data, &options, &mut |_| {}) {
                Ok(fit) => {
                    self.warm[k] = Some(fit.params.clone());
                    fits.push(fit);
                }
                Err(_) => self.warm[k] = None,
            }
        }
        fits.sort_by(|a, b| a.aic.total_cmp(&b.aic));
        (!fits.is_empty()).then_some(fits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::law::InvariantLaw;

    /// Simulates a rig pulling a Smactane sheet (width 20 mm, thickness 2 mm) along `case`.
    fn simulate(
        id: &mut OnlineIdentifier,
        case: LoadCase,
        max_stretch: f64,
        first_sample: u64,
    ) -> u64 {
        let law = InvariantLaw::smactane();
        let mut sample_id = first_sample;
        for k in 1..=40 {
            let stretch = 1.0 + (max_stretch - 1.0) * k as f64 / 40.0;
            let (l1, l2) = case.in_plane_stretches(stretch);
            let s = law.in_plane_stress(l1, l2);
            let l3 = s.stretch3;
            let section_x_mm2 = 20.0 * l2 * 2.0 * l3;
            let section_y_mm2 = 20.0 * l1 * 2.0 * l3;
            let rig = RigSample {
                sample_id,
                t_ns: sample_id * 1000,
                force_x_n: s.cauchy_stress_mpa[0] * section_x_mm2,
                force_y_n: s.cauchy_stress_mpa[1] * section_y_mm2,
                section_x_mm2,
                section_y_mm2,
            };
            let field = FieldSample {
                frame_id: sample_id,
                rig_sample_id: sample_id,
                t_capture_ns: sample_id * 1000,
                log_strain_xx: l1.ln(),
                log_strain_yy: l2.ln(),
            };
            // Alternate orders: field first (pending) or rig first.
            if k % 2 == 0 {
                assert_eq!(id.push_field(field), FieldOutcome::Pending);
                let resolved = id.push_rig(rig);
                assert!(
                    matches!(resolved[0].1, FieldOutcome::Accepted { .. }),
                    "{resolved:?}"
                );
            } else {
                id.push_rig(rig);
                let out = id.push_field(field);
                match out {
                    FieldOutcome::Accepted { case: c, state } => {
                        assert_eq!(c, Some(case));
                        let nominal_stress_mpa = state.nominal_stress1_mpa;
                        let expected = s.nominal_stress_mpa[0];
                        assert!(
                            (nominal_stress_mpa - expected).abs() < 1e-9 * expected.abs().max(1.0)
                        );
                    }
                    other => panic!("{other:?}"),
                }
            }
            sample_id += 1;
        }
        sample_id
    }

    /// Fields at rest before each test (the gauge's noise, |ln λ| ~ 1e-5 in every direction)
    /// open no path: the equibiaxial test after a uniaxial one still has its path (they used
    /// to open one each, until `max_paths` refused the equibiaxial states).
    #[test]
    fn noise_at_rest_opens_no_path() {
        let mut id = OnlineIdentifier::new(OnlineConfig::default());
        let mut sample_id = 1;
        let at_rest = |id: &mut OnlineIdentifier, sample_id: &mut u64| {
            for k in 0..20 {
                let angle = k as f64 * 2.4;
                id.push_rig(RigSample {
                    sample_id: *sample_id,
                    t_ns: *sample_id * 1000,
                    force_x_n: 0.1,
                    force_y_n: 0.1,
                    section_x_mm2: 40.0,
                    section_y_mm2: 40.0,
                });
                let outcome = id.push_field(FieldSample {
                    frame_id: *sample_id,
                    rig_sample_id: *sample_id,
                    t_capture_ns: *sample_id * 1000,
                    log_strain_xx: 2e-5 * angle.cos(),
                    log_strain_yy: 2e-5 * angle.sin(),
                });
                assert_eq!(outcome, FieldOutcome::Skipped(SkipReason::NotStretched));
                *sample_id += 1;
            }
        };
        at_rest(&mut id, &mut sample_id);
        sample_id = simulate(&mut id, LoadCase::Uniaxial, 2.0, sample_id);
        at_rest(&mut id, &mut sample_id);
        simulate(&mut id, LoadCase::Equibiaxial, 1.8, sample_id);
        assert_eq!(id.point_counts(), [40, 40, 0]);
        assert_eq!(id.counters.skipped, 40);
    }

    #[test]
    fn online_path_gives_back_smactane() {
        let mut id = OnlineIdentifier::new(OnlineConfig::default());
        let next = simulate(&mut id, LoadCase::Uniaxial, 3.0, 0);
        // Equibiaxial points go to their own case; the uniaxial path is kept.
        let n = id.point_counts();
        simulate(&mut id, LoadCase::Equibiaxial, 2.0, next);
        assert_eq!(id.point_counts(), [n[0], 40, 0]);
        let fits = id.refit().expect("enough points");
        let ldr = fits
            .iter()
            .find(|f| matches!(f.model, Model::LambertDianiRey { .. }))
            .unwrap();
        let truth = [-1.27, -2.52e-2, 1.40e-3, -1.02, -3.92e-3, -5.30e-4];
        for (p, t) in ldr.params.iter().zip(truth) {
            assert!((p - t).abs() < 1e-4 * t.abs().max(1.0), "{:?}", ldr.params);
        }
        assert_eq!(
            fits[0].model.name(),
            ldr.model.name(),
            "exact model ranks first"
        );
    }

    /// A deterministic noise in [−1, 1] (hash of `k`).
    fn noise(k: u64) -> f64 {
        let mut x = k.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
        x ^= x >> 31;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 29;
        (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// Feeds a proportional path ln λy = ρ ln λx up to λx = `max_stretch` (`steps` states),
    /// with a strain noise of ±`strain_noise` and a force noise of ±`force_noise` (relative);
    /// returns the next sample id.
    fn general_path(
        id: &mut OnlineIdentifier,
        ratio: f64,
        max_stretch: f64,
        steps: u64,
        first_sample: u64,
        (strain_noise, force_noise): (f64, f64),
    ) -> u64 {
        let law = InvariantLaw::smactane();
        for k in 1..=steps {
            let sample_id = first_sample + k;
            let ex = max_stretch.ln() * k as f64 / steps as f64;
            let (l1, l2) = (ex.exp(), (ratio * ex).exp());
            let s = law.in_plane_stress(l1, l2);
            let (section_x_mm2, section_y_mm2) =
                (20.0 * l2 * 2.0 * s.stretch3, 20.0 * l1 * 2.0 * s.stretch3);
            let rig = RigSample {
                sample_id,
                t_ns: sample_id * 10_000_000,
                force_x_n: s.cauchy_stress_mpa[0]
                    * section_x_mm2
                    * (1.0 + force_noise * noise(4 * sample_id)),
                force_y_n: s.cauchy_stress_mpa[1]
                    * section_y_mm2
                    * (1.0 + force_noise * noise(4 * sample_id + 1)),
                section_x_mm2,
                section_y_mm2,
            };
            id.push_rig(rig);
            id.push_field(FieldSample {
                frame_id: sample_id,
                rig_sample_id: sample_id,
                t_capture_ns: sample_id * 1000,
                log_strain_xx: l1.ln() + strain_noise * noise(4 * sample_id + 2),
                log_strain_yy: l2.ln() + strain_noise * noise(4 * sample_id + 3),
            });
        }
        first_sample + steps
    }

    /// Largest |P_fit − P_true| / P_true over both directions of the proportional paths
    /// `ratios` for λx in [1.05, `max_stretch`].
    fn worst_relative_error(fit: &Fit, ratios: &[f64], max_stretch: f64) -> f64 {
        let law = InvariantLaw::smactane();
        let mut worst: f64 = 0.0;
        for &ratio in ratios {
            for k in 0..=50 {
                let l1 = 1.05 + (max_stretch - 1.05) * k as f64 / 50.0;
                let l2 = (ratio * l1.ln()).exp();
                let truth = law.in_plane_stress(l1, l2).nominal_stress_mpa;
                let sigma = fit
                    .model
                    .in_plane_cauchy_stress_mpa(&fit.params, l1, l2)
                    .expect("in the model's domain");
                for (fitted, truth) in [(sigma[0] / l1, truth[0]), (sigma[1] / l2, truth[1])] {
                    worst = worst.max((fitted - truth).abs() / truth.abs());
                }
            }
        }
        worst
    }

    #[test]
    fn general_biaxial_paths_give_the_true_law_within_two_percent() {
        // Noise: ±2e-4 on the gauge log strains (a good DIC gauge), ±0.5 % on the forces.
        let noisy = (2e-4, 5e-3);
        for ratios in [&[0.5][..], &[1.0], &[0.5, 1.0]] {
            let mut id = OnlineIdentifier::new(OnlineConfig::default());
            let mut next = 0;
            for &ratio in ratios {
                next = general_path(&mut id, ratio, 1.8, 80, next, noisy);
            }
            assert_eq!(id.path_count(), ratios.len(), "{ratios:?}");
            let kept = id.states().len();
            assert!(kept >= 70 * ratios.len(), "{ratios:?}: {kept} states kept");
            // ρ = 0.5 is no canonical case: every state of it is a general one.
            let general = id.general_count();
            let half = ratios.iter().filter(|&&r| r == 0.5).count();
            assert!(general >= 70 * half && general <= 80 * half, "{general}");
            let fits = id.refit().expect("enough states");
            let ldr = fits
                .iter()
                .find(|f| matches!(f.model, Model::LambertDianiRey { .. }))
                .expect("the exp-poly law fits");
            let worst = worst_relative_error(ldr, ratios, 1.8);
            eprintln!("paths {ratios:?}: {kept} states, worst |ΔP|/P = {worst:.4}");
            assert!(
                worst < 0.02,
                "paths {ratios:?}: worst relative error {worst}"
            );
            // Both directions are fitted: the general group has 2 points a state.
            assert_eq!(ldr.cases.len(), 1);
            assert_eq!(ldr.cases[0].points, 2 * kept);
        }
    }

    #[test]
    fn unloading_and_reloading_below_the_maximum_are_skipped_per_path() {
        let mut id = OnlineIdentifier::new(OnlineConfig::default());
        let next = general_path(&mut id, 0.5, 1.5, 20, 0, (0.0, 0.0));
        assert_eq!(id.states().len(), 20);
        // Reloading the same path up to the same maximum adds nothing...
        let next = general_path(&mut id, 0.5, 1.5, 20, next, (0.0, 0.0));
        assert_eq!(id.states().len(), 20);
        assert_eq!(id.counters.skipped, 20);
        // ...another direction is another path, from its start.
        general_path(&mut id, 1.0, 1.3, 10, next, (0.0, 0.0));
        assert_eq!((id.states().len(), id.path_count()), (30, 2));
        assert_eq!(id.point_counts(), [0, 10, 0]);
        assert_eq!(id.general_count(), 20);
        // A restored state obeys the same rule.
        let last = *id.states().last().unwrap();
        assert!(!id.restore(last), "not beyond its path's maximum");
    }

    #[test]
    fn old_rig_samples_drop_fields_and_queue_is_bounded() {
        let config = OnlineConfig {
            rig_history: 4,
            pending_fields: 2,
            ..OnlineConfig::default()
        };
        let mut id = OnlineIdentifier::new(config);
        for s in 10..20 {
            id.push_rig(RigSample {
                sample_id: s,
                t_ns: s,
                force_x_n: 1.0,
                force_y_n: 0.0,
                section_x_mm2: 1.0,
                section_y_mm2: 1.0,
            });
        }
        let field = FieldSample {
            frame_id: 1,
            rig_sample_id: 3,
            t_capture_ns: 0,
            log_strain_xx: 0.1,
            log_strain_yy: -0.05,
        };
        assert_eq!(id.push_field(field), FieldOutcome::Dropped);
        for s in 100..105 {
            assert_eq!(
                id.push_field(FieldSample {
                    rig_sample_id: s,
                    ..field
                }),
                FieldOutcome::Pending
            );
        }
        assert_eq!(id.counters.dropped, 1 + 3);
    }

    #[test]
    fn fields_without_a_rig_sample_are_paired_by_time_with_interpolated_forces() {
        let mut id = OnlineIdentifier::new(OnlineConfig::default());
        let law = InvariantLaw::smactane();
        // A machine log: a uniaxial strip of initial section 40 mm², a sample every 10 ms.
        let a0 = 40.0;
        let stretch_at = |t_ns: u64| 1.0 + 1e-9 * t_ns as f64;
        let nominal_at = |t_ns: u64| {
            let l = stretch_at(t_ns);
            law.in_plane_stress(l, l.powf(-0.5)).nominal_stress_mpa[0]
        };
        let field = |t_ns: u64| {
            let l = stretch_at(t_ns);
            FieldSample {
                frame_id: t_ns,
                rig_sample_id: PAIR_BY_TIME,
                t_capture_ns: t_ns,
                log_strain_xx: l.ln(),
                log_strain_yy: -0.5 * l.ln(),
            }
        };
        let sample = |k: u64| RigSample {
            sample_id: k,
            t_ns: k * 10_000_000,
            force_x_n: nominal_at(k * 10_000_000) * a0,
            force_y_n: 0.0,
            section_x_mm2: a0,
            section_y_mm2: 50.0,
        };
        for k in 0..=10 {
            id.push_rig(sample(k));
        }
        // Between two samples: the force interpolated, the section A0 / λ.
        let t = 55_000_000;
        match id.push_field(field(t)) {
            FieldOutcome::Accepted { case, state } => {
                assert_eq!(case, Some(LoadCase::Uniaxial));
                assert!((state.stretch1 - stretch_at(t)).abs() < 1e-12);
                let nominal_stress_mpa = state.nominal_stress1_mpa;
                let expected = 0.5 * (nominal_at(50_000_000) + nominal_at(60_000_000));
                assert!(
                    (nominal_stress_mpa - expected).abs() < 1e-12,
                    "{nominal_stress_mpa} {expected}"
                );
            }
            other => panic!("{other:?}"),
        }
        // After the newest sample: waits for the next, then is resolved by it.
        let t = 105_000_000;
        assert_eq!(id.push_field(field(t)), FieldOutcome::Pending);
        let resolved = id.push_rig(sample(11));
        assert!(
            matches!(resolved[..], [(_, FieldOutcome::Accepted { .. })]),
            "{resolved:?}"
        );
        // Before the oldest kept sample: dropped.
        let mut small = OnlineIdentifier::new(OnlineConfig {
            rig_history: 2,
            ..OnlineConfig::default()
        });
        for k in 0..5 {
            small.push_rig(sample(k));
        }
        assert_eq!(small.push_field(field(5_000_000)), FieldOutcome::Dropped);
        assert_eq!(small.counters.dropped, 1);
    }
}
