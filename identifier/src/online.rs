//! On-line identification, pure logic (no IPC): pair measured strains with rig forces by rig
//! sample id, classify each state into a load case, accumulate the loading path, refit.
//!
//! Inputs are plain structs so the logic is tested without shared memory; the process shell
//! (`process` module) converts wire samples into them.
//!
//! Pairing: a field names the rig sample its frame was taken at. Rig samples are kept in a
//! bounded ring ([`OnlineConfig::rig_history`]); a field whose sample has not arrived yet waits
//! in a bounded queue ([`OnlineConfig::pending_fields`]) and is dropped (counted) when the queue
//! is full or its sample has left the ring.
//!
//! A field whose frame names no rig sample ([`PAIR_BY_TIME`]: a real camera, a watched folder,
//! beside a followed machine log) is paired by time: its capture instant against the samples'
//! instants ([`RigSample::t_ns`], one monotonic clock), forces interpolated between the two
//! samples around it; it waits until a sample at or after it has come. Such samples come
//! from a machine's log, which knows no specimen model: their sections are the initial ones
//! A0, and the current section normal to an axis is A0 / λ of that axis (incompressible).
//!
//! Classification by the ratio ρ = ln λ2 / ln λ1 (λ1 the larger in-plane stretch):
//! uniaxial −1/2, pure shear 0, equibiaxial 1, within [`OnlineConfig::classify_tolerance`].
//! Only the loading branch is kept: a point is accepted when its stretch exceeds the last
//! accepted one of its case by [`OnlineConfig::min_stretch_increment`].

use crate::data::{Curve, LoadCase};
use crate::fit::{fit_model, Fit, FitOptions};
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
#[derive(Clone, Debug)]
pub struct OnlineConfig {
    pub rig_history: usize,
    pub pending_fields: usize,
    pub classify_tolerance: f64,
    pub min_stretch_increment: f64,
    /// Points per case kept at most (later points are refused, counted).
    pub max_points_per_case: usize,
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
            min_stretch_increment: 2e-3,
            max_points_per_case: 2000,
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
    /// Paired and accepted as a new point of `case`.
    Accepted {
        case: LoadCase,
        stretch: f64,
        nominal_stress_mpa: f64,
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
    Unclassified,
    NotIncreasing,
    CaseFull,
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
    /// (stretch, nominal stress MPa) per case, in [`LoadCase::ALL`] order.
    points: [Vec<(f64, f64)>; 3],
    pub counters: OnlineCounters,
    /// The last field accepted (frame id, capture time ns).
    pub last_accepted: Option<(u64, u64)>,
    /// Per configured model, its last fitted parameters (the next refit's start).
    warm: Vec<Option<Vec<f64>>>,
    refits: u64,
    /// Load cases in the last refit (a new case calls for a full search).
    fitted_cases: usize,
}

/// A full multi-start search every this many refits (the others start from the last fit).
pub const FULL_SEARCH_EVERY: u64 = 16;

fn case_index(case: LoadCase) -> usize {
    LoadCase::ALL
        .iter()
        .position(|c| *c == case)
        .expect("case in ALL")
}

impl OnlineIdentifier {
    pub fn new(config: OnlineConfig) -> Self {
        assert!(
            config.rig_history > 0 && config.pending_fields > 0,
            "buffers must be non-empty"
        );
        OnlineIdentifier {
            rig: VecDeque::with_capacity(config.rig_history),
            pending: VecDeque::with_capacity(config.pending_fields),
            points: [Vec::new(), Vec::new(), Vec::new()],
            counters: OnlineCounters::default(),
            last_accepted: None,
            warm: vec![None; config.models.len()],
            refits: 0,
            fitted_cases: 0,
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
                if self.pending.len() == self.config.pending_fields {
                    self.pending.pop_front();
                    self.counters.dropped += 1;
                }
                self.pending.push_back(field);
                return FieldOutcome::Pending;
            }
            (None, None) => {
                if self.pending.len() == self.config.pending_fields {
                    self.pending.pop_front();
                    self.counters.dropped += 1;
                }
                self.pending.push_back(field);
                return FieldOutcome::Pending;
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
        // Loaded direction 1: the larger stretch.
        let (l1, l2, force_n, section_mm2) = if sx >= sy {
            (sx, sy, rig.force_x_n, rig.section_x_mm2)
        } else {
            (sy, sx, rig.force_y_n, rig.section_y_mm2)
        };
        if l1 <= 1.0 + 1e-6 {
            return FieldOutcome::Skipped(SkipReason::NotStretched);
        }
        if !(section_mm2 > 0.0 && section_mm2.is_finite() && force_n.is_finite()) {
            return FieldOutcome::Skipped(SkipReason::BadSection);
        }
        let rho = l2.ln() / l1.ln();
        let tol = self.config.classify_tolerance;
        let case = if (rho + 0.5).abs() < tol {
            LoadCase::Uniaxial
        } else if rho.abs() < tol {
            LoadCase::PureShear
        } else if (rho - 1.0).abs() < tol {
            LoadCase::Equibiaxial
        } else {
            return FieldOutcome::Skipped(SkipReason::Unclassified);
        };
        let (stretch, cauchy_mpa) = match case {
            // Equibiaxial: mean of both directions.
            LoadCase::Equibiaxial => {
                let sig_x = rig.force_x_n / rig.section_x_mm2;
                let sig_y = rig.force_y_n / rig.section_y_mm2;
                if !(rig.section_y_mm2 > 0.0 && sig_y.is_finite()) {
                    return FieldOutcome::Skipped(SkipReason::BadSection);
                }
                (0.5 * (sx + sy), 0.5 * (sig_x + sig_y))
            }
            _ => (l1, force_n / section_mm2),
        };
        let nominal_stress_mpa = cauchy_mpa / stretch;
        let points = &mut self.points[case_index(case)];
        if points.len() >= self.config.max_points_per_case {
            return FieldOutcome::Skipped(SkipReason::CaseFull);
        }
        if let Some(&(last, _)) = points.last() {
            if stretch < last + self.config.min_stretch_increment {
                return FieldOutcome::Skipped(SkipReason::NotIncreasing);
            }
        }
        points.push((stretch, nominal_stress_mpa));
        self.last_accepted = Some((field.frame_id, field.t_capture_ns));
        FieldOutcome::Accepted {
            case,
            stretch,
            nominal_stress_mpa,
        }
    }

    /// Puts back a point accepted by an earlier run (from its journal), with the same
    /// loading-branch rule as live points; returns whether it was kept.
    pub fn restore(&mut self, case: LoadCase, stretch: f64, nominal_stress_mpa: f64) -> bool {
        let points = &mut self.points[case_index(case)];
        let increasing = points
            .last()
            .is_none_or(|&(last, _)| stretch >= last + self.config.min_stretch_increment);
        let ok = stretch > 1.0
            && nominal_stress_mpa.is_finite()
            && increasing
            && points.len() < self.config.max_points_per_case;
        if ok {
            points.push((stretch, nominal_stress_mpa));
        }
        ok
    }

    /// Points accepted per case, in [`LoadCase::ALL`] order.
    pub fn point_counts(&self) -> [usize; 3] {
        [
            self.points[0].len(),
            self.points[1].len(),
            self.points[2].len(),
        ]
    }

    /// The accumulated load path as curves (cases with at least 2 points).
    pub fn curves(&self) -> Vec<Curve> {
        LoadCase::ALL
            .iter()
            .zip(&self.points)
            .filter(|(_, p)| p.len() >= crate::data::MIN_POINTS_PER_CURVE)
            .filter_map(|(&case, p)| {
                Curve::new(
                    case,
                    p.iter().map(|q| q.0).collect(),
                    p.iter().map(|q| q.1).collect(),
                )
                .ok()
            })
            .collect()
    }

    /// Refits the configured models on the path so far; `None` before enough points. Each
    /// model starts from its last solution (a few Levenberg-Marquardt steps after a few more
    /// points); every [`FULL_SEARCH_EVERY`]th refit, when a case appears, or when the warm
    /// start fails, the full multi-start search runs instead.
    pub fn refit(&mut self) -> Option<Vec<Fit>> {
        let total: usize = self.point_counts().iter().sum();
        if total < self.config.min_points_to_fit {
            return None;
        }
        let curves = self.curves();
        let cases = curves.len();
        let full = self.refits.is_multiple_of(FULL_SEARCH_EVERY) || cases != self.fitted_cases;
        self.refits += 1;
        self.fitted_cases = cases;
        let mut fits = Vec::with_capacity(self.config.models.len());
        for (k, model) in self.config.models.iter().enumerate() {
            let options = FitOptions {
                warm_start: if full { None } else { self.warm[k].clone() },
                ..FitOptions::default()
            };
            match fit_model(model, &curves, &options) {
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
                    FieldOutcome::Accepted {
                        case: c,
                        nominal_stress_mpa,
                        ..
                    } => {
                        assert_eq!(c, case);
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
            FieldOutcome::Accepted {
                case,
                stretch,
                nominal_stress_mpa,
            } => {
                assert_eq!(case, LoadCase::Uniaxial);
                assert!((stretch - stretch_at(t)).abs() < 1e-12);
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
