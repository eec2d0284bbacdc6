//! The shared contract between dicstream processes: shared-memory layouts (`#[repr(C)]`,
//! `ZeroCopySend`, an explicit `#[type_name]` carrying the layout version), service names and
//! sizes, node creation under an instance prefix, the `/dev/shm` space check, and the thin
//! publish/subscribe wrappers every process uses. One place per concept: no other crate defines
//! a type that crosses a process boundary.
//!
//! Feature `ipc` (default): iceoryx2 and everything built on it (`instance`, `pubsub`,
//! `shm`, `signals::waitset`, the layouts' `ZeroCopySend` derives). Without it the crate is
//! the pure contract (layouts with their compile-time size and offset checks, codes, service
//! specs, files, signals' flag): what the algorithm crates use with their `process` feature off.
//!
//! Units are in every field name. Coordinates follow DESIGN.md: x = pixel column, y = pixel row,
//! origin at the centre of the top-left pixel; u, v are Lagrangian displacements in pixels.

pub mod clock;
pub mod colour_map;
pub mod colour_range;
pub mod column_units;
pub mod delimited;
pub mod descriptors;
pub mod exit;
pub mod field;
pub mod files;
pub mod frame;
pub mod identification;
#[cfg(feature = "ipc")]
pub mod instance;
mod layout_check;
pub mod layouts;
pub mod linked;
pub mod names;
pub mod owner;
pub mod plain;
#[cfg(feature = "ipc")]
pub mod pubsub;
#[cfg(feature = "ipc")]
pub mod resources;
pub mod rig;
pub mod scale;
pub mod seconds;
pub mod services;
#[cfg(feature = "ipc")]
pub mod shm;
pub mod signals;
pub mod specimen;
pub mod stats;
pub mod text;
pub mod toml_hint;
pub mod units;

pub use clock::monotonic_ns;
pub use field::{FieldHeader, FieldNode, GaugeStrain, GradientSource, NodeStatus, StrainMeasure};
pub use frame::{FrameHeader, GroundTruth, NO_SPECIMEN_SOLVE};
pub use identification::IdentificationReport;
#[cfg(feature = "ipc")]
pub use instance::{Instance, InstanceError};
pub use rig::{ActuatorState, RigCommand, RigCommandKind, RigControl, RigReply, RigState};
pub use specimen::{SpecimenError, SpecimenHeader, SpecimenParts};

/// Version of every layout in this crate. Bump it (and the `#[type_name]` suffixes, which
/// embed it) whenever a field changes: processes of different versions then refuse to connect
/// instead of misreading each other.
pub const LAYOUT_VERSION: u32 = 6;

/// Marks an absent rig sample id (a frame not taken under a rig, e.g. a replayed image).
pub const NO_RIG_SAMPLE: u64 = u64::MAX;
