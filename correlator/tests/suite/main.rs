//! The correlator crate's integration tests, one module per subject, in one binary: a binary per
//! file compiled and linked the crate's dependencies once each, and ran one after another
//! (`cargo test -p correlator --test suite -- MODULE::` runs one subject).

#[path = "../common/mod.rs"]
mod common;

mod bad_input;
mod dic_challenge;
mod gradient_correction;
mod icgn;
mod independent_images;
mod large_motion;
mod large_strain;
mod prediction_jump;
mod renewal;
mod restore;
mod rotation;
mod steep_band;
mod structure;
mod table1;
mod translation;
