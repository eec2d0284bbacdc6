//! The subcommands of `dicstream`, one module each.

pub mod bench;
pub mod bench_pipeline;
pub mod cameras;
pub mod correlate;
pub mod correlator;
pub mod gauge_report;
pub mod identifier;
pub mod identify;
pub mod identify_femu;
pub mod identify_fields;
pub mod link;
pub mod log_rows;
pub mod monitor;
pub mod named_arg;
pub mod producer;
pub mod producer_genicam;
pub mod producer_watch;
pub mod rig;
pub mod rig_follow_csv;
pub mod run;
pub mod settings_file;
pub mod sim_args;
pub mod specimen;
pub mod synth;
pub mod tap;
