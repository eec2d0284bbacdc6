//! Simulated ASTREE multiaxial servo-hydraulic machine (paper section 2): six actuators on a
//! shared power station, PIDF control with centroid mode, programs, limits and a hyperelastic
//! specimen. A deterministic library stepped in simulated time; the process shell is separate.

#![forbid(unsafe_code)]

pub mod actuator;
pub mod bad_setting;
pub mod builtin;
pub mod campaign;
pub mod codes;
pub mod config;
pub mod control;
pub mod csv_follow;
pub mod hydraulics;
pub mod ids;
pub mod journal;
pub mod limits;
pub mod log;
pub mod log_check;
pub mod params;
pub mod pidf;
#[cfg(feature = "process")]
pub mod process;
pub mod program;
pub mod refusal;
pub mod rig;
pub mod session;
pub mod settings;
pub mod snapshot;
pub mod specimen;
pub mod strain;

pub use campaign::{Campaign, CampaignEvent, CampaignTest};
pub use config::RigConfig;
pub use control::{AxisControl, ControlGains, ControlMode};
pub use ids::{ActuatorId, Axis, Channel};
pub use limits::{ChannelLimits, LimitAction, LimitActions, LimitKind};
pub use program::{Program, StopTransition};
pub use refusal::Refusal;
pub use rig::{Rig, RigCommand};
pub use snapshot::{ProgramStatus, RigSnapshot, SpecimenKinematics};
pub use specimen::{
    Loading, Misalignment, SolveSchedule, SpecimenConfig, SpecimenModel, SpecimenSettings,
};
