//! `dicstream run` on the specimen as a structure (`[specimen] model = "structure"`), with
//! real processes: the rig publishes its solved states on `specimen`, the camera films the
//! finite-element field of each state, and the run compares every correlated node with that
//! field (issue "the specimen is a structure", deliverable 4).

mod common;

use common::bench_run::{
    child_pid, completed_summary, config, rows, signal, start_run, wait_rows, SHORT_CAMPAIGN,
};
use common::Run;

/// The short campaign on the structure, with `run_keys` in `[run]`, filmed at 0.015 mm/px:
/// 3.8 mm of the strip's and the cruciform's centres, all material (the default views'
/// edges and fillets are `the_default_run_films_the_cruciform_and_its_field_decides`'s).
fn structure_config(run: &Run, run_keys: &str) -> std::path::PathBuf {
    let extra = format!("{SHORT_CAMPAIGN}[specimen]\nmodel = \"structure\"\n");
    let path = config(run, run_keys, &extra);
    let text = std::fs::read_to_string(&path).unwrap().replace(
        "height_px = 256\n",
        "height_px = 256\nmm_per_px = 0.015\nstrip_mm_per_px = 0.015\n",
    );
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_run_on_the_structure_compares_every_node_with_the_filmed_field() {
    let mut run = Run::new("run_structure");
    let config = structure_config(&run, "");
    // Two of the user's gauges (issue 28 d2): their columns in frames.csv.
    let text = std::fs::read_to_string(&config).unwrap().replace(
        "[correlator]\n",
        "[correlator]\ngauges = [\"mid=rect:96,96,64,64\", \"span=extensometer:64,128 192,128\"]\n",
    );
    std::fs::write(&config, text).unwrap();
    let out = run.dir.join("out");
    start_run(&mut run, "run", &config, &out, &["--no-dashboard"]);
    // The acceptance divides forces by the gauge's sections, wrong on a heterogeneous field
    // (issue "identification from the whole field"): completed, doubtful (2), or passed.
    let (summary, stdout) = completed_summary(&mut run, &out);
    let truth = &summary["truth"];
    assert_eq!(truth["compared_with"], "finite-element field", "{summary}");
    assert!(truth["specimen_solves"].as_u64().unwrap() > 10, "{truth}");
    assert_eq!(truth["fields_without_truth"], 0, "{truth}");
    assert_eq!(truth["fields_compared"], summary["fields"], "{truth}");
    // Node by node against the field the images show: the correlator's usual error at this
    // speckle and noise. (Against the homogeneous mean motion instead, a 1024 px run of the
    // same campaign was off by 0.35 px on average: the field is not homogeneous in view.)
    let p99 = truth["node_error_p99_px"].as_f64().unwrap();
    assert!(p99 < 0.05, "node error p99 {p99} px\n{truth}");
    // Every row says its error: no frame of the structure went without its truth.
    let header = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let columns: Vec<&str> = header.lines().next().unwrap().split(',').collect();
    let mean = columns
        .iter()
        .position(|c| *c == "disp_error_mean_px")
        .unwrap();
    let rows = rows(&out.join("frames.csv"));
    assert!(rows.len() > 20, "{} rows", rows.len());
    for row in &rows {
        let error: f64 = row[mean].parse().unwrap_or_else(|_| panic!("{row:?}"));
        assert!(error < 0.05, "{row:?}");
    }
    assert!(stdout.contains("(finite-element field)"), "{stdout}");
    // The gauges' columns, before sequence_id. At the centre of the specimen the field is
    // near homogeneous at this scale: the central strain gauge reads what the control gauge
    // (the mesh's central half) reads, and the extensometer across it the same stretch.
    let column = |name: &str| {
        columns
            .iter()
            .position(|c| *c == name)
            .unwrap_or_else(|| panic!("no column {name}: {columns:?}"))
    };
    assert_eq!(columns.last(), Some(&"sequence_id"));
    let (control, mid, mid_nodes, span) = (
        column("log_exx"),
        column("gauge_mid_log_exx"),
        column("gauge_mid_nodes"),
        column("ext_span_nominal_strain"),
    );
    // The simulated camera's scale (0.015 mm/px on both specimens here) gives the mm column.
    let (span_px, span_mm) = (
        column("ext_span_elongation_px"),
        column("ext_span_elongation_mm"),
    );
    // The most stretched row (the campaign ends unloaded).
    let cell = |row: &Vec<String>, k: usize| -> f64 { row[k].parse().unwrap_or(f64::NAN) };
    let last = rows
        .iter()
        .filter(|r| cell(r, mid).is_finite() && cell(r, span).is_finite())
        .max_by(|a, b| cell(a, control).total_cmp(&cell(b, control)))
        .unwrap();
    let value = |k: usize| cell(last, k);
    eprintln!(
        "most stretched row: control log exx {:.5}, mid {:.5} over {} nodes, span nominal {:.5}",
        value(control),
        value(mid),
        last[mid_nodes],
        value(span)
    );
    assert!(value(control) > 0.05, "{last:?}");
    let mm_per_px = value(span_mm) / value(span_px);
    assert!(
        (mm_per_px - 0.015).abs() < 1e-4,
        "{mm_per_px} mm/px: {last:?}"
    );
    assert!(value(mid_nodes) > 10.0, "{last:?}");
    assert!((value(mid) - value(control)).abs() < 0.01, "{last:?}");
    assert!(
        (value(span) - value(control).exp_m1()).abs() < 0.02,
        "{last:?}"
    );
}

/// kill -9 of the rig while it publishes the structure's solves: the restarted rig resumes
/// from its journal and publishes its solves again; the camera renders no frame whose solve it
/// lacks (it skips it, saying so), and every correlated field still has its truth.
#[test]
fn a_rig_killed_mid_test_on_the_structure_leaves_no_field_without_its_truth() {
    let mut run = Run::new("kill_rig_structure");
    // VTK fields too: their time series must list every one written, the kill notwithstanding.
    let config = structure_config(&run, "vtk = true");
    let out = run.dir.join("out");
    let parent = start_run(
        &mut run,
        "run",
        &config,
        &out,
        &["--no-dashboard", "--quiet"],
    );
    wait_rows(&out.join("frames.csv"), 0, 15);
    let rig = child_pid(parent, "rig").expect("the rig runs while the campaign does");
    signal(rig, libc::SIGKILL);
    // Frames lost to the fault make the results doubtful (2); the acceptance fails on a
    // heterogeneous field anyway (see above).
    let (summary, _) = completed_summary(&mut run, &out);
    let restarts = summary["restarts"].to_string();
    assert!(restarts.contains("rig restarted"), "{summary}");
    let truth = &summary["truth"];
    assert_eq!(truth["compared_with"], "finite-element field", "{summary}");
    assert_eq!(truth["fields_without_truth"], 0, "{truth}");
    assert_eq!(truth["fields_compared"], summary["fields"], "{truth}");
    let p99 = truth["node_error_p99_px"].as_f64().unwrap();
    assert!(p99 < 0.05, "node error p99 {p99} px\n{truth}");
    let fields = out.join("fields");
    let series: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fields.join("fields.vtk.series")).unwrap())
            .unwrap();
    let listed: Vec<&str> = series["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    let mut written: Vec<String> = std::fs::read_dir(&fields)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".vtk"))
        .collect();
    written.sort();
    assert!(!written.is_empty());
    assert_eq!(listed, written, "{series}");
    let times: Vec<f64> = series["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["time"].as_f64().unwrap())
        .collect();
    assert!(times.windows(2).all(|t| t[0] < t[1]), "{times:?}");
    assert!(
        run.instance.leftover_files().is_empty(),
        "{:?}",
        run.instance.leftover_files()
    );
}
