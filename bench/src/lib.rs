//! Shared helpers for the dicstream benchmarks.

#![forbid(unsafe_code)]
