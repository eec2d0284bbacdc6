//! The rig with the finite-element specimen against the wall clock, on one core, as the
//! process runs it (a `Session`: publication periods of 500 Hz, the log at 100 Hz written to a
//! file): simulated time per wall time, the solves (how many, how often, Newton iterations,
//! wall time per solve), and how long a restarted rig takes to replay its journal.
//!
//! Run: `cargo run --release -p rig --example structure_realtime [-- TEST STRETCH RATE]`
//! (default: the paper campaign's equibiaxial test, `equibiaxial 2 0.04`; `uniaxial 3 0.08`
//! for the strip).

use rig::builtin::BuiltinTest;
use rig::session::{Session, SessionError};
use rig::{Loading, ProgramStatus, RigConfig, SpecimenConfig, SpecimenModel, SpecimenSettings};
use std::io::Write;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let test = args
        .first()
        .and_then(|t| BuiltinTest::parse(t))
        .unwrap_or(BuiltinTest::Equibiaxial);
    let number = |i: usize, default: f64| {
        args.get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(default)
    };
    let (stretch, rate) = match test {
        BuiltinTest::Equibiaxial => (number(1, 2.0), number(2, 0.04)),
        BuiltinTest::Uniaxial => (number(1, 3.0), number(2, 0.08)),
    };
    let loading = match test {
        BuiltinTest::Equibiaxial => Loading::Equibiaxial,
        BuiltinTest::Uniaxial => Loading::Uniaxial(rig::Axis::X),
    };
    let specimen = SpecimenConfig::of(
        loading,
        &SpecimenSettings {
            model: SpecimenModel::Structure,
            ..SpecimenSettings::default()
        },
    );
    let program = test.program(&specimen, rate, stretch).expect("program");
    let config = RigConfig {
        specimen: Some(specimen),
        ..RigConfig::default()
    };
    // 500 Hz publication (10 steps of 5 kHz), log every 50 steps (100 Hz): the process's.
    let make = || Session::new(&config, 1, Some(&program), None, 10, 50).expect("session");
    let started = Instant::now();
    let mut session = make();
    let setup_s = started.elapsed().as_secs_f64();
    let log_path =
        std::env::temp_dir().join(format!("structure_realtime_{}.csv", std::process::id()));
    let mut log = std::io::BufWriter::new(std::fs::File::create(&log_path).expect("log file"));
    let mut rows = String::new();
    let mut solve_wall_s = Vec::new();
    let mut period_wall_s = Vec::new();
    let wall = Instant::now();
    let cpu_start_s = cpu_s();
    while !matches!(
        session.rig.state().program,
        ProgramStatus::Finished | ProgramStatus::Stopped
    ) {
        let id = solve_id(&session);
        let t0 = Instant::now();
        rows.clear();
        session.period(Some(&mut rows)).expect("period");
        log.write_all(rows.as_bytes()).expect("log");
        let dt = t0.elapsed().as_secs_f64();
        period_wall_s.push(dt);
        // A period with a solve (at most one per period at these rates): its extra time.
        if solve_id(&session) != id {
            solve_wall_s.push(dt);
        }
    }
    log.flush().expect("log");
    let wall_s = wall.elapsed().as_secs_f64();
    let run_cpu_s = cpu_s() - cpu_start_s;
    let simulated_s = session.rig.state().t_s;
    let structure = session.rig.specimen().unwrap().structure().unwrap();
    let figures = structure.figures();
    let fault = session
        .rig
        .specimen()
        .unwrap()
        .fault()
        .map(|f| f.to_string());
    // The journal replay of a restarted rig: the same periods, at once.
    let journal = session.journal(1, 0, 0, 0);
    let replay = Instant::now();
    let replay_cpu_start_s = cpu_s();
    let mut again = make();
    again
        .resume(&journal, None, |_: &str| Ok::<(), SessionError>(()))
        .expect("replay reaches the journal's state");
    let replay_s = replay.elapsed().as_secs_f64();
    let replay_cpu_s = cpu_s() - replay_cpu_start_s;
    std::fs::remove_file(&log_path).ok();

    let quiet: Vec<f64> = {
        let mut v: Vec<f64> = period_wall_s.clone();
        v.sort_by(f64::total_cmp);
        v
    };
    solve_wall_s.sort_by(f64::total_cmp);
    let median = |v: &[f64]| v.get(v.len() / 2).copied().unwrap_or(f64::NAN);
    let mesh = structure.mesh();
    println!(
        "{} to nominal λ {stretch} at {rate} /s on the structure ({} nodes, {} elements), \
         specimen set up (meshed, solved at rest) in {:.0} ms",
        test.name(),
        mesh.nodes_mm.len(),
        mesh.elements.len(),
        setup_s * 1e3
    );
    println!(
        "simulated {simulated_s:.1} s in {wall_s:.2} s wall: {:.1}x real time on one core, \
         logging 100 Hz ({run_cpu_s:.2} s on the CPU: {:.1}x per CPU second, what a core of \
         its own gives)",
        simulated_s / wall_s,
        simulated_s / run_cpu_s
    );
    println!(
        "solves: {} ({:.1} per simulated s while the program ran), {:.2} Newton iterations per \
         solve (at most {}), {} load increments; wall time of a period with a solve: median \
         {:.1} ms, max {:.1} ms; of a period: median {:.3} ms",
        figures.solves,
        figures.solves as f64 / simulated_s,
        figures.newton_iterations as f64 / figures.solves.max(1) as f64,
        figures.max_iterations_per_solve,
        figures.load_steps,
        median(&solve_wall_s) * 1e3,
        solve_wall_s.last().copied().unwrap_or(f64::NAN) * 1e3,
        median(&quiet) * 1e3
    );
    println!(
        "journal replay of {} periods ({simulated_s:.1} s simulated) by a restarted rig: \
         {replay_s:.2} s wall, {replay_cpu_s:.2} s CPU",
        journal.periods
    );
    if let Some(fault) = fault {
        println!("stopped: {fault}");
    }
}

/// CPU time of this thread (s), from /proc/thread-self/schedstat (Linux: ns on the CPU);
/// NaN where it cannot be read.
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

fn solve_id(session: &Session) -> u64 {
    session
        .rig
        .specimen()
        .and_then(|s| s.structure())
        .map_or(0, |s| s.solved().id)
}
