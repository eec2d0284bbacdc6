//! The subcommands of `dicstream`, one module each.

pub mod identify;
pub mod identifier;
pub mod rig;
pub mod synth;
