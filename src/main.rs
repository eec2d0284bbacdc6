//! `dicstream`: one binary, one subcommand per process and per tool a user runs by hand.
//! Each subcommand lives in its own file under `src/cmd/`; this file only dispatches.

// The unsafe items, each allowed where it stands: the load-time signal installer below
// (`link_section`) and, with the `genicam` feature, the view of the camera driver's buffer
// (`genicam/device.rs`, `Frame::bytes`).
#![deny(unsafe_code)]

mod cmd;
#[cfg(feature = "genicam")]
mod genicam;
#[cfg(feature = "link")]
mod link_zenoh;

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
    /// The GenICam cameras found (GigE Vision, USB3 Vision); needs the `genicam` feature.
    Cameras(cmd::cameras::CamerasArgs),
    /// Offline correlation of image files: fields (CSV, VTK, PNG) and summary.json.
    Correlate(cmd::correlate::CorrelateArgs),
    /// Live correlation process: frames in, fields out (zero-copy); resumes from --state-dir.
    Correlator(cmd::correlator::CorrelatorArgs),
    /// Fit hyperelastic potentials to uniaxial/equibiaxial/pure-shear CSV data (offline).
    Identify(cmd::identify::IdentifyArgs),
    /// Live identification process: fields + rig/state in, identification reports out.
    Identifier(cmd::identifier::IdentifierArgs),
    /// Carry chosen services between this host's instance and another host's over Zenoh.
    Link(cmd::link::LinkArgs),
    /// Live dashboard in the browser, attached read-only to a running instance.
    Monitor(cmd::monitor::MonitorArgs),
    /// Camera process: publishes frames (scenario, replay, or following the rig state).
    Producer(Box<cmd::producer::ProducerArgs>),
    /// Simulated ASTREE machine: publishes rig/state, answers rig/command, logs rig.csv.
    Rig(Box<cmd::rig::RigArgs>),
    /// The whole simulated bench: rig, camera, correlator, identifier; live status; results.
    Run(cmd::run::RunArgs),
    /// Solve the specimen as a finite-element structure for a path of grip stretches (offline).
    Specimen(cmd::specimen::SpecimenArgs),
    /// Write simulated speckle images with their exact ground truth (truth.csv).
    Synth(cmd::synth::SynthArgs),
    /// Watch a service (frames, fields, rig/state, identification): rate, drops, latency.
    Tap(cmd::tap::TapArgs),
}

/// The termination signals are handled from the moment the program is loaded, before the
/// Rust runtime and `main` (a signal in the first millisecond is then a request to stop).
#[used]
#[allow(unsafe_code)]
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
        Command::Cameras(args) => ok(cmd::cameras::run(args)),
        Command::Correlate(args) => ok(cmd::correlate::run(args)),
        Command::Correlator(args) => ok(cmd::correlator::run(args)),
        Command::Identify(args) => ok(cmd::identify::run(args)),
        Command::Identifier(args) => ok(cmd::identifier::run(args)),
        Command::Link(args) => ok(cmd::link::run(args)),
        Command::Monitor(args) => ok(cmd::monitor::run(args)),
        Command::Producer(args) => ok(cmd::producer::run(*args)),
        Command::Rig(args) => ok(cmd::rig::run(*args)),
        Command::Run(args) => cmd::run::run(args),
        Command::Specimen(args) => ok(cmd::specimen::run(args)),
        Command::Synth(args) => ok(cmd::synth::run(args)),
        Command::Tap(args) => ok(cmd::tap::run(args)),
    };
    match result {
        Ok(code) => code,
        Err(error) => {
            eprintln!("dicstream: error: {error:#}");
            std::process::ExitCode::from(exit_code_of(&error))
        }
    }
}

/// The exit code of a failed subcommand: one with a meaning for `dicstream run` that some
/// error of the chain asks for (a results file that could not be written, a rig that could not
/// resume; `wire::exit::code_of`), else 1.
fn exit_code_of(error: &anyhow::Error) -> u8 {
    error.chain().find_map(wire::exit::code_of).unwrap_or(1)
}

#[cfg(test)]
mod tests {
    use super::exit_code_of;
    use anyhow::Context;
    use wire::exit::{ExitWith, CANNOT_RESUME, OUTPUT_FAILED};

    fn full_disk(path: &str) -> wire::files::FileError {
        wire::files::FileError {
            path: path.into(),
            what: "write",
            reason: std::io::Error::from_raw_os_error(libc::ENOSPC),
        }
    }

    #[test]
    fn a_file_error_keeps_its_code_through_contexts_and_is_said_once() {
        let error: anyhow::Result<()> = Err(full_disk("frames.csv")).context("recorder");
        let error = error.context("run").unwrap_err();
        assert_eq!(exit_code_of(&error), OUTPUT_FAILED);
        let message = format!("{error:#}");
        assert!(
            message.starts_with("run: recorder: cannot write frames.csv: "),
            "{message}"
        );
        assert_eq!(message.matches("No space left").count(), 1, "{message}");
    }

    #[test]
    fn a_process_error_keeps_the_code_of_its_cause() {
        // As the process commands say it: flattened, with the code of the cause.
        let log = rig::process::ProcessError::File(full_disk("rig.csv"));
        let error = anyhow::Error::from(wire::exit::in_context("rig process", &log));
        assert_eq!(exit_code_of(&error), OUTPUT_FAILED);
        assert!(
            format!("{error:#}").starts_with("rig process: cannot write rig.csv: "),
            "{error:#}"
        );
        // Through anyhow's own chain too (the cause is the variant's source).
        let error = anyhow::Error::new(rig::process::ProcessError::File(full_disk("rig.csv")))
            .context("rig process");
        assert_eq!(exit_code_of(&error), OUTPUT_FAILED);
        let journal = rig::process::ProcessError::CannotResume(ExitWith {
            code: CANNOT_RESUME,
            message: "cannot resume from rig.journal".into(),
        });
        let error = anyhow::Error::new(journal).context("rig process");
        assert_eq!(exit_code_of(&error), CANNOT_RESUME);
        // A state file of the correlator, through its transparent wrappers.
        let state = correlator::state::StateError::Write(full_disk("reference.state"));
        let error = anyhow::Error::new(correlator::process::ProcessError::State(state));
        assert_eq!(exit_code_of(&error), OUTPUT_FAILED);
        let error = anyhow::Error::new(identifier::process::ProcessError::File(full_disk(
            "identification.json",
        )));
        assert_eq!(exit_code_of(&error), OUTPUT_FAILED);
    }

    /// `dicstream run` starts each child with `--settings FILE` (`live::run::child_launch`):
    /// its command accepts the flag and reads the file as its own settings, for every source
    /// of camera and rig.
    #[test]
    fn every_child_of_a_run_reads_the_settings_the_run_writes() {
        use crate::cmd::settings_file::read;
        use clap::Parser;
        let dir = std::env::temp_dir().join(format!("child_settings_{}", std::process::id()));
        let results = live::results::ResultsDir { root: dir.clone() };
        let mut configs = vec![live::RunConfig::default()];
        for (camera, rig) in [
            ("watch", "csv-follow"),
            ("replay", "simulated"),
            ("genicam", "simulated"),
        ] {
            let mut config = live::RunConfig::default();
            config.camera.source = camera.parse().unwrap();
            config.camera.replay_files = "/lab/*.tif".into();
            config.rig.source = rig.parse().unwrap();
            config.rig.csv.time_column = "Time".into();
            config.rig.csv.force_x_column = "Fx".into();
            config.link = Some(link::LinkSection {
                start_with_run: true,
                ..link::LinkSection::default()
            });
            configs.push(config);
        }
        for config in &configs {
            // A run starts the link only when `[link]` asks (the default configuration has none).
            let roles = live::children::Role::ALL
                .into_iter()
                .filter(|&role| role != live::children::Role::Link || config.link_started_by_run());
            for role in roles {
                let launch = live::run::child_launch(role, config, "bench_7", &results, 5)
                    .unwrap_or_else(|e| panic!("{role:?}: {e:#}"));
                let args = launch.into_args().unwrap();
                let line = ["dicstream", role.name()]
                    .into_iter()
                    .map(String::from)
                    .chain(args.clone());
                if let Err(e) = super::Cli::try_parse_from(line) {
                    panic!("{role:?}: {e}");
                }
                let file = std::path::Path::new(&args[1]);
                let read = match role {
                    live::children::Role::Rig => {
                        read::<rig::process::RigProcessSettings>(file).map(|_| ())
                    }
                    live::children::Role::Producer => {
                        read::<producer::settings::ProducerSettings>(file).map(|_| ())
                    }
                    live::children::Role::Correlator => {
                        read::<correlator::process::ProcessConfig>(file).map(|_| ())
                    }
                    live::children::Role::Identifier => {
                        read::<identifier::process::ProcessConfig>(file).map(|_| ())
                    }
                    live::children::Role::Link => read::<link::LinkSettings>(file).map(|_| ()),
                };
                read.unwrap_or_else(|e| panic!("{role:?}: {e:#}"));
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_error_without_a_code_exits_with_1() {
        assert_eq!(exit_code_of(&anyhow::anyhow!("no")), 1);
        let error = anyhow::Error::new(ExitWith {
            code: 1,
            message: "the run could not start".into(),
        });
        assert_eq!(exit_code_of(&error.context("run")), 1);
    }
}
