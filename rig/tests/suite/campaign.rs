//! The paper's campaign in simulated time: uniaxial tension to λ 3, unload, mount the
//! equibiaxial specimen, equibiaxial tension to λ 2, unload. Each test reaches its stretch
//! with the other axes as the load case says, the specimen change happens only unloaded, and
//! the forces follow the specimen law of the mounted specimen.

use material::InvariantLaw;
use rig::{Campaign, CampaignEvent, Loading, ProgramStatus, Rig, RigCommand, RigConfig};

#[test]
fn paper_campaign_runs_both_tests_in_order() {
    let config = RigConfig {
        specimen: None,
        ..RigConfig::default()
    };
    let mut rig = Rig::new(config, 3).unwrap();
    let mut campaign = Campaign::paper();
    let steps_per_s = rig.config().control_hz;
    let budget_steps = ((campaign.duration_s() + 10.0) * steps_per_s) as u64;
    let law = InvariantLaw::smactane();

    let mut started = Vec::new();
    // Per test: largest stretches seen, and the worst relative force error beyond noise.
    let mut max_stretch = [[1.0f64; 2]; 2];
    let mut worst_force_rel = [0.0f64; 2];
    for step in 0..budget_steps {
        match campaign.advance(&mut rig).unwrap() {
            CampaignEvent::Started { index, test } => {
                let s = rig.state();
                // Mounted unloaded: grips at the mounting position.
                assert!(s.axes[0].elongation_mm.abs() < 0.5, "{:?}", s.axes[0]);
                started.push((index, test.test, s.t_s));
            }
            CampaignEvent::Done => break,
            CampaignEvent::Busy => {}
        }
        rig.step();
        let Some(k) = started.last().map(|s| s.0) else {
            continue;
        };
        let s = rig.state();
        let kin = s.specimen;
        max_stretch[k][0] = max_stretch[k][0].max(kin.stretch_x);
        max_stretch[k][1] = max_stretch[k][1].max(kin.stretch_y);
        if step % 500 == 0 && kin.stretch_x > 1.2 && s.program == ProgramStatus::Running {
            let specimen = rig.specimen().unwrap();
            let section0 = specimen.config().reference_sections_mm2()[0];
            let loading = specimen.config().loading;
            let (lambda, expected_kn) = match loading {
                Loading::Uniaxial(_) => {
                    let l = kin.stretch_x;
                    (l, law.uniaxial_nominal_stress_mpa(l) * section0 * 1e-3)
                }
                Loading::Equibiaxial => {
                    let l = kin.stretch_x;
                    let stress = law.in_plane_stress(l, kin.stretch_y);
                    (l, stress.nominal_stress_mpa[0] * section0 * 1e-3)
                }
            };
            let measured_kn = s.axes[0].force_kn;
            // The pair mean of two load cells: noise σ / √2. Allow 5 σ of noise plus 1 %.
            let noise_kn = rig.config().load_cell_noise_kn / 2f64.sqrt();
            let rel = ((measured_kn - expected_kn).abs() - 5.0 * noise_kn).max(0.0) / expected_kn;
            assert!(lambda > 1.0);
            worst_force_rel[k] = worst_force_rel[k].max(rel);
        }
    }
    assert!(campaign.is_done(&rig), "campaign did not finish in budget");
    println!("started: {started:?}");
    println!("max stretches: {max_stretch:?}; worst force error {worst_force_rel:?}");
    assert_eq!(started.len(), 2);
    assert_eq!(started[0].1, rig::builtin::BuiltinTest::Uniaxial);
    assert_eq!(started[1].1, rig::builtin::BuiltinTest::Equibiaxial);
    // The homogeneous sheet (the default model) stretches as the grips, less the grips' give
    // (1 mm/kN each: 0.15 mm in uniaxial, 2.3 mm at the equibiaxial 1.15 kN). Uniaxial: to λ 3, the free lateral stretch
    // contracts; equibiaxial: to λ 2 on both axes, on the equibiaxial path.
    assert!(
        max_stretch[0][0] <= 3.0 && max_stretch[0][0] > 2.99,
        "{max_stretch:?}"
    );
    assert!(max_stretch[0][1] <= 1.0 + 1e-3, "{max_stretch:?}");
    for axis in 0..2 {
        assert!(
            max_stretch[1][axis] <= 2.0 && max_stretch[1][axis] > 1.97,
            "{max_stretch:?}"
        );
    }
    let rho = max_stretch[1][1].ln() / max_stretch[1][0].ln();
    assert!((rho - 1.0).abs() < 1e-3, "ρ {rho}");
    for rel in worst_force_rel {
        assert!(
            rel < 0.01,
            "force off the specimen law by {rel} beyond noise"
        );
    }
    // Ends unloaded with the equibiaxial specimen mounted.
    let s = rig.state();
    assert!(s.axes[0].elongation_mm.abs() < 0.5 && s.axes[1].elongation_mm.abs() < 0.5);
    assert_eq!(
        rig.specimen().unwrap().config().loading,
        Loading::Equibiaxial
    );
}

#[test]
fn specimen_change_is_refused_while_loaded() {
    let mut rig = Rig::new(RigConfig::default(), 5).unwrap();
    let mut campaign = Campaign::parse("equibiaxial:1.5@0.1").unwrap();
    assert!(matches!(
        campaign.advance(&mut rig).unwrap(),
        CampaignEvent::Started { index: 0, .. }
    ));
    rig.advance_to(5.0);
    assert!(rig.state().axes[0].elongation_mm > 5.0);
    let refused = rig.command(RigCommand::MountSpecimen(None)).unwrap_err();
    assert!(
        refused.to_string().contains("program is running"),
        "{refused}"
    );
    rig.command(RigCommand::StopProgram { transition: None })
        .unwrap();
    rig.step();
    let refused = rig.command(RigCommand::MountSpecimen(None)).unwrap_err();
    assert!(refused.to_string().contains("unload"), "{refused}");
}
