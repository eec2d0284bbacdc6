//! The subcommands of `dicstream`, one module each.

pub mod correlate;
pub mod identify;
pub mod identifier;
pub mod rig;
pub mod synth;
