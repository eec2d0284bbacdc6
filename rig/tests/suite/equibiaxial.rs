//! Equibiaxial ramp to λ = 2 at 1e-3 /s in centroid displacement control, in simulated time
//! (1000 s at 5 kHz = 5 M steps): centre drift of each axis, elongation following error, and
//! grip forces against eq. (19) evaluated directly with the law (`material`).

use material::InvariantLaw;
use rig::{Axis, Program, ProgramStatus, Rig, RigCommand, RigConfig};

const PROGRAM: &str = r#"
name = "equibiaxial to 2 at 1e-3 /s"
[[setup]]
axis = "x"
control = "centroid_displacement"
[[setup]]
axis = "y"
control = "centroid_displacement"
[[channel]]
target = "x.elongation"
segments = [{ kind = "hold", duration_s = 1.0 }, { kind = "ramp", to = 100.0, rate_per_s = 0.1 }]
[[channel]]
target = "y.elongation"
segments = [{ kind = "hold", duration_s = 1.0 }, { kind = "ramp", to = 100.0, rate_per_s = 0.1 }]
"#;

#[test]
fn equibiaxial_ramp_to_stretch_two() {
    // The homogeneous sheet with rigid grips: this test checks the grips against eq. (19);
    // the structure's grip effects have their own tests (tests/suite/strain_control.rs,
    // rig/tests/suite/structure.rs).
    let mut config = RigConfig::default();
    config.specimen.as_mut().unwrap().grip_compliance_mm_per_kn = 0.0;
    let specimen = config.specimen.clone().unwrap();
    assert_eq!(specimen.model, rig::SpecimenModel::Homogeneous);
    let [gauge_mm, gauge_y_mm] = specimen.gauge_mm();
    let section_mm2 = specimen.reference_sections_mm2()[0];
    assert_eq!(gauge_mm, gauge_y_mm, "square cruciform centre");
    let noise_kn = config.load_cell_noise_kn;
    let mut rig = Rig::new(config, 11).unwrap();
    rig.advance_to(0.5);
    let program = Program::from_toml(PROGRAM, std::path::Path::new(".")).unwrap();
    rig.command(RigCommand::StartProgram(Box::new(program)))
        .unwrap();
    let centre0 = [rig.state().axes[0].centre_mm, rig.state().axes[1].centre_mm];

    let law = InvariantLaw::smactane();
    let started = std::time::Instant::now();
    let mut max_drift_mm = [0.0f64; 2];
    let mut max_error_mm = [0.0f64; 2];
    let mut max_force_rel = 0.0f64;
    let mut checkpoints = 0;
    let steps_per_s = rig.config().control_hz as u64;
    let mut guard = 0u64;
    while rig.state().program == ProgramStatus::Running {
        rig.step();
        guard += 1;
        assert!(guard < 1_100 * steps_per_s, "program did not finish");
        let s = rig.state();
        for axis in [Axis::X, Axis::Y] {
            let a = axis.index();
            let drift = (s.axes[a].centre_mm - centre0[a]).abs();
            max_drift_mm[a] = max_drift_mm[a].max(drift);
            // Elongation command = sum of the two actuator commands.
            let (p, m) = (axis.plus().index(), axis.minus().index());
            let command = s.actuators[p].command + s.actuators[m].command;
            max_error_mm[a] = max_error_mm[a].max((command - s.axes[a].elongation_mm).abs());
        }
        if s.step.is_multiple_of(100 * steps_per_s) {
            let lambda = 1.0 + s.axes[0].elongation_mm / gauge_mm;
            if lambda > 1.05 {
                // Eq. (19): Cauchy stress × current section (w t / λ) = nominal × reference.
                let expected_kn =
                    law.equibiaxial_cauchy_stress_mpa(lambda) * section_mm2 / lambda * 1e-3;
                let measured_kn = s.axes[0].force_kn;
                let rel = (measured_kn - expected_kn).abs() / expected_kn;
                println!(
                    "t {:7.1} s  λ {lambda:.4}  F_x {measured_kn:.4} kN  eq.19 {expected_kn:.4} kN  \
                     rel {rel:.2e}",
                    s.t_s
                );
                assert!(
                    (measured_kn - expected_kn).abs() < 0.002 * expected_kn + 5.0 * noise_kn,
                    "force {measured_kn} vs eq. 19 {expected_kn} at λ {lambda}"
                );
                max_force_rel = max_force_rel.max(rel);
                checkpoints += 1;
            }
        }
    }
    let wall_s = started.elapsed().as_secs_f64();
    let s = rig.state();
    assert_eq!(s.program, ProgramStatus::Finished);
    let level_mm = 100.0;
    let lambda = [s.specimen.stretch_x, s.specimen.stretch_y];
    println!(
        "equibiaxial: {:.1} s simulated in {wall_s:.2} s wall ({:.0}x), final λ {:.5} {:.5}",
        s.t_s,
        s.t_s / wall_s,
        lambda[0],
        lambda[1]
    );
    println!(
        "max centre drift X {:.2e} mm Y {:.2e} mm; max elongation following error X {:.2e} mm \
         Y {:.2e} mm ({:.3} % of {level_mm} mm); max force deviation from eq. 19 {:.2e} \
         ({checkpoints} checkpoints)",
        max_drift_mm[0],
        max_drift_mm[1],
        max_error_mm[0],
        max_error_mm[1],
        max_error_mm[0].max(max_error_mm[1]) / level_mm * 100.0,
        max_force_rel
    );
    assert!(checkpoints >= 8);
    for a in 0..2 {
        assert!(
            max_drift_mm[a] < 0.01,
            "centre drift {} mm",
            max_drift_mm[a]
        );
        assert!(
            max_error_mm[a] < 0.01 * level_mm,
            "following error {} mm",
            max_error_mm[a]
        );
        assert!(
            (lambda[a] - 2.0).abs() < 1e-3,
            "final stretch {}",
            lambda[a]
        );
    }
    assert_eq!(s.limits_tripped, 0);
}
