//! PIDF controller: proportional, integral with anti-windup, derivative on the measurement
//! through a first-order filter (the "F"), and a velocity feed-forward of the set-point.
//! Output limits are those of the servo-valve command, [−1, 1] by default.

/// Gains of one loop. Units: output per unit of the controlled quantity (mm or kN).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PidfGains {
    pub kp: f64,
    /// Integral gain, per second.
    pub ki_per_s: f64,
    /// Derivative gain, seconds.
    pub kd_s: f64,
    /// Cut-off of the derivative filter.
    pub derivative_filter_hz: f64,
    /// Feed-forward of the set-point rate (output per unit/s).
    pub feedforward_s: f64,
    pub output_min: f64,
    pub output_max: f64,
}

impl PidfGains {
    pub fn is_valid(&self) -> bool {
        let finite = [
            self.kp,
            self.ki_per_s,
            self.kd_s,
            self.derivative_filter_hz,
            self.feedforward_s,
            self.output_min,
            self.output_max,
        ]
        .iter()
        .all(|v| v.is_finite());
        finite
            && self.kp >= 0.0
            && self.ki_per_s >= 0.0
            && self.kd_s >= 0.0
            && self.derivative_filter_hz > 0.0
            && self.output_min < self.output_max
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pidf {
    pub gains: PidfGains,
    integral: f64,
    derivative: f64,
    last_measurement: f64,
    last_setpoint: f64,
    output: f64,
}

impl Pidf {
    pub fn new(gains: PidfGains) -> Pidf {
        assert!(gains.is_valid(), "invalid PIDF gains {gains:?}");
        Pidf {
            gains,
            integral: 0.0,
            derivative: 0.0,
            last_measurement: 0.0,
            last_setpoint: 0.0,
            output: 0.0,
        }
    }

    pub fn output(&self) -> f64 {
        self.output
    }

    /// Bumpless transfer: with the set-point set to the measurement, the next output equals
    /// `output` (the integrator carries it, the derivative filter restarts from rest).
    pub fn reset_bumpless(&mut self, measurement: f64, output: f64) {
        let output = output.clamp(self.gains.output_min, self.gains.output_max);
        self.integral = output;
        self.derivative = 0.0;
        self.last_measurement = measurement;
        self.last_setpoint = measurement;
        self.output = output;
    }

    pub fn update(&mut self, setpoint: f64, measurement: f64, dt_s: f64) -> f64 {
        debug_assert!(dt_s > 0.0);
        let g = &self.gains;
        let error = setpoint - measurement;
        let tau_s = 1.0 / (std::f64::consts::TAU * g.derivative_filter_hz);
        let alpha = dt_s / (dt_s + tau_s);
        let raw_rate = -(measurement - self.last_measurement) / dt_s;
        self.derivative += alpha * (raw_rate - self.derivative);
        let setpoint_rate = (setpoint - self.last_setpoint) / dt_s;
        self.last_measurement = measurement;
        self.last_setpoint = setpoint;

        let candidate = self.integral + g.ki_per_s * error * dt_s;
        let fixed = g.kp * error + g.kd_s * self.derivative + g.feedforward_s * setpoint_rate;
        let unsaturated = fixed + candidate;
        // Anti-windup (conditional integration): integrate unless it drives the output
        // further into the limit it already sits on.
        let winding_up = (unsaturated > g.output_max && error > 0.0)
            || (unsaturated < g.output_min && error < 0.0);
        if !winding_up {
            self.integral = candidate.clamp(g.output_min, g.output_max);
        }
        self.output = (fixed + self.integral).clamp(g.output_min, g.output_max);
        self.output
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gains() -> PidfGains {
        PidfGains {
            kp: 1.0,
            ki_per_s: 10.0,
            kd_s: 0.0,
            derivative_filter_hz: 100.0,
            feedforward_s: 0.0,
            output_min: -1.0,
            output_max: 1.0,
        }
    }

    #[test]
    fn integrator_does_not_wind_up_in_saturation() {
        let mut pid = Pidf::new(gains());
        for _ in 0..10_000 {
            assert_eq!(pid.update(100.0, 0.0, 1e-3), 1.0);
        }
        // The error reverses: the output leaves the limit at once.
        let out = pid.update(-0.5, 0.0, 1e-3);
        assert!(out < 1.0, "{out}");
    }

    #[test]
    fn bumpless_reset_keeps_the_output() {
        let mut pid = Pidf::new(gains());
        pid.reset_bumpless(3.0, 0.25);
        let out = pid.update(3.0, 3.0, 1e-3);
        assert!((out - 0.25).abs() < 1e-12);
    }
}
