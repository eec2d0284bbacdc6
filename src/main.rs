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
    /// Live dashboard in the browser, attached read-only to a running instance.
    Monitor(cmd::monitor::MonitorArgs),
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

/// The termination signals are handled from the moment the program is loaded, before the
/// Rust runtime and `main` (a signal in the first millisecond is then a request to stop).
#[used]
#[link_section = ".init_array"]
static INSTALL_SIGNAL_HANDLERS_AT_LOAD: extern "C" fn() = {
    extern "C" fn install() {
        // `main` installs them again and reports an error.
        let _ = wire::signals::install();
    }
    install
};

/// A subcommand that succeeds or fails (exit code 0, or one chosen by its error).
fn ok(result: anyhow::Result<()>) -> anyhow::Result<std::process::ExitCode> {
    result.map(|()| std::process::ExitCode::SUCCESS)
}

fn main() -> std::process::ExitCode {
    // First, so that SIGINT/SIGTERM/SIGHUP in the first milliseconds is a request to stop like
    // any other, never a default-action kill that leaves shared memory behind.
    if let Err(e) = wire::signals::install() {
        eprintln!("dicstream: error: cannot install the signal handlers: {e}");
        return std::process::ExitCode::FAILURE;
    }
    let cli = Cli::parse();
    // `run` chooses its exit code (see live::run::exit_code); the others succeed or fail.
    let result: anyhow::Result<std::process::ExitCode> = match cli.command {
        // One arm per subcommand.
        Command::Bench(args) => ok(cmd::bench::run(args)),
        Command::Correlate(args) => ok(cmd::correlate::run(args)),
        Command::Correlator(args) => ok(cmd::correlator::run(args)),
        Command::Identify(args) => ok(cmd::identify::run(args)),
        Command::Identifier(args) => ok(cmd::identifier::run(args)),
        Command::Monitor(args) => ok(cmd::monitor::run(args)),
        Command::Producer(args) => ok(cmd::producer::run(args)),
        Command::Rig(args) => ok(cmd::rig::run(args)),
        Command::Run(args) => cmd::run::run(args),
        Command::Synth(args) => ok(cmd::synth::run(args)),
        Command::Tap(args) => ok(cmd::tap::run(args)),
    };
    match result {
        Ok(code) => code,
        Err(error) => {
            eprintln!("dicstream: error: {error:#}");
            // A code with a meaning for `dicstream run` (a results file that could not be
            // written, a rig that could not resume), else 1.
            let code = error.chain().find_map(wire::exit::code_of).unwrap_or(1);
            std::process::ExitCode::from(code)
        }
    }
}
