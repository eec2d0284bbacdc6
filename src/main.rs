//! `dicstream`: one binary, one subcommand per process and per tool a user runs by hand.
//! Each subcommand lives in its own file under `src/cmd/`; this file only dispatches.

mod cmd;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "dicstream", version, about = "Live digital image correlation bench", long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    // One variant per subcommand; keep one line each so parallel edits stay simple.
    /// Speed benchmarks a user can reproduce (`bench correlate`).
    Bench(cmd::bench::BenchArgs),
    /// Offline correlation of image files: fields (CSV, VTK, PNG) and summary.json.
    Correlate(cmd::correlate::CorrelateArgs),
    /// Live correlation process: frames in, fields out (zero-copy); resumes from --state-dir.
    Correlator(cmd::correlator::CorrelatorArgs),
    /// Fit hyperelastic potentials to uniaxial/equibiaxial/pure-shear CSV data (offline).
    Identify(cmd::identify::IdentifyArgs),
    /// Live identification process: fields + rig/state in, identification reports out.
    Identifier(cmd::identifier::IdentifierArgs),
    /// Camera process: publishes frames (scenario, replay, or following the rig state).
    Producer(cmd::producer::ProducerArgs),
    /// Simulated ASTREE machine: publishes rig/state, answers rig/command, logs rig.csv.
    Rig(cmd::rig::RigArgs),
    /// The whole simulated bench: rig, camera, correlator, identifier; live status; results.
    Run(cmd::run::RunArgs),
    /// Write simulated speckle images with their exact ground truth (truth.csv).
    Synth(cmd::synth::SynthArgs),
    /// Watch a service (frames, fields, rig/state, identification): rate, drops, latency.
    Tap(cmd::tap::TapArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result: anyhow::Result<()> = match cli.command {
        // One arm per subcommand.
        Command::Bench(args) => cmd::bench::run(args),
        Command::Correlate(args) => cmd::correlate::run(args),
        Command::Correlator(args) => cmd::correlator::run(args),
        Command::Identify(args) => cmd::identify::run(args),
        Command::Identifier(args) => cmd::identifier::run(args),
        Command::Producer(args) => cmd::producer::run(args),
        Command::Rig(args) => cmd::rig::run(args),
        Command::Run(args) => cmd::run::run(args),
        Command::Synth(args) => cmd::synth::run(args),
        Command::Tap(args) => cmd::tap::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("dicstream: error: {error:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
