//! `dicstream monitor --config FILE`: the run's named gauges (virtual extensometers and strain
//! gauges) on a monitor's dashboard, read from the fields it receives with the run's own code,
//! against what the run writes in `frames.csv`'s gauge columns; a configuration whose gauges
//! are wrong, or that does not parse, refused before anything is served.

use crate::common;
use crate::dashboard_support::{spawn_monitor, try_snapshot};

use common::bench_run::{rows, start_run};
use common::{dicstream, Run};
use serde_json::Value;
use std::path::{Path, PathBuf};
use testkit::until;

/// A run long enough to watch (a slow uniaxial ramp, interrupted once the checks are done)
/// with two named gauges, `gauges` being the TOML array's items.
fn write_config(dir: &Path, gauges: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("monitor.toml");
    std::fs::write(
        &path,
        format!(
            "[run]\nresults_dir = \"{}\"\nstatus_interval_s = 0.5\n\
             [camera]\nwidth_px = 256\nheight_px = 256\nfps = 10.0\n\
             [correlator]\nthreads = 1\ngauges = [{gauges}]\n\
             [rig]\npublish_hz = 100.0\nlog_hz = 20.0\n\
             [specimen]\nmodel = \"homogeneous\"\n\
             [[rig.tests]]\nkind = \"uniaxial\"\nstretch = 1.5\nrate_per_s = 0.02\n",
            dir.join("results").display()
        ),
    )
    .unwrap();
    path
}

const GAUGES: &str = "\"middle=rect:64,64,128,128\", \"span=extensometer:64,128 192,128\"";

/// A gauge's series `key` as numbers (NaN for null: no reading on that field).
fn series(gauge: &Value, key: &str) -> Vec<f64> {
    gauge["series"][key]
        .as_array()
        .unwrap_or_else(|| panic!("no series {key}: {gauge}"))
        .iter()
        .map(|v| v.as_f64().unwrap_or(f64::NAN))
        .collect()
}

#[test]
fn monitor_charts_the_runs_named_gauges_as_its_frames_csv_says() {
    let mut bench = Run::new("monitor_gauges");
    let dir = bench.dir.clone();
    let config = write_config(&dir, GAUGES);
    let out = dir.join("out");
    start_run(
        &mut bench,
        "run",
        &config,
        &out,
        &["--no-dashboard", "--quiet"],
    );
    bench
        .child("run")
        .wait_for_stderr("rig ready", |l| l.contains("rig ready"));
    let config_arg = config.display().to_string();
    let (addr, said) = spawn_monitor(&mut bench, &["--config", &config_arg]);
    assert!(
        said.contains("gauges middle (strain), span (extensometer); extensometers in mm"),
        "{said}"
    );

    // The monitor's snapshot carries both gauges by name, with points on the test's clock.
    let snapshot = until("12 points of the named gauges on the monitor", || {
        let s = try_snapshot(&addr)?;
        let points = s["user_gauges"][1]["t_s"].as_array().map_or(0, Vec::len);
        (points >= 12 && s["gauge"]["clock"] == "test").then_some(s)
    });
    let gauges = &snapshot["user_gauges"];
    assert_eq!(gauges[0]["name"], "middle");
    assert_eq!(gauges[0]["kind"], "strain gauge");
    assert_eq!(gauges[1]["name"], "span");
    assert_eq!(gauges[1]["unit"], "mm");

    // The run's own numbers for the same fields (the same rig sample: the same test time).
    let run = bench.child("run");
    run.signal(libc::SIGINT);
    let (status, _, stderr) = run.wait();
    assert_eq!(status.code(), Some(130), "{stderr}");
    let frames_csv = out.join("frames.csv");
    let text = std::fs::read_to_string(&frames_csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|c| *c == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    let (t_col, exx_col, eyy_col, span_col) = (
        column("t_sim_s"),
        column("gauge_middle_log_exx"),
        column("gauge_middle_log_eyy"),
        column("ext_span_elongation_mm"),
    );
    let csv_rows = rows(&frames_csv);
    let cell = |row: &[String], k: usize| row[k].parse::<f64>().unwrap_or(f64::NAN);
    let (t_s, exx, eyy, span) = (
        gauges[0]["t_s"].as_array().unwrap(),
        series(&gauges[0], "exx"),
        series(&gauges[0], "eyy"),
        series(&gauges[1], "elongation"),
    );
    let mut compared = 0;
    let mut largest_elongation_mm = 0f64;
    for (k, t) in t_s.iter().enumerate() {
        let t = t.as_f64().unwrap();
        let Some(row) = csv_rows.iter().find(|r| (cell(r, t_col) - t).abs() < 1e-4) else {
            continue;
        };
        for (what, monitor, run, tolerance) in [
            ("middle exx", exx[k], cell(row, exx_col), 1e-6),
            ("middle eyy", eyy[k], cell(row, eyy_col), 1e-6),
            ("span elongation (mm)", span[k], cell(row, span_col), 1e-5),
        ] {
            assert!(
                (monitor - run).abs() <= tolerance,
                "{what} at t = {t} s: monitor {monitor}, frames.csv {run}"
            );
        }
        largest_elongation_mm = largest_elongation_mm.max(span[k]);
        compared += 1;
    }
    assert!(
        compared >= 8,
        "only {compared} of the monitor's {} points found in frames.csv",
        t_s.len()
    );
    // The ramp stretches the specimen: the numbers compared are not all zero.
    assert!(largest_elongation_mm > 0.0, "{span:?}");

    let monitor = bench.child("monitor");
    monitor.signal(libc::SIGINT);
    assert_eq!(monitor.wait_exit().code(), Some(0), "{}", monitor.stderr());
}

#[test]
fn monitor_without_a_config_says_gauges_need_one() {
    let mut bench = Run::new("monitor_no_config");
    let (addr, said) = spawn_monitor(&mut bench, &["--wait"]);
    assert!(said.contains("add --config FILE"), "{said}");
    let snapshot = until("the monitor's first snapshot", || try_snapshot(&addr));
    assert_eq!(snapshot["user_gauges"], Value::Null);
    let monitor = bench.child("monitor");
    monitor.signal(libc::SIGINT);
    monitor.wait_exit();
}

#[test]
fn monitor_refuses_a_config_with_bad_gauges_or_bad_toml() {
    let bench = Run::new("monitor_bad_config");
    let instance = bench.name().to_string();
    let refuse = |label: &str, config: &Path, expected: &str| {
        let output = dicstream(&[
            "monitor",
            "--instance",
            &instance,
            "--dashboard",
            "127.0.0.1:0",
            "--config",
            config.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{label}: accepted\n{stderr}");
        assert!(stderr.contains(expected), "{label}: {stderr}");
        assert!(!stderr.contains("http://"), "{label}: served\n{stderr}");
    };
    let outside = write_config(
        &bench.dir.join("outside"),
        "\"far=extensometer:64,128 300,128\"",
    );
    refuse(
        "a gauge outside the image",
        &outside,
        "point 300,128 is outside the 256x256 px image",
    );
    let unknown = write_config(&bench.dir.join("unknown"), "\"round=circle:128,128,20\"");
    refuse(
        "an unknown gauge kind",
        &unknown,
        "gauge \"round=circle:128,128,20\": expected NAME=rect",
    );
    let broken = bench.dir.join("broken.toml");
    std::fs::write(&broken, "[camera\nwidth_px = 256\n").unwrap();
    refuse(
        "a configuration that does not parse",
        &broken,
        "broken.toml",
    );
    let missing = bench.dir.join("missing.toml");
    refuse(
        "a configuration that is not there",
        &missing,
        "missing.toml",
    );
}
