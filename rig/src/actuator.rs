//! The plant of one servo-hydraulic actuator: servo-valve (second order), orifice flow with
//! saturation, oil-column compressibility (load-pressure model of a symmetric cylinder),
//! moving mass with viscous friction, end-of-stroke cushions and rigid stops.
//!
//! State equations (Merritt, *Hydraulic Control Systems*, ch. 5), integrated with semi-implicit
//! Euler at the plant sub-step:
//! - valve spool x_v ∈ [−1, 1]: ẍ_v = ω_v² (u − x_v) − 2 ζ_v ω_v ẋ_v
//! - load flow: Q = Q_r x_v √((p_s − sgn(x_v) p_L) / Δp_r) (orifice, zero past p_s)
//! - load pressure: (V_t / 4β) ṗ_L = Q − A v − C_l p_L
//! - mass: m v̇ = A p_L − b v − F_ext − F_cushion
//!
//! Sign convention: positive position extends the actuator away from the specimen centre;
//! the specimen tension `F_ext` pulls it back (positive = tension).

use crate::params::ActuatorParams;

/// Dynamic state of one actuator (SI inside).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Actuator {
    params: ActuatorParams,
    spool: f64,
    spool_rate_per_s: f64,
    load_pressure_pa: f64,
    position_m: f64,
    velocity_m_s: f64,
    /// Spool null bias (fraction of full opening): manufacturing offset, seeded per actuator.
    spool_bias: f64,
}

impl Actuator {
    pub fn new(params: ActuatorParams, position_mm: f64, spool_bias: f64) -> Actuator {
        assert!(position_mm.abs() <= params.half_stroke_mm());
        assert!(
            spool_bias.abs() < 0.1,
            "spool bias {spool_bias} is not a small offset"
        );
        Actuator {
            params,
            spool: 0.0,
            spool_rate_per_s: 0.0,
            load_pressure_pa: 0.0,
            position_m: position_mm * 1.0e-3,
            velocity_m_s: 0.0,
            spool_bias,
        }
    }

    pub fn params(&self) -> &ActuatorParams {
        &self.params
    }

    pub fn position_mm(&self) -> f64 {
        self.position_m * 1.0e3
    }

    pub fn velocity_mm_s(&self) -> f64 {
        self.velocity_m_s * 1.0e3
    }

    pub fn spool(&self) -> f64 {
        self.spool
    }

    /// Force the oil applies to the piston (A p_L), kN.
    pub fn hydraulic_force_kn(&self) -> f64 {
        self.params.piston_area_m2 * self.load_pressure_pa * 1.0e-3
    }

    /// Flow the valve would draw from the supply now (m³/s, ≥ 0), before supply sharing.
    pub fn supply_demand_m3_s(&self, supply_on: bool) -> f64 {
        self.load_flow_m3_s(supply_on).abs()
    }

    fn load_flow_m3_s(&self, supply_on: bool) -> f64 {
        if !supply_on {
            return 0.0;
        }
        let p = &self.params;
        let drop_pa = (p.supply_pressure_pa - self.spool.signum() * self.load_pressure_pa).max(0.0);
        p.valve_rated_flow_m3_s * self.spool * (drop_pa / p.valve_rated_drop_pa).sqrt()
    }

    /// One plant sub-step of `dt_s`. `valve_command` is the (already delayed) servo-valve
    /// command in [−1, 1]; `flow_scale` ∈ [0, 1] is the share of the supply this actuator gets;
    /// `external_force_n` is the specimen tension on the grip.
    pub fn substep(
        &mut self,
        dt_s: f64,
        valve_command: f64,
        flow_scale: f64,
        supply_on: bool,
        external_force_n: f64,
    ) {
        debug_assert!(valve_command.is_finite() && valve_command.abs() <= 1.0);
        debug_assert!((0.0..=1.0).contains(&flow_scale));
        let p = self.params;

        // Servo-valve, second order with spool end stops.
        let omega = p.valve_natural_hz * std::f64::consts::TAU;
        let input = if supply_on {
            valve_command + self.spool_bias
        } else {
            0.0
        };
        let accel = omega * omega * (input - self.spool)
            - 2.0 * p.valve_damping * omega * self.spool_rate_per_s;
        self.spool_rate_per_s += dt_s * accel;
        self.spool += dt_s * self.spool_rate_per_s;
        if self.spool.abs() > 1.0 {
            self.spool = self.spool.clamp(-1.0, 1.0);
            self.spool_rate_per_s = 0.0;
        }

        // Oil column.
        let flow = self.load_flow_m3_s(supply_on) * flow_scale;
        let capacity = p.total_volume_m3() / (4.0 * p.bulk_modulus_pa);
        let net_flow =
            flow - p.piston_area_m2 * self.velocity_m_s - p.leakage_m3_s_pa * self.load_pressure_pa;
        self.load_pressure_pa += dt_s * net_flow / capacity;
        self.load_pressure_pa = self
            .load_pressure_pa
            .clamp(-p.supply_pressure_pa, p.supply_pressure_pa);

        // Moving mass.
        let force_n = p.piston_area_m2 * self.load_pressure_pa
            - p.viscous_damping_n_s_m * self.velocity_m_s
            - external_force_n
            - self.cushion_force_n();
        self.velocity_m_s += dt_s * force_n / p.moving_mass_kg;
        self.position_m += dt_s * self.velocity_m_s;

        // Rigid stop at the end of the stroke.
        let end_m = p.half_stroke_mm() * 1.0e-3;
        if self.position_m.abs() > end_m {
            self.position_m = self.position_m.clamp(-end_m, end_m);
            self.velocity_m_s = 0.0;
        }
    }

    /// Cushion force (N, along +position): spring on the penetration into the last
    /// `cushion_length_mm`, damper only while moving into the end.
    fn cushion_force_n(&self) -> f64 {
        let p = &self.params;
        let start_m = (p.half_stroke_mm() - p.cushion_length_mm) * 1.0e-3;
        let x = self.position_m;
        let v = self.velocity_m_s;
        if x > start_m {
            let damping = if v > 0.0 {
                p.cushion_damping_n_s_m * v
            } else {
                0.0
            };
            p.cushion_stiffness_n_m * (x - start_m) + damping
        } else if x < -start_m {
            let damping = if v < 0.0 {
                p.cushion_damping_n_s_m * v
            } else {
                0.0
            };
            p.cushion_stiffness_n_m * (x + start_m) + damping
        } else {
            0.0
        }
    }

    /// Whether any state is NaN or infinite (the invalid-signal detector reads this).
    pub fn is_finite(&self) -> bool {
        self.spool.is_finite()
            && self.load_pressure_pa.is_finite()
            && self.position_m.is_finite()
            && self.velocity_m_s.is_finite()
    }
}
