//! The subcommands of `dicstream`, one module each.

pub mod identify;
pub mod identifier;
