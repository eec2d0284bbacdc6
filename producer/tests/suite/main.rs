//! The producer crate's integration tests, one module per subject, in one binary: a binary per
//! file compiled and linked the crate's dependencies once each, and ran one after another
//! (`cargo test -p producer --test suite -- MODULE::` runs one subject).

mod camera;
mod fast_vs_exact;
mod image_out;
mod replay;
mod truth;
