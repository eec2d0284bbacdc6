//! The identifier crate's integration tests, one module per subject, in one binary: a binary per
//! file compiled and linked the crate's dependencies once each, and ran one after another
//! (`cargo test -p identifier --test suite -- MODULE::` runs one subject).

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/cruciform.rs"]
mod cruciform;

mod bad_input;
mod fast_path;
mod femu_structure;
mod field_resolution;
mod plot;
mod round_trip;
mod state_contributions;
mod treloar;
mod vfm_discrimination;
mod vfm_structure;
