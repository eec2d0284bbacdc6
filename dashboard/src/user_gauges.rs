//! The user's named gauges (virtual extensometers and strain gauges) as a dashboard that
//! reads them itself computes them: their shapes are a run's configuration, not on the wire,
//! so the code that places and reads them is its owner's (`live::monitor_gauges`, with the
//! correlator's gauge code and the run's own history), handed to [`crate::Dashboard::start`]
//! and called by the feeder on every field it receives. `dicstream run` reads them in its
//! recorder instead and hands the result over (`Dashboard::set_user_gauges`).

use serde_json::Value;
use wire::{FieldHeader, FieldNode};

/// When a field was taken, on the dashboard's chart clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldTime {
    /// The test's time (s), or without a rig the time since the dashboard started.
    pub t_s: f64,
    /// The clock changed with this field (the first rig sample): the histories restart.
    pub restarted: bool,
}

/// What reads the user's gauges on every field the dashboard receives.
pub trait UserGauges: Send {
    /// One field (its nodes in place) at `time`.
    fn on_field(&mut self, header: &FieldHeader, nodes: &[FieldNode], time: FieldTime);
    /// The gauges as the page draws them, one chart per gauge: each gauge's name, kind,
    /// quantity, unit, times and series (`Dashboard::set_user_gauges`'s form).
    fn to_json(&self) -> Value;
}
