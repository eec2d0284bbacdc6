//! The subcommands of `dicstream`, one module each.
