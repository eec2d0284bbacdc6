//! The rig crate's integration tests, one module per subject, in one binary: a binary per
//! file compiled and linked the crate's dependencies once each, and ran one after another
//! (`cargo test -p rig --test suite -- MODULE::` runs one subject).

mod campaign;
mod determinism;
mod equibiaxial;
mod interlocks;
mod step_response;
mod strain_control;
mod structure;
