//! The six actuators and the shared hydraulic power station (330 l/min).
//!
//! When the valves together ask for more than the station delivers, every actuator gets the
//! same fraction of its demand (the supply pressure sags for all): a first-order picture of a
//! shared pressure line, enough to make simultaneous fast moves slower than single ones.

use crate::actuator::Actuator;
use crate::params::SUPPLY_FLOW_M3_S;

pub const ACTUATOR_COUNT: usize = 6;

#[derive(Clone, Debug)]
pub struct Hydraulics {
    pub actuators: [Actuator; ACTUATOR_COUNT],
    pub supply_flow_m3_s: f64,
    /// Fraction of the demand served on the last sub-step (1 = not saturated).
    pub last_flow_scale: f64,
}

impl Hydraulics {
    pub fn new(actuators: [Actuator; ACTUATOR_COUNT]) -> Hydraulics {
        Hydraulics {
            actuators,
            supply_flow_m3_s: SUPPLY_FLOW_M3_S,
            last_flow_scale: 1.0,
        }
    }

    /// Advance all actuators by `substeps` sub-steps of `dt_s / substeps`, with constant valve
    /// commands and external forces over the step.
    pub fn step(
        &mut self,
        dt_s: f64,
        substeps: u32,
        valve_commands: &[f64; ACTUATOR_COUNT],
        supply_on: bool,
        external_forces_n: &[f64; ACTUATOR_COUNT],
    ) {
        assert!((1..=64).contains(&substeps));
        let h = dt_s / f64::from(substeps);
        for _ in 0..substeps {
            let demand: f64 = self
                .actuators
                .iter()
                .map(|a| a.supply_demand_m3_s(supply_on))
                .sum();
            let scale = if demand > self.supply_flow_m3_s {
                self.supply_flow_m3_s / demand
            } else {
                1.0
            };
            self.last_flow_scale = scale;
            for (i, actuator) in self.actuators.iter_mut().enumerate() {
                actuator.substep(h, valve_commands[i], scale, supply_on, external_forces_n[i]);
            }
        }
    }
}
