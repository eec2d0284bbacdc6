//! The live bench as a user meets it: `dicstream run` starts rig, camera, correlator and
//! identifier as separate processes on one instance, watches every service, shows a status
//! line, restarts a process that dies (if asked), stops everything in order, and keeps the
//! results of the run in a folder of its own.
//!
//! Pure parts (configuration, `frames.csv` rows, ground-truth errors, latency histograms,
//! acceptance, results files) are separate from the shells that talk to processes
//! ([`children`]) and to shared memory ([`subscriptions`]); [`run`] ties them together.

pub mod acceptance;
pub mod camera_events;
pub mod children;
pub mod config;
pub mod dashboard_view;
pub mod field_acceptance;
pub mod field_route_figure;
pub mod field_scale;
pub mod figures;
pub mod frames;
pub mod gauge_columns;
pub mod gauge_history;
pub mod latency;
pub mod leftovers;
pub mod liveness;
pub mod mechanics_figures;
pub mod monitor_gauges;
pub mod origin_frames;
pub mod pipeline;
pub mod recorder;
pub mod results;
pub mod run;
pub mod status;
pub mod subscriptions;
pub mod truth;
pub mod units_file;
pub mod vtk_series;

pub use config::RunConfig;
pub use run::{run, Ending, RunOptions, RunReport};
