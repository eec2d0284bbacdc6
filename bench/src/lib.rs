//! Shared helpers for the dicstream benchmarks.
