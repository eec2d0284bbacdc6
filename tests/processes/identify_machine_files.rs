//! `dicstream identify` reads test machines' exports as they come (issue 28, deliverable 6): a
//! title line, a units row, `;` delimited cells with decimal commas, quoted cells, a force in
//! kN and an extension in mm with the specimen's section and gauge length give the same fit
//! as the identifier's own clean CSV; a bad cell is an error naming the file, line and column.

use crate::common::dicstream;
use std::path::Path;
use testkit::Run;

const SECTION_MM2: f64 = 8.0;
const GAUGE_MM: f64 = 40.0;

/// (stretch, nominal stress MPa) of a Mooney law (C10 0.2, C01 0.05 MPa) with a 1 % wobble;
/// the stretches are those of whole µm extensions of the gauge length, so both files hold the
/// same numbers.
fn points(equibiaxial: bool) -> Vec<(f64, f64)> {
    (1..=40)
        .map(|k| {
            let extension_mm = 1.5 * k as f64;
            let l = 1.0 + extension_mm / GAUGE_MM;
            let l3 = if equibiaxial {
                1.0 / (l * l)
            } else {
                1.0 / l.sqrt()
            };
            let (w1, w2) = (0.2, 0.05);
            let sigma = 2.0 * w1 * (l * l - l3 * l3) - 2.0 * w2 * (1.0 / (l * l) - 1.0 / (l3 * l3));
            let wobble = 1.0 + 0.01 * ((k * 7919) % 13) as f64 / 13.0;
            (l, sigma / l * wobble)
        })
        .collect()
}

fn clean_csv(path: &Path, equibiaxial: bool) {
    let mut text = String::from("stretch,nominal_stress_mpa\n");
    for (l, p) in points(equibiaxial) {
        text.push_str(&format!("{l},{p}\n"));
    }
    std::fs::write(path, text).unwrap();
}

/// What Bluehill or testXpert writes: a title, a header with quoted names, a units row, `;`
/// and decimal commas, time, extension in mm, force in kN.
fn machine_csv(path: &Path, equibiaxial: bool) {
    let mut text = String::from(
        "\"Results Table 1\"\r\n\"Time\";\"Extension\";\"Load\"\r\n\"(s)\";\"(mm)\";\"(kN)\"\r\n",
    );
    for (k, (l, p)) in points(equibiaxial).into_iter().enumerate() {
        let extension_mm = (l - 1.0) * GAUGE_MM;
        let force_kn = p * SECTION_MM2 / 1000.0;
        let cell = |v: f64| format!("{v}").replace('.', ",");
        text.push_str(&format!(
            "{};{};{}\r\n",
            cell(0.5 * k as f64),
            cell(extension_mm),
            cell(force_kn)
        ));
    }
    std::fs::write(path, text).unwrap();
}

/// The fits of one `identify --json` run: (model, [param values]) in rank order.
fn fits(args: &[&str]) -> Vec<(String, Vec<f64>)> {
    let output = dicstream(args);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{args:?}: {stderr}");
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).expect("JSON on stdout");
    json["fits"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let params = f["params"]
                .as_object()
                .unwrap()
                .values()
                .map(|v| v.as_f64().unwrap())
                .collect();
            (f["model"].as_str().unwrap().to_string(), params)
        })
        .collect()
}

#[test]
fn a_machine_export_gives_the_same_fit_as_the_clean_csv() {
    // The scratch folder, removed on drop.
    let run = Run::new("identify_machine_same", env!("CARGO_BIN_EXE_dicstream"));
    let d = |name: &str| run.dir.join(name).display().to_string();
    clean_csv(&run.dir.join("u.csv"), false);
    clean_csv(&run.dir.join("b.csv"), true);
    machine_csv(&run.dir.join("u_machine.csv"), false);
    machine_csv(&run.dir.join("b_machine.csv"), true);
    let models = "mooney,yeoh,ogden:2";
    let clean = fits(&[
        "identify",
        "--uniaxial",
        &d("u.csv"),
        "--biaxial",
        &d("b.csv"),
        "--model",
        models,
        "--json",
    ]);
    let machine = fits(&[
        "identify",
        "--uniaxial",
        &d("u_machine.csv"),
        "--biaxial",
        &d("b_machine.csv"),
        "--model",
        models,
        "--json",
        "--section-mm2",
        &SECTION_MM2.to_string(),
        "--gauge-length-mm",
        &GAUGE_MM.to_string(),
    ]);
    assert_eq!(clean.len(), 3);
    println!("clean: {clean:?}\nmachine: {machine:?}");
    for ((m_clean, p_clean), (m_machine, p_machine)) in clean.iter().zip(&machine) {
        assert_eq!(m_clean, m_machine, "same ranking");
        for (a, b) in p_clean.iter().zip(p_machine) {
            assert!(
                (a - b).abs() <= 1e-6 * a.abs().max(1e-6),
                "{m_clean}: {a} against {b}"
            );
        }
    }
}

#[test]
fn a_bad_cell_or_a_missing_specimen_is_named() {
    let run = Run::new("identify_machine_bad", env!("CARGO_BIN_EXE_dicstream"));
    let path = run.dir.join("u_machine.csv");
    machine_csv(&path, false);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    lines[9] = "4,5;13,5;n/a".to_string();
    std::fs::write(&path, lines.join("\n")).unwrap();
    let p = path.display().to_string();
    let output = dicstream(&[
        "identify",
        "--uniaxial",
        &p,
        "--model",
        "mooney",
        "--section-mm2",
        "8",
        "--gauge-length-mm",
        "40",
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "{p}: line 10, column 3 `Load`: `n/a` is not a finite number"
        )),
        "{stderr}"
    );
    assert!(output.stdout.is_empty());
    let output = dicstream(&["identify", "--uniaxial", &p, "--model", "mooney"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(
            "column 2 `Extension` is an extension: give the gauge length with --gauge-length-mm"
        ),
        "{stderr}"
    );
}
