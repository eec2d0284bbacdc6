//! `dicstream run`: the whole simulated bench (rig, camera, correlator, identifier as
//! processes), live status, results folder. See the `live` crate.

use anyhow::Context;
use live::config::DashboardListen;
use live::{Ending, RunConfig, RunOptions};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Configuration file (TOML); missing keys take their defaults (see --print-config).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Print the default configuration as a commented TOML file and exit.
    #[arg(long)]
    pub print_config: bool,
    /// Results folder of this run [default: <results_dir>/<date-time>/].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Instance name (shared-memory prefix) [default: run_<pid>].
    #[arg(long)]
    pub instance: Option<String>,
    /// Also write the kept fields as legacy VTK for ParaView (the configuration's `vtk`).
    #[arg(long)]
    pub vtk: bool,
    /// No status line (start and end only).
    #[arg(long)]
    pub quiet: bool,
    /// The long status line (every figure) instead of one that fits 100 columns.
    #[arg(long)]
    pub verbose: bool,
    /// Serve the live dashboard at ADDR:PORT [default: the configuration's `dashboard`,
    /// 127.0.0.1:8421]; a non-loopback address serves other machines too, with a warning.
    #[arg(long, conflicts_with = "no_dashboard")]
    pub dashboard: Option<DashboardListen>,
    /// No live dashboard.
    #[arg(long)]
    pub no_dashboard: bool,
}

pub fn run(args: RunArgs) -> anyhow::Result<std::process::ExitCode> {
    if args.print_config {
        print!("{}", RunConfig::commented_defaults());
        return Ok(std::process::ExitCode::SUCCESS);
    }
    let mut config = RunConfig::read(args.config.as_deref())?;
    config.run.vtk |= args.vtk;
    if let Some(address) = args.dashboard {
        config.run.dashboard = address;
    }
    if args.no_dashboard {
        config.run.dashboard = DashboardListen::Off;
    }
    config.validate().context("configuration refused")?;
    refuse_a_link_not_built(&config)?;
    let exe = std::env::current_exe().context("cannot find the dicstream binary")?;
    let report = live::run(RunOptions {
        config,
        exe,
        instance: args.instance,
        results: args.out,
        status: !args.quiet,
        verbose: args.verbose,
    })
    // `run` has exit codes of its own (see live::run::exit_code): one that cannot start
    // fails with 1, whatever the cause in the error's chain (a file it could not write).
    .map_err(|e| wire::exit::ExitWith {
        code: live::run::exit_code::FAILED,
        message: format!("{e:#}"),
    })?;
    println!(
        "run: {:?} after {:.1} s: {} frames captured, {} correlated, {} not correlated ({} lost \
         to faults); latency capture to field p50 {:.0} ms p99 {:.0} ms, to identification p50 \
         {:.0} ms",
        report.ending,
        report.wall_s,
        report.frames_captured,
        report.fields,
        report.frames_not_correlated,
        report.frames_lost_to_faults,
        report.latency_field_ms.p50,
        report.latency_field_ms.p99,
        report.latency_identification_ms.p50,
    );
    if let Some(error) = report.displacement_error_mean_px {
        match &report.truth {
            Some(t) => println!(
                "run: mean displacement error against the ground truth ({}) {error:.4} px, node p99 {:.4} px{}{}",
                t.compared_with,
                t.node_error_p99_px.unwrap_or(f64::NAN),
                by_load_case(&t.node_error_by_load_case),
                match t.fields_without_truth {
                    0 => String::new(),
                    n => format!(" ({n} field(s) without truth: their solves not received)"),
                }
            ),
            None => println!("run: mean displacement error against the ground truth {error:.4} px"),
        }
    }
    // On a structure the law from the whole field decides; the gauge's is said, not judged.
    let gauge = match report.field_acceptance_decides {
        true => "gauge route (force / section, no stress on a structure: not the verdict): ",
        false => "",
    };
    match &report.acceptance {
        Some(a) => println!(
            "run: identified a = {:?}, b = {:?}\nrun: {gauge}{}",
            a.a,
            a.b,
            a.verdict_line()
        ),
        None => println!("run: nothing identified by the gauge route"),
    }
    if let Some(field) = &report.field_acceptance {
        println!("run: {}", field.verdict_line());
    }
    if let Some(strain) = &report.strain_target {
        println!("run: {}", strain.line());
    }
    if let Some(link) = &report.link {
        println!("run: {}", link.line());
    }
    println!("run: results in {}", report.results.display());
    if report.leftover_shm_files > 0 {
        eprintln!(
            "run: warning: the processes of instance {} left {} shared-memory file(s) (named \
             above, removed)",
            report.instance, report.leftover_shm_files
        );
    }
    let failure = report.failure.as_deref().unwrap_or("unknown");
    match report.ending {
        Ending::Completed if report.exit_code == live::run::exit_code::PASSED => {}
        Ending::Completed => eprintln!("run: completed, but the results are doubtful: {failure}"),
        Ending::Interrupted => eprintln!("run: {failure}"),
        Ending::Failed => eprintln!("run: failed: {failure}"),
    }
    if report.exit_code != live::run::exit_code::PASSED {
        eprintln!(
            "run: exit code {} (see `ending` and `failure` in {})",
            report.exit_code,
            report.results.join("summary.json").display()
        );
    }
    Ok(std::process::ExitCode::from(report.exit_code))
}

/// A `[link]` that asks the run to start it, in a binary built without the `link` feature:
/// refused before anything starts (exit 78, a configuration this binary cannot run).
fn refuse_a_link_not_built(config: &RunConfig) -> anyhow::Result<()> {
    if config.link_started_by_run() && !cfg!(feature = "link") {
        return Err(wire::exit::ExitWith {
            code: wire::exit::CONFIG,
            message: format!(
                "configuration refused: [link] start_with_run = true, but {}",
                super::link::NO_LINK
            ),
        }
        .into());
    }
    Ok(())
}

/// " (by test, p99: uniaxial 0.0812 px, equibiaxial 0.1143 px)" when more than one load case was
/// compared, else nothing.
fn by_load_case(cases: &[live::run::NodeErrorReport]) -> String {
    if cases.len() < 2 {
        return String::new();
    }
    let parts: Vec<String> = cases
        .iter()
        .map(|c| {
            format!(
                "{} {:.4} px",
                c.load_case,
                c.node_error_p99_px.unwrap_or(f64::NAN)
            )
        })
        .collect();
    format!(" (by test, p99: {})", parts.join(", "))
}
