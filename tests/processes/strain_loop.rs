//! Strain control in the live bench with real processes (issue 16): a strain-controlled
//! equibiaxial run whose correlator hangs mid-ramp (SIGSTOP: no field comes) and is killed once
//! the rig has held (a restart alone is quicker than the stale limit). The rig holds the grips (a `HELD` line
//! naming the stale fields on its stderr, `held` rows in `rig.csv`, the elongations still),
//! the run restarts the correlator from its state folder, and the test resumes (or, with
//! `on_interlock = "stop"`, unloads and ends there). No wall-clock assertion: waits are on
//! result files, bounded by the hang guard.

use crate::common;

use common::bench_run::{child_pid, config, signal, start_run, summary, wait_rows, whole_rows};
use common::Run;
use std::path::Path;

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in rig.csv"))
}

/// (t_s, control, X elongation, Y elongation) of every `rig.csv` row.
fn rig_rows(out: &Path) -> Vec<(f64, String, f64, f64)> {
    let text = std::fs::read_to_string(out.join("rig.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let (t, mode, ex, ey) = (
        column(&header, "t_s"),
        column(&header, "control"),
        column(&header, "X_elongation_mm"),
        column(&header, "Y_elongation_mm"),
    );
    // Whole rows only (the run has ended: every row is whole).
    whole_rows(&out.join("rig.csv")).unwrap();
    lines
        .map(|l| {
            let r: Vec<&str> = l.split(',').collect();
            (
                r[t].parse().unwrap(),
                r[mode].to_string(),
                r[ex].parse().unwrap(),
                r[ey].parse().unwrap(),
            )
        })
        .collect()
}

/// (log_exx, log_eyy, target (ln λx, ln λy) or None) of every `frames.csv` row.
fn frame_targets(out: &Path) -> Vec<(f64, f64, Option<[f64; 2]>)> {
    let text = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let at = |name: &str| {
        header
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name} in frames.csv"))
    };
    let (lx, ly, tx, ty) = (
        at("log_exx"),
        at("log_eyy"),
        at("target_log_exx"),
        at("target_log_eyy"),
    );
    lines
        .map(|l| {
            let r: Vec<&str> = l.split(',').collect();
            let target = match (r[tx], r[ty]) {
                ("", "") => None,
                (x, y) => Some([x.parse().unwrap(), y.parse().unwrap()]),
            };
            (r[lx].parse().unwrap(), r[ly].parse().unwrap(), target)
        })
        .collect()
}

/// Waits (bounded by the hang guard) until the file at `path` contains `text`.
fn wait_for_text(path: &Path, text: &str) {
    let give_up = std::time::Instant::now() + common::HANG_GUARD;
    while !std::fs::read_to_string(path).is_ok_and(|t| t.contains(text)) {
        assert!(
            std::time::Instant::now() < give_up,
            "no {text:?} in {}",
            path.display()
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// The modes of `rig.csv` in order, repeats merged.
fn mode_sequence(rows: &[(f64, String, f64, f64)]) -> Vec<String> {
    let mut modes: Vec<String> = Vec::new();
    for (_, m, _, _) in rows {
        if modes.last() != Some(m) {
            modes.push(m.clone());
        }
    }
    modes
}

fn kill_correlator_mid_ramp(on_interlock: &str) {
    let mut run = Run::new(&format!("strain_loop_{on_interlock}"));
    let config = config(
        &run,
        "stale_after_s = 2.0",
        &format!(
            "[[rig.tests]]\nkind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.3\n\
             rate_per_s = 0.03\nstale_s = 0.5\non_interlock = \"{on_interlock}\"\n"
        ),
    );
    let out = run.dir.join("out");
    let parent = start_run(&mut run, "run", &config, &out, &["--quiet"]);
    // About 4 s of fields at 10 frames/s: past the 1 s hold, on the ramp (≈ λ 1.08).
    wait_rows(&out.join("frames.csv"), 0, 40);
    // The correlator hangs (no field comes), then is killed: the rig must hold within its
    // stale limit, before the run restarts the correlator.
    let pid = child_pid(parent, "correlator").expect("the correlator runs");
    signal(pid, libc::SIGSTOP);
    wait_for_text(&out.join("logs/rig.log"), "strain control HELD");
    signal(pid, libc::SIGKILL);
    let (status, stdout, stderr) = run.child("run").wait();
    let s = summary(&out);
    println!("{on_interlock}: {status:?}, summary {s}");
    assert_eq!(s["ending"], "completed", "{s}\n{stderr}");
    // The acceptance line names what was compared (the equibiaxial curve this test ran) and
    // agrees with summary.json and the exit code.
    if s["acceptance"].is_null() {
        assert!(stdout.contains("run: nothing identified"), "{stdout}");
        assert_eq!(status.code(), Some(2), "{stderr}");
    } else {
        let verdict = stdout
            .lines()
            .find(|l| l.contains(" -> PASSED") || l.contains(" -> NOT PASSED"))
            .unwrap_or_else(|| panic!("no acceptance line:\n{stdout}"));
        println!("{verdict}");
        let passed = s["acceptance"]["passed"].as_bool().unwrap();
        assert!(
            verdict.starts_with("run: uniaxial: not tested; equibiaxial to λ")
                || verdict.starts_with("run: acceptance tested nothing"),
            "{verdict}"
        );
        assert_eq!(verdict.contains("-> PASSED"), passed, "{verdict}\n{s}");
        if !passed {
            assert_eq!(status.code(), Some(2), "{verdict}\n{stderr}");
        }
    }
    assert!(
        s["faults"].as_array().unwrap().iter().any(|f| f
            .as_str()
            .unwrap()
            .starts_with("correlator killed by signal 9")),
        "{s}"
    );
    let rig_log = std::fs::read_to_string(out.join("logs/rig.log")).unwrap();
    let held_line = rig_log
        .lines()
        .find(|l| l.contains("strain control HELD") && l.contains("stale fields"))
        .unwrap_or_else(|| panic!("no hold on stale fields:\n{rig_log}"));
    println!("{held_line}");
    let rows = rig_rows(&out);
    let modes = mode_sequence(&rows);
    println!("rig.csv modes: {modes:?}");
    // Strain control ran, held, and the test ended unloaded under displacement control.
    let first_strain = modes.iter().position(|m| m == "strain").unwrap();
    assert!(
        modes[first_strain..].iter().any(|m| m == "held"),
        "{modes:?}"
    );
    assert_eq!(modes.last().map(String::as_str), Some("displacement"));
    let last = rows.last().unwrap();
    assert!(
        last.2.abs() < 0.2 && last.3.abs() < 0.2,
        "not unloaded: {last:?}"
    );
    // Never a runaway: within each held stretch of rows the grips stay where they were.
    let mut k = 0;
    while k < rows.len() {
        if rows[k].1 != "held" {
            k += 1;
            continue;
        }
        let start = k;
        while k < rows.len() && rows[k].1 == "held" {
            k += 1;
        }
        for axis in [2, 3] {
            let values = rows[start..k]
                .iter()
                .map(|r| if axis == 2 { r.2 } else { r.3 });
            let (lo, hi) = values.fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
            assert!(
                hi - lo < 0.1,
                "grips moved {} mm while held at t = {}",
                hi - lo,
                rows[start].0
            );
        }
    }
    let reached = rows.iter().map(|r| r.2).fold(f64::MIN, f64::max);
    match on_interlock {
        "resume" => {
            assert!(rig_log.contains("strain control resumed"), "{rig_log}");
            // The program ends when a field shows its last target, and the run says so.
            assert!(
                rig_log.contains("strain program done, the last target reached"),
                "{rig_log}"
            );
            assert_eq!(s["strain_target"]["reached"], true, "{s}");
            assert_eq!(s["strain_target"]["target_stretch"], 1.3, "{s}");
            // The ramp went on to the target after the correlator came back.
            let after_hold = modes[first_strain..]
                .iter()
                .skip_while(|m| *m != "held")
                .any(|m| m == "strain");
            assert!(after_hold, "{modes:?}");
        }
        _ => {
            assert!(rig_log.contains("stopped after the hold"), "{rig_log}");
            assert_eq!(s["strain_target"]["reached"], false, "{s}");
            assert!(!rig_log.contains("strain program done"), "{rig_log}");
        }
    }
    println!("{on_interlock}: largest X elongation {reached:.2} mm");
    // frames.csv: the target the rig aimed at when each frame was taken. Empty while waiting
    // for the first field and after the unloading began (displacement control); equibiaxial
    // and within the program's range under strain control (or held); the measured log
    // strains follow it.
    let frames = frame_targets(&out);
    let targeted: Vec<_> = frames
        .iter()
        .filter_map(|(x, y, t)| t.map(|t| (*x, *y, t)))
        .collect();
    assert!(
        !targeted.is_empty() && targeted.len() < frames.len(),
        "{} of {} frames with a target",
        targeted.len(),
        frames.len()
    );
    assert!(
        frames.first().unwrap().2.is_none(),
        "a target before the start"
    );
    let mut gaps: Vec<f64> = Vec::new();
    for (x, y, [tx, ty]) in &targeted {
        assert!((tx - ty).abs() < 1e-6, "not equibiaxial: ({tx}, {ty})");
        assert!(
            (-1e-6..=1.3f64.ln() + 1e-6).contains(tx),
            "target ln λ {tx} outside the program"
        );
        gaps.push((x - tx).abs().max((y - ty).abs()));
    }
    gaps.sort_by(f64::total_cmp);
    let median_gap = gaps[gaps.len() / 2];
    println!("{on_interlock}: median |measured - target| log strain {median_gap:.2e}");
    assert!(median_gap < 0.002, "measured far from target: {median_gap}");
}

#[test]
fn correlator_killed_mid_ramp_the_rig_holds_then_resumes() {
    kill_correlator_mid_ramp("resume");
}

#[test]
fn correlator_killed_mid_ramp_the_rig_holds_then_stops_cleanly() {
    kill_correlator_mid_ramp("stop");
}
