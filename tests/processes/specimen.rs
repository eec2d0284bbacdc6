//! `dicstream specimen` end to end: a cruciform and a strip solved along a path of grip
//! stretches, the files it writes (summary.json, a CSV and a VTK per state) checked against
//! mechanics (balanced grip forces, the cruciform's symmetry, the strip's analytic uniaxial
//! stress far from its clamps), and its refusals (a y stretch on a strip, a folder that holds
//! something, a geometry that cannot be meshed, a path that does not converge).

use crate::common::dicstream;
use serde_json::Value;
use std::path::Path;
use std::process::Output;
use testkit::Run;

fn text(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A configuration whose strip has a coarse mesh (quick); the cruciform and the law are the
/// defaults.
fn coarse_config(run: &Run) -> std::path::PathBuf {
    let config = run.dir.join("coarse.toml");
    std::fs::write(
        &config,
        "[specimen.geometry.uniaxial_strip]\nlength_mm = 100.0\nwidth_mm = 10.0\n\
         thickness_mm = 2.0\nelement_size_mm = 2.5\n",
    )
    .unwrap();
    config
}

/// A CSV row: column name to cell.
type Row = std::collections::HashMap<String, String>;

/// The CSV's rows.
fn rows(csv: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

fn number(row: &Row, key: &str) -> f64 {
    row[key].parse().unwrap()
}

/// The node nearest the specimen's centre (its reference position).
fn nearest_centre(nodes: &[Row]) -> &Row {
    let radius = |n: &Row| number(n, "x_mm").hypot(number(n, "y_mm"));
    nodes
        .iter()
        .min_by(|a, b| radius(a).total_cmp(&radius(b)))
        .unwrap()
}

/// `dicstream specimen --config <coarse_config> ARGS --out <a fresh folder>`, which must
/// succeed: the test's bench (kept alive for its folder), the folder and the output.
fn solved(test: &str, args: &[&str]) -> (Run, std::path::PathBuf, Output) {
    let run = Run::new(test, env!("CARGO_BIN_EXE_dicstream"));
    let config = coarse_config(&run);
    let out = run.dir.join("out");
    let mut all = vec!["specimen", "--config", text(&config)];
    all.extend_from_slice(args);
    all.extend(["--out", text(&out)]);
    let o = dicstream(&all);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (run, out, o)
}

#[test]
fn a_cruciform_path_writes_balanced_symmetric_states() {
    let (_run, out, o) = solved(
        "specimen_cruciform",
        &["--stretch", "1.4", "--states", "2", "--json"],
    );
    // --json: the summary alone on stdout, the same as summary.json.
    let printed: Value = serde_json::from_slice(&o.stdout).expect("stdout is JSON alone");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(printed, summary);
    assert_eq!(summary["shape"], "cruciform");
    assert!(summary["stopped"].is_null());
    let states = summary["states"].as_array().unwrap();
    assert_eq!(states.len(), 2);
    let mut previous_force = 0.0;
    for (index, state) in states.iter().enumerate() {
        let stretch = state["grip_stretch"]["x"].as_f64().unwrap();
        assert!((stretch - [1.2, 1.4][index]).abs() < 1e-12, "{stretch}");
        let forces = &state["grip_force_n"];
        let (mut sum_x, mut sum_y) = (0.0, 0.0);
        for grip in ["x+", "x-", "y+", "y-"] {
            sum_x += forces[grip][0].as_f64().unwrap();
            sum_y += forces[grip][1].as_f64().unwrap();
        }
        let axial = &state["grip_axial_force_n"];
        let fx = axial["x+"].as_f64().unwrap();
        assert!(fx > previous_force, "the arm force grows along the path");
        previous_force = fx;
        assert!(
            sum_x.abs() < 1e-6 * fx && sum_y.abs() < 1e-6 * fx,
            "{forces}"
        );
        // Equal arms pull equally, up to the mesh's own asymmetry (its patches' alternating
        // diagonals are not mirror images: about 1e-5 here).
        for grip in ["x-", "y+", "y-"] {
            let f = axial[grip].as_f64().unwrap();
            assert!((f - fx).abs() < 1e-4 * fx, "{grip}: {f} against {fx}");
        }
        // Newton converged quadratically: the last step's residuals fall fast at the end.
        let residuals: Vec<f64> = state["last_step_residuals_n"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r.as_f64().unwrap())
            .collect();
        assert!(residuals.len() >= 2, "{residuals:?}");
        let n = residuals.len();
        assert!(residuals[n - 1] < 1e-3 * residuals[n - 2], "{residuals:?}");
    }
    // The last state's nodes: one row each, and the centre (a node of the default mesh) is
    // equibiaxial.
    let nodes = rows(&out.join("state_002.csv"));
    assert_eq!(nodes.len() as u64, summary["nodes"].as_u64().unwrap());
    let centre = nearest_centre(&nodes);
    assert_eq!(number(centre, "x_mm").hypot(number(centre, "y_mm")), 0.0);
    let (l1, l2) = (number(centre, "stretch_1"), number(centre, "stretch_2"));
    assert!(
        l1 > 1.05 && (l1 - l2).abs() < 1e-6 * l1,
        "centre λ {l1} {l2}"
    );
    let vtk = std::fs::read_to_string(out.join("state_002.vtk")).unwrap();
    assert!(vtk.contains("DATASET UNSTRUCTURED_GRID"));
    assert!(vtk.contains(&format!("POINT_DATA {}", nodes.len())));
}

#[test]
fn a_strip_far_from_its_clamps_carries_the_analytic_uniaxial_stress() {
    let (_run, out, o) = solved(
        "specimen_strip",
        &["--shape", "uniaxial_strip", "--stretch", "2"],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("state 1: grip stretch x 2.0000 y 1.0000"),
        "{stdout}"
    );
    let nodes = rows(&out.join("state_001.csv"));
    let law = material::InvariantLaw::smactane();
    // The node nearest the centre, 50 mm (5 widths) from either clamp.
    let centre = nearest_centre(&nodes);
    let lambda = number(centre, "stretch_1");
    let expected = law.uniaxial_cauchy_stress_mpa(lambda);
    let measured = number(centre, "cauchy_xx_mpa");
    println!("centre λ {lambda}: σxx {measured} MPa, analytic uniaxial {expected} MPa");
    assert!((measured - expected).abs() < 5e-3 * expected);
    assert!(number(centre, "cauchy_yy_mpa").abs() < 5e-3 * expected);
    // Near the clamps the strip is not uniaxial: the neck is held in width.
    let at_clamp = nodes
        .iter()
        .find(|n| number(n, "x_mm") > 49.9 && number(n, "y_mm").abs() < 1e-9)
        .unwrap();
    assert!(number(at_clamp, "cauchy_yy_mpa") > 0.05 * expected);
}

/// Runs `dicstream ARGS`, which must fail with `expected` in its error.
fn refused(args: &[&str], expected: &str) {
    let o = dicstream(args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(stderr.contains(expected), "{args:?}: {stderr}");
}

#[test]
fn what_cannot_be_solved_is_refused_naming_why() {
    let run = Run::new("specimen_refusals", env!("CARGO_BIN_EXE_dicstream"));
    let config = coarse_config(&run);
    let out = |label: &str| run.dir.join(label);
    let (strip, out_a) = ("uniaxial_strip", out("a"));
    refused(
        &[
            "specimen",
            "--config",
            text(&config),
            "--shape",
            strip,
            "--stretch-y",
            "1.2",
            "--out",
            text(&out_a),
        ],
        "no grip along y",
    );

    let busy = run.temp_dir("busy");
    std::fs::write(busy.join("keep.txt"), "mine").unwrap();
    refused(
        &["specimen", "--config", text(&config), "--out", text(&busy)],
        "is not empty (it holds keep.txt)",
    );
    assert_eq!(
        std::fs::read_to_string(busy.join("keep.txt")).unwrap(),
        "mine"
    );

    for (label, table, expected) in [
        (
            "bad",
            "arm_width_mm = 20.0\nfillet_radius_mm = -5.0\n",
            "[specimen.geometry] cruciform refused",
        ),
        ("typo", "arm_widht_mm = 20.0\n", "arm_widht_mm"),
    ] {
        let file = run.dir.join(format!("{label}.toml"));
        std::fs::write(&file, format!("[specimen.geometry.cruciform]\n{table}")).unwrap();
        let folder = out(label);
        refused(
            &["specimen", "--config", text(&file), "--out", text(&folder)],
            expected,
        );
    }
}

/// A law that softens (ln f falling with I1: not stable in Drucker's sense at large strain)
/// cannot be followed to the end: the path stops at the state where the tangent stops being
/// positive definite, says so, exits non-zero and keeps the states before it, with no force of
/// the failed one.
#[test]
fn a_path_that_stops_keeps_its_converged_states_and_names_the_failure() {
    let run = Run::new("specimen_unstable", env!("CARGO_BIN_EXE_dicstream"));
    let config = run.dir.join("softening.toml");
    std::fs::write(
        &config,
        "[specimen]\nlaw_f = [-1.27, -0.4]\nlaw_g = [-1.02]\n\n\
         [specimen.geometry.uniaxial_strip]\nlength_mm = 100.0\nwidth_mm = 10.0\n\
         thickness_mm = 2.0\nelement_size_mm = 5.0\n\n[specimen.geometry]\nshape = \"uniaxial_strip\"\n",
    )
    .unwrap();
    let out = run.dir.join("out");
    let o = dicstream(&[
        "specimen",
        "--config",
        text(&config),
        "--stretch",
        "4",
        "--states",
        "6",
        "--out",
        text(&out),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("the path stopped after"), "{stderr}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let reached = summary["states"].as_array().unwrap().len();
    assert!((1..6).contains(&reached), "{summary}");
    let stopped = summary["stopped"].as_str().unwrap();
    assert!(
        stopped.starts_with(&format!("state {}", reached + 1)),
        "{stopped}"
    );
    assert!(out.join(format!("state_{reached:03}.csv")).exists());
    assert!(!out.join(format!("state_{:03}.csv", reached + 1)).exists());
}
