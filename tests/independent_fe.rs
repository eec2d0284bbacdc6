//! The specimen's mechanics against an independent finite-element code: the clamped uniaxial
//! strip solved by `dicstream specimen` (plane-stress incompressible membrane, T6 elements)
//! and by felupe (a 3D nearly incompressible solid of trilinear hexahedra,
//! `tests/independent_fe/strip_felupe.py`), the paper's law truncated after its linear terms.
//! The two codes share nothing: not the element, not the incompressibility treatment (plane
//! stress against a bulk modulus 5000 times the shear modulus), not the solver.
//!
//! felupe is a Python package: without it the test says so and passes, unless
//! `DICSTREAM_REQUIRE_FELUPE=1` (`.ci/run` installs it and sets that).

use serde_json::Value;
use std::process::Command;
use testkit::Run;

/// `ln f(I1) = A0 + A1 (I1 − 3)`, `ln g(I2) = B0 + B1 (I2 − 3)`: Smactane's first two terms.
const A: [f64; 2] = [-1.27, -0.0252];
const B: [f64; 2] = [-1.02, -0.00392];
const LENGTH_MM: f64 = 100.0;
const WIDTH_MM: f64 = 20.0;
const THICKNESS_MM: f64 = 2.0;
/// Largest relative difference of the grip forces accepted. Measured: 2e-5 at these meshes
/// (63.1016 N and 63.1027 N at a grip stretch of 2); the converged forces (membrane at
/// 1.25 mm elements, felupe at 2,560 hexahedra) are 63.0950 N and 63.0911 N.
const TOLERANCE: f64 = 1e-3;

const REQUIRE_VAR: &str = "DICSTREAM_REQUIRE_FELUPE";

fn felupe_available() -> bool {
    Command::new("python3")
        .args(["-c", "import felupe, tensortrax"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Asserts the command succeeded, with its stderr if not.
fn succeeded(output: &std::process::Output) {
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// The membrane's grip force (N) at the grip stretch `stretch`.
fn membrane_force_n(run: &Run, stretch: f64) -> f64 {
    let config = run.dir.join("strip.toml");
    std::fs::write(
        &config,
        format!(
            "[specimen]\nlaw_f = [{}, {}]\nlaw_g = [{}, {}]\n\
             [specimen.geometry.uniaxial_strip]\nlength_mm = {LENGTH_MM}\nwidth_mm = {WIDTH_MM}\n\
             thickness_mm = {THICKNESS_MM}\nelement_size_mm = 2.5\n",
            A[0], A[1], B[0], B[1]
        ),
    )
    .unwrap();
    let out = run.dir.join("membrane");
    let output = Command::new(env!("CARGO_BIN_EXE_dicstream"))
        .args(["specimen", "--config", config.to_str().unwrap()])
        .args([
            "--shape",
            "uniaxial_strip",
            "--stretch",
            &stretch.to_string(),
        ])
        .args(["--out", out.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    succeeded(&output);
    let summary: Value = serde_json::from_slice(&output.stdout).unwrap();
    summary["states"][0]["grip_axial_force_n"]["x+"]
        .as_f64()
        .unwrap()
}

/// felupe's grip force (N) at the grip stretch `stretch`, and the seconds it took.
fn felupe_force_n(stretch: f64) -> (f64, f64) {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/independent_fe/strip_felupe.py"
    );
    let numbers = [
        A[0],
        A[1],
        B[0],
        B[1],
        LENGTH_MM,
        WIDTH_MM,
        THICKNESS_MM,
        stretch,
    ];
    let output = Command::new("python3")
        .arg(script)
        .args(numbers.iter().map(f64::to_string))
        // One eighth of the strip: 40 x 8 x 2 hexahedra (2.5 mm in plane, 0.5 mm deep).
        .args(["40", "8", "2"])
        .output()
        .unwrap();
    succeeded(&output);
    let stdout = String::from_utf8_lossy(&output.stdout);
    let last = stdout.lines().last().unwrap_or_default();
    let result: Value =
        serde_json::from_str(last).unwrap_or_else(|e| panic!("{e}: felupe printed {stdout}"));
    (
        result["grip_force_n"].as_f64().unwrap(),
        result["seconds"].as_f64().unwrap(),
    )
}

#[test]
fn the_clamped_strip_gives_felupes_grip_force() {
    if !felupe_available() {
        assert!(
            !std::env::var(REQUIRE_VAR).is_ok_and(|v| v == "1"),
            "{REQUIRE_VAR}=1 but python3 cannot import felupe and tensortrax \
             (pip install felupe==11.3.0 tensortrax==0.29.0)"
        );
        eprintln!(
            "skipped: python3 cannot import felupe and tensortrax (pip install felupe==11.3.0 \
             tensortrax==0.29.0)"
        );
        return;
    }
    let run = Run::new("independent_fe", env!("CARGO_BIN_EXE_dicstream"));
    let stretch = 2.0;
    let membrane = membrane_force_n(&run, stretch);
    let (felupe, seconds) = felupe_force_n(stretch);
    let relative = (membrane - felupe).abs() / felupe;
    eprintln!(
        "grip stretch {stretch}: membrane {membrane:.4} N, felupe {felupe:.4} N ({seconds:.1} s), \
         relative difference {relative:.1e}"
    );
    // Both well above the homogeneous sheet's force: the clamps' share is in both.
    let homogeneous = {
        let l: f64 = stretch;
        let (i1, i2) = (l * l + 2.0 / l, 2.0 * l + 1.0 / (l * l));
        let f = (A[0] + A[1] * (i1 - 3.0)).exp();
        let g = (B[0] + B[1] * (i2 - 3.0)).exp();
        2.0 * (f + g / l) * (l - 1.0 / (l * l)) * WIDTH_MM * THICKNESS_MM
    };
    assert!(
        membrane > homogeneous && felupe > homogeneous,
        "{membrane} {felupe} {homogeneous}"
    );
    assert!(relative < TOLERANCE, "{membrane} N against {felupe} N");
}
