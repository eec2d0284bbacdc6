//! The outer (strain) loop's law: latency compensation by a delay-aligned model.
//!
//! The rig knows its own grips-to-gauge map only approximately: gauge log strain ≈ k̂ × nominal
//! log strain of the axis + ĉ × that of the other axis (k̂ = [`OuterLoopConfig::model_fraction`],
//! ĉ = [`OuterLoopConfig::model_cross`]: the mounted specimen's small-strain map,
//! [`OuterLoopConfig::for_specimen`] — 1 and 0 on the homogeneous sheet, the finite-element
//! structure's from its tangent at rest — against a true map that depends on the stretch and
//! on the grips' give). Per axis the loop keeps an on-line model
//! y_i ≈ g_i k̂_i u_i + ĉ u_j + b_i (u = ln(1 + elongation / gauge length), the nominal log
//! strain the rig measures with its own position sensors) and:
//!
//! - **aligns each measurement with its capture time** (the Smith predictor's idea): a field
//!   captured at t_m is compared with the model evaluated at the nominal strain the rig *had*
//!   at t_m, read back from a short history, so the measurement latency (capture → field →
//!   rig, 50–200 ms) never enters a feedback path: no delay in the loop, nothing to oscillate;
//! - **identifies g and b** from those aligned pairs by normalised least mean squares (one
//!   update per field, gain [`OuterLoopConfig::adaptation_gain`]), g kept in
//!   [`OuterLoopConfig::gain_range`] so a bad model can never run away;
//! - **inverts the model as a feed-forward** at the present target: u = (T − b) / (g k̂), so a
//!   ramp is followed without the lag an integrator would have.
//!
//! The residual error is the model's curvature over one latency of travel, far below the
//! measurement noise at the rates. Pure arithmetic: no IPC, no clock of its own.

use crate::bad_setting::BadSetting;
use std::collections::VecDeque;

/// A field sample as the strain loop uses it: mean gauge log strains, capture time in rig
/// time (s) and how many correlation nodes converged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaugeMeasurement {
    pub t_capture_s: f64,
    pub log_strain: [f64; 2],
    pub valid_nodes: u32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OuterLoopConfig {
    /// The rig's approximate grips-to-gauge model k̂ along x and y.
    pub model_fraction: [f64; 2],
    /// The rig's approximate cross term ĉ (gauge log strain per nominal log strain of the
    /// other axis), fixed; what it misses goes into the offsets.
    pub model_cross: f64,
    /// Fastest elongation change the loop commands (mm/s per pair): a step of the target
    /// becomes a ramp the inner loop follows without overshoot.
    pub max_elongation_rate_mm_s: f64,
    /// NLMS step μ in (0, 1] per measurement.
    pub adaptation_gain: f64,
    /// Scale of the offset regressor (log strain): how fast b moves against g.
    pub offset_scale: f64,
    /// Range of the identified gain g (a multiple of k̂).
    pub gain_range: [f64; 2],
    /// How far back the nominal-strain history reaches (s): the longest latency compensated.
    pub history_s: f64,
}

impl Default for OuterLoopConfig {
    fn default() -> Self {
        OuterLoopConfig {
            model_fraction: [1.0, 1.0],
            model_cross: 0.0,
            max_elongation_rate_mm_s: 25.0,
            adaptation_gain: 0.6,
            offset_scale: 0.005,
            gain_range: [0.5, 2.0],
            history_s: 5.0,
        }
    }
}

impl OuterLoopConfig {
    /// The default loop on the grips-to-gauge map of `specimen` at small strain.
    pub fn for_specimen(specimen: &crate::specimen::Specimen) -> OuterLoopConfig {
        let (model_fraction, model_cross) = specimen.gauge_map();
        OuterLoopConfig {
            model_fraction,
            model_cross,
            ..OuterLoopConfig::default()
        }
    }
}

/// History spacing (s): 1 ms, so 5 s of history is 5000 entries, allocated once.
const HISTORY_SPACING_S: f64 = 1.0e-3;

#[derive(Clone, Debug)]
pub struct OuterLoop {
    config: OuterLoopConfig,
    gauge_mm: [f64; 2],
    gain: [f64; 2],
    offset: [f64; 2],
    /// (rig time s, nominal log strains), oldest first.
    history: VecDeque<(f64, [f64; 2])>,
}

impl OuterLoop {
    /// `gauge_mm`: the lengths the rig divides elongations by (x, y).
    pub fn new(config: OuterLoopConfig, gauge_mm: [f64; 2]) -> OuterLoop {
        let capacity = (config.history_s / HISTORY_SPACING_S).ceil() as usize + 2;
        OuterLoop {
            config,
            gauge_mm,
            gain: [1.0; 2],
            offset: [0.0; 2],
            history: VecDeque::with_capacity(capacity),
        }
    }

    pub fn config(&self) -> &OuterLoopConfig {
        &self.config
    }

    /// Identified (g, b) per axis.
    pub fn model(&self) -> ([f64; 2], [f64; 2]) {
        (self.gain, self.offset)
    }

    pub fn nominal_log_strain(&self, elongation_mm: [f64; 2]) -> [f64; 2] {
        std::array::from_fn(|i| (1.0 + elongation_mm[i] / self.gauge_mm[i]).max(1e-3).ln())
    }

    /// Record the rig's actual elongations at rig time `t_s` (call every control step).
    pub fn record(&mut self, t_s: f64, elongation_mm: [f64; 2]) {
        if let Some(&(last, _)) = self.history.back() {
            if t_s < last + HISTORY_SPACING_S {
                return;
            }
        }
        if self.history.len() == self.history.capacity() {
            self.history.pop_front();
        }
        self.history
            .push_back((t_s, self.nominal_log_strain(elongation_mm)));
        while let Some(&(first, _)) = self.history.front() {
            if first < t_s - self.config.history_s {
                self.history.pop_front();
            } else {
                break;
            }
        }
    }

    /// Nominal log strains at `t_s`, interpolated in the history; None before it or after it.
    pub fn nominal_at(&self, t_s: f64) -> Option<[f64; 2]> {
        let (first, _) = *self.history.front()?;
        let (last, newest) = *self.history.back()?;
        if t_s.is_nan() || t_s < first - 1e-12 {
            return None;
        }
        if t_s >= last {
            return (t_s <= last + 2.0 * HISTORY_SPACING_S).then_some(newest);
        }
        let k = self.history.partition_point(|&(t, _)| t <= t_s);
        let (t0, u0) = self.history[k - 1];
        let (t1, u1) = self.history[k];
        let f = (t_s - t0) / (t1 - t0);
        Some(std::array::from_fn(|i| u0[i] + f * (u1[i] - u0[i])))
    }

    pub fn predict(&self, nominal: [f64; 2]) -> [f64; 2] {
        std::array::from_fn(|i| {
            self.gain[i] * self.config.model_fraction[i] * nominal[i]
                + self.config.model_cross * nominal[1 - i]
                + self.offset[i]
        })
    }

    /// Model prediction minus measurement at the capture time; None if the capture time is
    /// outside the history (too old, or from the future).
    pub fn innovation(&self, m: &GaugeMeasurement) -> Option<[f64; 2]> {
        let u = self.nominal_at(m.t_capture_s)?;
        let p = self.predict(u);
        Some(std::array::from_fn(|i| m.log_strain[i] - p[i]))
    }

    /// Bumpless (re)start: b such that the model gives the measurement at its capture; the
    /// gains learnt so far are kept, and enter b (g k̂ u, as [`OuterLoop::predict`] has it: a
    /// re-anchor after a hold mid-ramp, with g ≠ 1 learnt, must not shift the model by
    /// (g − 1) k̂ u).
    pub fn reset_to(&mut self, m: &GaugeMeasurement) -> bool {
        let Some(u) = self.nominal_at(m.t_capture_s) else {
            return false;
        };
        for i in 0..2 {
            self.offset[i] = m.log_strain[i]
                - self.gain[i] * self.config.model_fraction[i] * u[i]
                - self.config.model_cross * u[1 - i];
        }
        true
    }

    /// One NLMS update from a measurement aligned with its capture time; returns the
    /// innovation, None if it could not be aligned (nothing changed then).
    pub fn update(&mut self, m: &GaugeMeasurement) -> Option<[f64; 2]> {
        let u = self.nominal_at(m.t_capture_s)?;
        let p = self.predict(u);
        let mu = self.config.adaptation_gain;
        let s = self.config.offset_scale;
        let mut innovation = [0.0; 2];
        for i in 0..2 {
            let e = m.log_strain[i] - p[i];
            innovation[i] = e;
            let phi = self.config.model_fraction[i] * u[i];
            let norm = phi * phi + s * s + 1e-12;
            self.gain[i] = (self.gain[i] + mu * e * phi / norm)
                .clamp(self.config.gain_range[0], self.config.gain_range[1]);
            self.offset[i] += mu * e * s * s / norm;
        }
        Some(innovation)
    }

    /// Elongations (mm) the model says give the gauge log strains `target`.
    pub fn elongation_for(&self, target: [f64; 2]) -> [f64; 2] {
        // Solve [[a, c], [c, d]] u = target − b; the diagonal dominates (|c| ≤ 0.3, a, d ≥ 0.1).
        let a = self.gain[0] * self.config.model_fraction[0];
        let d = self.gain[1] * self.config.model_fraction[1];
        let c = self.config.model_cross;
        let r = [target[0] - self.offset[0], target[1] - self.offset[1]];
        let det = a * d - c * c;
        let u = [(d * r[0] - c * r[1]) / det, (a * r[1] - c * r[0]) / det];
        std::array::from_fn(|i| self.gauge_mm[i] * (u[i].clamp(-2.0, 2.5).exp() - 1.0))
    }

    /// Checks the configuration: a model the loop can invert, gains it can use.
    pub fn validate(config: &OuterLoopConfig) -> Result<(), BadSetting> {
        let c = config;
        if !c
            .model_fraction
            .iter()
            .all(|k| k.is_finite() && *k >= 0.05 && *k <= 1.5)
        {
            return Err(BadSetting::new(
                "model_fraction",
                c.model_fraction,
                "values in [0.05, 1.5]",
            ));
        }
        if !(c.model_cross.is_finite()
            && c.model_cross.abs() <= 0.5
            && c.model_cross.abs() < c.model_fraction[0].min(c.model_fraction[1]))
        {
            return Err(BadSetting::new(
                "model_cross",
                c.model_cross,
                "a value in [−0.5, 0.5], smaller than the fractions",
            ));
        }
        if !(c.adaptation_gain > 0.0 && c.adaptation_gain <= 1.0) {
            return Err(BadSetting::new(
                "adaptation_gain",
                c.adaptation_gain,
                "(0, 1]",
            ));
        }
        if !(c.offset_scale.is_finite() && c.offset_scale > 0.0) {
            return Err(BadSetting::new(
                "offset_scale",
                c.offset_scale,
                "a positive number",
            ));
        }
        if !(c.gain_range[0] >= 0.5
            && c.gain_range[0] <= 1.0
            && c.gain_range[1] >= 1.0
            && c.gain_range[1] <= 2.0)
        {
            return Err(BadSetting::new(
                "gain_range",
                c.gain_range,
                "[≥ 0.5, ≤ 2] around 1",
            ));
        }
        if !(c.history_s.is_finite() && c.history_s > 0.0 && c.history_s <= 60.0) {
            return Err(BadSetting::new("history_s", c.history_s, "(0, 60] s"));
        }
        if !(c.max_elongation_rate_mm_s.is_finite() && c.max_elongation_rate_mm_s > 0.0) {
            return Err(BadSetting::new(
                "max_elongation_rate_mm_s",
                c.max_elongation_rate_mm_s,
                "a positive number",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn history_interpolates_and_refuses_outside() {
        let mut o = OuterLoop::new(OuterLoopConfig::default(), [100.0; 2]);
        assert_eq!(o.nominal_at(0.0), None);
        for k in 0..=1000 {
            let t = k as f64 * 2e-4;
            o.record(t, [100.0 * t, 0.0]);
        }
        let u = o.nominal_at(0.1).unwrap();
        assert!((u[0] - (1.1f64).ln()).abs() < 1e-3, "{u:?}");
        assert_eq!(o.nominal_at(-1.0), None);
        assert_eq!(o.nominal_at(1.0), None);
    }

    #[test]
    fn identifies_a_linear_map_and_inverts_it() {
        // True map: y = 0.9 ux − 0.03 uy + 0.01 on x, 0.8 uy − 0.03 ux − 0.005 on y: gains and
        // offsets off the model's (k̂ 0.85, ĉ −0.03), its cross term right.
        let config = OuterLoopConfig {
            model_fraction: [0.85, 0.85],
            model_cross: -0.03,
            ..OuterLoopConfig::default()
        };
        let mut o = OuterLoop::new(config, [100.0; 2]);
        let truth = |u: [f64; 2]| {
            [
                0.9 * u[0] - 0.03 * u[1] + 0.01,
                0.8 * u[1] - 0.03 * u[0] - 0.005,
            ]
        };
        for k in 0..5000 {
            let t = k as f64 * 1e-3;
            let e = 30.0 * (t * 1.3).sin().abs();
            o.record(t, [e, 20.0 * (t * 0.7).sin().abs()]);
            if k == 0 {
                // Anchored on a field of the unloaded state, as `StrainControl::start` is.
                let m = GaugeMeasurement {
                    t_capture_s: t,
                    log_strain: truth(o.nominal_at(t).unwrap()),
                    valid_nodes: 100,
                };
                assert!(o.reset_to(&m));
            }
            if k % 50 == 0 && k > 100 {
                let tc = t - 0.08;
                let y = truth(o.nominal_at(tc).unwrap());
                let m = GaugeMeasurement {
                    t_capture_s: tc,
                    log_strain: y,
                    valid_nodes: 100,
                };
                o.update(&m);
            }
        }
        let e = o.elongation_for([0.2, 0.1]);
        let y = truth(o.nominal_log_strain(e));
        // The unadapted model (g = 1) misses by ≈ 0.01.
        assert!(
            (y[0] - 0.2).abs() < 5e-4 && (y[1] - 0.1).abs() < 5e-4,
            "{y:?}"
        );
    }
}
