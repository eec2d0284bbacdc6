//! The virtual fields method on the specimen as a structure, noise-free: the default cruciform
//! (100 mm arms, 20 mm fillets) solved by finite elements under a known law at equibiaxial and
//! biaxial grip stretches, its deformation gradient sampled on a 1 mm grid over ±80 mm (the
//! central square, the fillets and the roots of the arms, as a camera would see it), one section
//! cut across each arm beyond the fillets, and each arm's grip force from the solution
//! (`common/cruciform.rs`).

use crate::cruciform;

use cruciform::{
    observations, ramp_quadratures, relative_errors, solved_frames_on, worst_gap, GRID_STEP_MM,
};
use identifier::models::Model;
use identifier::vfm::fit;
use membrane::{InvariantDerivatives, Probe};

/// The grip stretches of the test: equibiaxial, then biaxial (the arms reach other states).
const STRETCHES: [(f64, f64); 6] = [
    (1.1, 1.1),
    (1.2, 1.2),
    (1.35, 1.35),
    (1.5, 1.5),
    (1.4, 1.1),
    (1.15, 1.45),
];

/// The cruciform meshed with `element_size_mm` and its frames on grids of `grid_steps_mm`,
/// solved under `model` at `truth`.
fn frames_of(
    model: &Model,
    truth: &[f64],
    element_size_mm: f64,
    grid_steps_mm: &[f64],
) -> (membrane::Mesh, Vec<Vec<cruciform::Frame>>) {
    let law = InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(truth, i1, i2));
    solved_frames_on(&law, &STRETCHES, element_size_mm, grid_steps_mm)
}

/// The finer camera grid of the recovery's convergence, mm.
const HALF_GRID_STEP_MM: f64 = 0.5 * GRID_STEP_MM;

/// Each virtual field's force under the true law is its arm's grip force up to the finite-
/// element solution's own discretisation error, which vanishes as the mesh is refined (the
/// equation of the virtual fields method holds for the mechanics, not only for homogeneous
/// states); the fit then gives the law back to that accuracy. Cuts see only the arms, whose
/// states barely depend on C01; the tapered ramps reach the equibiaxial centre.
///
/// Measured when written (Mooney-Rivlin, C10 0.3, C01 0.05 MPa, 1 mm grid): worst gap 3.8e-3
/// with the default 10 mm elements, 1.5e-4 with 5 mm; on 5 mm, cuts alone give C10 to 1.5e-4
/// and C01 to 1.9e-3 (condition 20.7), cuts and ramps C10 to 1.6e-4 and C01 to 5.4e-4
/// (condition 7.9).
///
/// Issue 25's 1e-4 on every parameter, noise-free: signed relative errors of cuts and ramps
/// (C10, C01) and the worst gap, by element size (mm) and camera grid step (mm), measured with
/// this file's frames (`solved_frames_on`; 12-93 s a row when measured, the rows other than
/// 10 and 5 mm by a scratch run):
///
/// | elements | grid | C10 | C01 | worst gap |
/// |---|---|---|---|---|
/// | 10 | 1 | +3.3e-3 | −1.4e-2 | 3.8e-3 |
/// | 10 | 0.5 | +3.2e-3 | −1.3e-2 | 3.9e-3 |
/// | 7.07 | 1 | +1.3e-4 | −2.4e-4 | 2.8e-4 |
/// | 7.07 | 0.5 | +2.2e-4 | −6.5e-4 | 3.3e-4 |
/// | 5 | 1 | +1.6e-4 | −5.4e-4 | 1.5e-4 |
/// | 5 | 0.5 | +9.6e-5 | −5.0e-4 | 7.8e-5 |
/// | 5 | 0.25 | +7.5e-5 | −5.8e-4 | 8.9e-5 |
/// | 3.54 | 1 | −5.8e-5 | +8.0e-4 | 1.3e-4 |
/// | 3.54 | 0.5 | +9.9e-6 | +2.5e-4 | 7.1e-5 |
/// | 3.54 | 0.25 | +4.9e-5 | −2.1e-4 | 4.6e-5 |
/// | 2.5 | 0.5 | −6.9e-5 | +6.5e-4 | 7.4e-5 |
/// | 2.5 | 0.25 | −8.7e-6 | +5.7e-5 | 9.6e-6 |
///
/// Only the last row reaches 1e-4 on both parameters
/// (`the_law_comes_back_to_1e_4_on_a_fine_mesh_and_grid`, ignored in CI: 61 s). Below 10 mm
/// the errors are in no asymptotic regime: C01 changes sign with the mesh and with the grid,
/// so Richardson extrapolation across two meshes has no order to use. Refining one of mesh and grid alone stalls (5 mm: the gap 1.5e-4, 7.8e-5, 8.9e-5 on
/// 1, 0.5, 0.25 mm grids; 0.5 mm grid: 7.8e-5, 7.1e-5, 7.4e-5 on 5, 3.54, 2.5 mm elements): the
/// grid's node-square quadrature (and the ramps' edge squares, whose material takes its nearest
/// node's stress, where the fillets' curved edges cross their taper) integrates a field that is
/// smooth only within each element, and both must shrink together. C01, which only the ramps
/// through the centre tell apart (condition 7.9), multiplies the gap by about 3 to 10. Asserted
/// here on 5 mm: the half grid halves the worst gap and gives C10 within 1e-4 (C01 within 1e-3,
/// as on the 1 mm grid).
#[test]
fn virtual_fields_balance_the_grip_forces_and_the_law_comes_back() {
    let model = Model::Mooney;
    let truth = [0.3, 0.05];
    let (coarse_mesh, mut coarse) = frames_of(&model, &truth, 10.0, &[GRID_STEP_MM]);
    let coarse = coarse.remove(0);
    let (mesh, mut fine) = frames_of(&model, &truth, 5.0, &[GRID_STEP_MM, HALF_GRID_STEP_MM]);
    let (fine, half_step) = (fine.remove(0), fine.remove(0));
    let (coarse_probe, probe) = (Probe::new(&coarse_mesh), Probe::new(&mesh));
    let coarse_ramps = ramp_quadratures(&coarse, &|x| coarse_probe.locate(x).is_some());
    let fine_ramps = ramp_quadratures(&fine, &|x| probe.locate(x).is_some());
    let coarse_gap = worst_gap(&model, &truth, &observations(&coarse, Some(&coarse_ramps)));
    let cuts_only = observations(&fine, None);
    let all = observations(&fine, Some(&fine_ramps));
    let fine_gap = worst_gap(&model, &truth, &all);
    let by_cuts = fit(&model, &cuts_only, &[0.0, 0.0]).unwrap();
    let by_all = fit(&model, &all, &[0.0, 0.0]).unwrap();
    let (cut_errors, all_errors) = (
        relative_errors(&by_cuts.params, &truth),
        relative_errors(&by_all.params, &truth),
    );
    println!(
        "{model}: worst force gap {coarse_gap:.2e} (10 mm elements), {fine_gap:.2e} (5 mm); on \
         5 mm, cuts alone: relative errors {cut_errors:?}, condition {:.1}; cuts and ramps: \
         {all_errors:?}, condition {:.1}, {} equations",
        by_cuts.condition, by_all.condition, by_all.equations
    );
    assert!(coarse_gap < 5e-3, "{coarse_gap}");
    assert!(
        fine_gap < coarse_gap / 8.0,
        "{fine_gap} against {coarse_gap}"
    );
    assert!(all_errors.iter().all(|&e| e < 1e-3), "{all_errors:?}");
    // The ramps reach the states that tell C01 apart.
    assert!(
        all_errors[1] < cut_errors[1] / 2.0,
        "{all_errors:?} against {cut_errors:?}"
    );
    assert!(by_all.condition < by_cuts.condition / 2.0);
    // Issue 25's 1e-4: on 5 mm elements, the 0.5 mm grid halves the worst gap (the ramps'
    // quadrature of the fillets' edges, first order in the grid step) and C10 comes within
    // 1e-4; C01 does not, on any mesh and grid tried (the table above).
    let half_ramps = ramp_quadratures(&half_step, &|x| probe.locate(x).is_some());
    let half = observations(&half_step, Some(&half_ramps));
    let half_gap = worst_gap(&model, &truth, &half);
    let by_half = fit(&model, &half, &[0.0, 0.0]).unwrap();
    let half_errors = relative_errors(&by_half.params, &truth);
    println!(
        "on 5 mm, {HALF_GRID_STEP_MM} mm grid: worst force gap {half_gap:.2e}, relative errors \
         {half_errors:?}"
    );
    assert!(half_gap < 0.6 * fine_gap, "{half_gap} against {fine_gap}");
    assert!(half_errors[0] < 1e-4, "{half_errors:?}");
    assert!(
        half_errors[1] < all_errors[1],
        "{half_errors:?} {all_errors:?}"
    );
}

/// Issue 25's target, noise-free: the law back to 1e-4 relative on every parameter, with 2.5 mm
/// elements and a 0.25 mm grid (measured when written: C10 −8.7e-6, C01 +5.7e-5, worst gap
/// 9.6e-6; the table above). 61 s in release: run with `--ignored`.
#[test]
#[ignore = "61 s in release: the fine mesh and grid of issue 25's 1e-4"]
fn the_law_comes_back_to_1e_4_on_a_fine_mesh_and_grid() {
    let model = Model::Mooney;
    let truth = [0.3, 0.05];
    let (mesh, mut frames) = frames_of(&model, &truth, 2.5, &[0.25 * GRID_STEP_MM]);
    let frames = frames.remove(0);
    let probe = Probe::new(&mesh);
    let ramps = ramp_quadratures(&frames, &|x| probe.locate(x).is_some());
    let all = observations(&frames, Some(&ramps));
    let gap = worst_gap(&model, &truth, &all);
    let by_all = fit(&model, &all, &[0.0, 0.0]).unwrap();
    let errors = relative_errors(&by_all.params, &truth);
    println!(
        "2.5 mm elements, 0.25 mm grid: worst force gap {gap:.2e}, relative errors {errors:?}"
    );
    assert!(errors.iter().all(|&e| e < 1e-4), "{errors:?}");
}
