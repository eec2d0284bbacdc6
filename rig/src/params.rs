//! Physical parameters of one servo-hydraulic actuator, with their sources.
//!
//! Units: the plant integrates in SI (m, Pa, kg, s, m³); every interface of the crate speaks mm
//! and kN. Each field carries its unit in its name.
//!
//! Sources and justification:
//! - Rated force and stroke: paper section 2 (ASTREE, LMT-Cachan / Schenck): horizontal X±, Y±
//!   100 kN, vertical Z± 250 kN, 250 mm stroke each; shared power station 330 l/min.
//! - Supply pressure 28 MPa (280 bar): the usual rating pressure of Schenck / MTS
//!   servo-hydraulic actuators. Piston area = rated force / supply pressure.
//! - Effective bulk modulus 1.4 GPa: mineral oil (≈1.6-1.8 GPa) softened by hoses and entrained
//!   air; 1.0-1.5 GPa is the textbook range (Merritt, *Hydraulic Control Systems*, 1967, ch. 2).
//! - Dead volume per chamber: manifold, servo-valve ports and hoses, taken as ≈11 % of the swept
//!   volume of one chamber at mid stroke.
//! - Moving mass: piston, rod, load cell, hydraulic bearing slide and grip. The values give
//!   an oil-column natural frequency of ≈144 Hz at mid stroke (the lowest along the stroke),
//!   inside the 100-170 Hz the issue asks for.
//! - Servo-valve: two-stage valve, rated flow at 7 MPa valve drop (the catalogue convention,
//!   e.g. Moog D634 / D792 families): 63 l/min horizontal, 160 l/min vertical; dynamics of
//!   second order ≈100 Hz, damping 0.7 (catalogue −90° frequency of such valves).
//! - Damping: viscous friction of seals and hydrostatic bearings plus a small cross-port leakage
//!   (valve null leakage), chosen for a hydraulic damping ratio of ≈0.1, typical of an actuator
//!   without pressure feedback.
//! - End-of-stroke cushions: the last 5 mm of each end, a stiff spring-damper (hydraulic
//!   cushion), and a rigid stop at the end of the stroke.

/// Parameters of one actuator plant. `Copy` so a `RigConfig` can hold six by value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActuatorParams {
    pub rated_force_kn: f64,
    /// Full stroke; the actuator moves in [−stroke/2, +stroke/2] about its mid position.
    pub stroke_mm: f64,
    pub supply_pressure_pa: f64,
    pub piston_area_m2: f64,
    pub moving_mass_kg: f64,
    pub bulk_modulus_pa: f64,
    pub dead_volume_per_chamber_m3: f64,
    pub valve_rated_flow_m3_s: f64,
    pub valve_rated_drop_pa: f64,
    pub valve_natural_hz: f64,
    pub valve_damping: f64,
    pub viscous_damping_n_s_m: f64,
    pub leakage_m3_s_pa: f64,
    pub cushion_length_mm: f64,
    pub cushion_stiffness_n_m: f64,
    pub cushion_damping_n_s_m: f64,
}

const SUPPLY_PRESSURE_PA: f64 = 28.0e6;
const LITRE_PER_MIN_M3_S: f64 = 1.0e-3 / 60.0;

/// Shared hydraulic power station flow (paper section 2).
pub const SUPPLY_FLOW_M3_S: f64 = 330.0 * LITRE_PER_MIN_M3_S;

impl ActuatorParams {
    /// X+, X−, Y+, Y−: 100 kN, 250 mm.
    pub fn horizontal() -> ActuatorParams {
        let piston_area_m2 = 100.0e3 / SUPPLY_PRESSURE_PA;
        ActuatorParams {
            rated_force_kn: 100.0,
            stroke_mm: 250.0,
            supply_pressure_pa: SUPPLY_PRESSURE_PA,
            piston_area_m2,
            moving_mass_kg: 80.0,
            bulk_modulus_pa: 1.4e9,
            dead_volume_per_chamber_m3: 0.11 * piston_area_m2 * 0.125,
            valve_rated_flow_m3_s: 63.0 * LITRE_PER_MIN_M3_S,
            valve_rated_drop_pa: 7.0e6,
            valve_natural_hz: 100.0,
            valve_damping: 0.7,
            viscous_damping_n_s_m: 9.0e3,
            leakage_m3_s_pa: 4.0e-12,
            cushion_length_mm: 5.0,
            cushion_stiffness_n_m: 2.0e7,
            cushion_damping_n_s_m: 4.0e4,
        }
    }

    /// Z+, Z−: 250 kN, 250 mm.
    pub fn vertical() -> ActuatorParams {
        let piston_area_m2 = 250.0e3 / SUPPLY_PRESSURE_PA;
        ActuatorParams {
            rated_force_kn: 250.0,
            stroke_mm: 250.0,
            supply_pressure_pa: SUPPLY_PRESSURE_PA,
            piston_area_m2,
            moving_mass_kg: 200.0,
            bulk_modulus_pa: 1.4e9,
            dead_volume_per_chamber_m3: 0.11 * piston_area_m2 * 0.125,
            valve_rated_flow_m3_s: 160.0 * LITRE_PER_MIN_M3_S,
            valve_rated_drop_pa: 7.0e6,
            valve_natural_hz: 100.0,
            valve_damping: 0.7,
            viscous_damping_n_s_m: 22.0e3,
            leakage_m3_s_pa: 10.0e-12,
            cushion_length_mm: 5.0,
            cushion_stiffness_n_m: 5.0e7,
            cushion_damping_n_s_m: 1.0e5,
        }
    }

    /// Total oil volume of both chambers at mid stroke.
    pub fn total_volume_m3(&self) -> f64 {
        self.piston_area_m2 * self.stroke_mm * 1.0e-3 + 2.0 * self.dead_volume_per_chamber_m3
    }

    /// Oil-column stiffness at mid stroke, 4 β A² / V_t (Merritt eq. 3-103 for a symmetric
    /// cylinder); the lowest along the stroke, so the worst case for the position loop.
    pub fn oil_stiffness_n_m(&self) -> f64 {
        4.0 * self.bulk_modulus_pa * self.piston_area_m2 * self.piston_area_m2
            / self.total_volume_m3()
    }

    pub fn hydraulic_natural_hz(&self) -> f64 {
        (self.oil_stiffness_n_m() / self.moving_mass_kg).sqrt() / std::f64::consts::TAU
    }

    /// Damping ratio of the oil-column mode from viscous friction and leakage.
    pub fn hydraulic_damping(&self) -> f64 {
        let k = self.oil_stiffness_n_m();
        let m = self.moving_mass_kg;
        let friction = self.viscous_damping_n_s_m / (2.0 * (k * m).sqrt());
        let leakage = self.leakage_m3_s_pa / self.piston_area_m2
            * (self.bulk_modulus_pa * m / self.total_volume_m3()).sqrt();
        friction + leakage
    }

    /// No-load speed at full valve opening (valve drop = supply pressure).
    pub fn max_speed_mm_s(&self) -> f64 {
        let flow = self.valve_rated_flow_m3_s
            * (self.supply_pressure_pa / self.valve_rated_drop_pa).sqrt();
        flow / self.piston_area_m2 * 1.0e3
    }

    /// Half stroke, the position bound of the actuator.
    pub fn half_stroke_mm(&self) -> f64 {
        0.5 * self.stroke_mm
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_frequency_in_the_issue_band() {
        for params in [ActuatorParams::horizontal(), ActuatorParams::vertical()] {
            let hz = params.hydraulic_natural_hz();
            assert!((100.0..=170.0).contains(&hz), "{hz} Hz");
            let zeta = params.hydraulic_damping();
            assert!((0.05..=0.2).contains(&zeta), "damping {zeta}");
            let speed = params.max_speed_mm_s();
            assert!((300.0..=1000.0).contains(&speed), "{speed} mm/s");
        }
    }
}
