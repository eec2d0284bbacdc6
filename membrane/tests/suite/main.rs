//! The membrane crate's integration tests, one module per subject, in one binary: a binary per
//! file compiled and linked the crate's dependencies once each, and ran one after another
//! (`cargo test -p membrane --test suite -- MODULE::` runs one subject).

#[path = "../common/mod.rs"]
mod common;

mod catalogue;
mod condensed;
mod cruciform;
mod homogeneous;
mod refusals;
mod strip;
mod tangent;
