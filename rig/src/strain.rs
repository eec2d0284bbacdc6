//! Strain control: the live correlator as the rig's strain channel (issue 16). The outer loop
//! takes the gauge-zone log strains of the newest `fields` sample, with its frame's capture
//! time; the inner loop stays the servo-hydraulic displacement loop of each pair in centroid
//! mode. Pure logic on [`crate::Rig`], no IPC: the process shell feeds it measurements.
//!
//! - [`path`]: strain programs (ramps of ln λx, ln λy at a rate, holds, constant-ratio paths,
//!   sequences) as targets in time.
//! - [`outer`]: the control law: a delay-aligned model of the grips-to-gauge map, identified
//!   on-line, inverted as a feed-forward.
//! - [`interlock`]: what makes a measurement unusable (stale, too few nodes, a jump, NaN).
//! - [`control`]: [`StrainControl`], which drives the rig's elongation set-points, holds in
//!   displacement on an interlock and reports why, and hands back bumplessly.
//! - [`test`]: a strain-controlled test as configured (kind, stretch, ratio, rate, interlocks).
//! - [`run`]: [`StrainRun`], such a test from mounting through waiting for a field and the
//!   program to unloading, as the process runs it.
//! - [`field_clock`]: a field's capture time on the rig's clock (by its rig sample).

pub mod control;
pub mod field_clock;
pub mod interlock;
pub mod outer;
pub mod path;
pub mod run;
pub mod settle;
pub mod test;

pub use control::{StrainControl, StrainEvent, StrainMode};
pub use field_clock::FieldClock;
pub use interlock::{HoldReason, InterlockLimits};
pub use outer::{GaugeMeasurement, OuterLoop, OuterLoopConfig};
pub use path::{StrainPath, StrainSegment};
pub use run::{ControlColumns, StrainRun, StrainRunEvent};
pub use settle::{ProgramEnd, ShortBecause};
pub use test::{StrainKind, StrainTest, TestControl};
