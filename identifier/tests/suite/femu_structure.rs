//! Finite-element model updating (FEMU) on the specimen as a structure, noise-free, against
//! the virtual fields method on the same data: the default cruciform (100 mm arms, 20 mm
//! fillets, 5 mm elements) solved under a known law at four grip stretches, its displacements
//! and gradients sampled on a 1 mm grid over ±80 mm (`common/cruciform.rs`), each arm's grip
//! force from the solution. FEMU's own model is another mesh: the cruciform clipped one step
//! inside the view (±79 mm), its edges at the measured displacements.

use crate::cruciform;

use cruciform::{
    observations, ramp_quadratures, relative_errors, solved_frames, Frame, GRID_STEP_MM,
};
use identifier::femu::{Femu, FemuError, FemuFrame, FemuSettings};
use identifier::field_layout::GRIPS;
use identifier::models::Model;
use identifier::vfm;
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::{InvariantDerivatives, NewtonSettings, Probe};

/// Equibiaxial, then biaxial both ways: the centre's equibiaxial states and the arms' others.
const STRETCHES: [(f64, f64); 4] = [(1.1, 1.1), (1.25, 1.25), (1.35, 1.2), (1.2, 1.35)];
const ELEMENT_SIZE_MM: f64 = 5.0;

fn settings() -> FemuSettings {
    FemuSettings {
        cruciform: CruciformGeometry {
            element_size_mm: ELEMENT_SIZE_MM,
            ..CruciformGeometry::default()
        },
        force_sigma_n: FemuSettings::DEFAULT_FORCE_SIGMA_N,
        // 0.02 px at 0.36 mm/px.
        displacement_sigma_mm: 0.0072,
        newton: NewtonSettings::default(),
    }
}

fn femu_frames(frames: &[Frame]) -> Vec<FemuFrame> {
    frames
        .iter()
        .enumerate()
        .map(|(k, frame)| FemuFrame {
            frame_id: 10 * (k as u64 + 1),
            field: frame.displacements.clone(),
            forces_n: GRIPS.map(|g| frame.force(g)),
        })
        .collect()
}

/// FEMU gives the true law back from a start 30 % and 40 % off, and the virtual fields method's
/// law on the same data within its own accuracy (1e-3, `vfm_structure.rs`).
///
/// Measured when written (Mooney-Rivlin, C10 0.3, C01 0.05 MPa): see the printed line and the
/// note in ARCHITECTURE.md's identifier paragraph.
#[test]
fn femu_gives_the_law_back_and_agrees_with_the_virtual_fields_method() {
    let model = Model::Mooney;
    let truth = [0.3, 0.05];
    let law = InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(&truth, i1, i2));
    let (mesh, frames) = solved_frames(&law, &STRETCHES, ELEMENT_SIZE_MM, GRID_STEP_MM);
    let probe = Probe::new(&mesh);
    let ramps = ramp_quadratures(&frames, &|x| probe.locate(x).is_some());
    let by_vfm = vfm::fit(&model, &observations(&frames, Some(&ramps)), &[0.0, 0.0]).unwrap();
    let femu = Femu::new(&femu_frames(&frames), settings()).unwrap();
    let by_femu = femu.fit(&model, &[0.39, 0.03]).unwrap();
    let (vfm_errors, femu_errors) = (
        relative_errors(&by_vfm.params, &truth),
        relative_errors(&by_femu.params, &truth),
    );
    let between = relative_errors(&by_femu.params, &by_vfm.params);
    println!(
        "FEMU: {:?} ± {:?}, relative errors {femu_errors:?}, rms force {:.3e} N, rms \
         displacement {:.3e} mm, {} + {} residuals, condition {:.1}, {} iterations, {} \
         evaluations; VFM: {:?}, relative errors {vfm_errors:?}; FEMU against VFM {between:?}",
        by_femu.params,
        by_femu.sigma,
        by_femu.rms_force_n,
        by_femu.rms_displacement_mm,
        by_femu.force_residuals,
        by_femu.displacement_residuals,
        by_femu.condition,
        by_femu.iterations,
        by_femu.evaluations,
        by_vfm.params
    );
    assert!(femu_errors.iter().all(|&e| e < 1e-3), "{femu_errors:?}");
    assert!(between.iter().all(|&e| e < 1e-3), "{between:?}");
    assert_eq!(by_femu.frames, STRETCHES.len());
    assert_eq!(by_femu.force_residuals, 4 * STRETCHES.len());
    assert!(by_femu.displacement_residuals > 2 * 10_000 * STRETCHES.len());
    // Every grip's computed force balances its measured one.
    for b in &by_femu.balance {
        let gap = (b.computed_n - b.measured_n).abs() / b.measured_n;
        assert!(gap < 2e-3, "{b:?}");
    }
    assert!(by_femu.sigma.iter().all(|s| s.is_finite() && *s > 0.0));
}

/// Bad input: a view that crosses no arm, an edge without valid nodes around it, fields of
/// different nodes, a law whose solve fails (at which frame said), noise levels that are not.
#[test]
fn bad_input_is_named() {
    let model = Model::Mooney;
    let truth = [0.3, 0.05];
    let law = InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(&truth, i1, i2));
    let coarse = CruciformGeometry::default().element_size_mm;
    let (_, frames) = solved_frames(&law, &STRETCHES[..2], coarse, 2.0);
    let frames = femu_frames(&frames);
    let coarse_settings = FemuSettings {
        cruciform: CruciformGeometry::default(),
        ..settings()
    };
    // The central ±40 mm only.
    let mut central = frames.clone();
    for f in &mut central {
        let keep = |k: usize| {
            let p = f.field.node_mm(k);
            p[0].abs() <= 40.0 && p[1].abs() <= 40.0
        };
        let n = (80.0 / f.field.step_mm) as usize + 1;
        let first = f.field.displacements_mm.iter().enumerate();
        let inside: Vec<_> = first.filter(|(k, _)| keep(*k)).map(|(_, u)| *u).collect();
        f.field.displacements_mm = inside;
        (f.field.cols, f.field.rows) = (n, n);
        (f.field.x0_mm, f.field.y0_mm) = (-40.0, -40.0);
    }
    let error = Femu::new(&central, coarse_settings.clone()).err().unwrap();
    assert!(matches!(error, FemuError::NoArmInView { .. }), "{error}");
    assert!(error.to_string().contains("crosses no arm"), "{error}");
    // The second frame lost its nodes near the x+ edge (x ≥ 72 mm).
    let mut lost = frames.clone();
    for k in 0..lost[1].field.displacements_mm.len() {
        if lost[1].field.node_mm(k)[0] >= 72.0 {
            lost[1].field.displacements_mm[k] = None;
        }
    }
    let error = Femu::new(&lost, coarse_settings.clone()).err().unwrap();
    assert!(
        matches!(
            error,
            FemuError::TooFewBoundaryNodes {
                frame_id: 20,
                arm: "x+",
                ..
            }
        ),
        "{error}"
    );
    assert!(
        error.to_string().contains("too few valid boundary nodes"),
        "{error}"
    );
    // Another grid.
    let mut moved = frames.clone();
    moved[1].field.x0_mm += 0.5;
    let error = Femu::new(&moved, coarse_settings.clone()).err().unwrap();
    assert_eq!(error, FemuError::GridsDiffer { frame_id: 20 });
    // Gent with a chain limit of I1 − 3 = 0.4: the first frame (equibiaxial 1.1, I1 − 3 about
    // 0.1) solves, the second (1.25, about 0.5) leaves the law's domain.
    let femu = Femu::new(&frames, coarse_settings.clone()).unwrap();
    let error = femu.fit(&Model::Gent, &[0.7, 0.4]).unwrap_err();
    let text = error.to_string();
    assert!(
        matches!(error, FemuError::Solve { frame_id: 20, .. }),
        "{text}"
    );
    assert!(
        text.contains("frame 20: the finite-element solve with gent"),
        "{text}"
    );
    let error = Femu::new(
        &frames,
        FemuSettings {
            force_sigma_n: 0.0,
            ..coarse_settings
        },
    )
    .err()
    .unwrap();
    assert!(error.to_string().contains("force σ (N) = 0"), "{error}");
}
