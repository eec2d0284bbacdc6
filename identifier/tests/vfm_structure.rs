//! The virtual fields method on the specimen as a structure, noise-free: the default cruciform
//! (100 mm arms, 20 mm fillets) solved by finite elements under a known law at equibiaxial and
//! biaxial grip stretches, its deformation gradient sampled on a 1 mm grid over ±80 mm (the
//! central square, the fillets and the roots of the arms, as a camera would see it), one section
//! cut across each arm beyond the fillets, and each arm's grip force from the solution
//! (`common/cruciform.rs`).

#[path = "common/cruciform.rs"]
mod cruciform;

use cruciform::{
    observations, ramp_quadratures, relative_errors, solved_frames, worst_gap, GRID_STEP_MM,
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

/// The cruciform meshed with `element_size_mm` and its frames, solved under `model` at `truth`.
fn frames_of(
    model: &Model,
    truth: &[f64],
    element_size_mm: f64,
) -> (membrane::Mesh, Vec<cruciform::Frame>) {
    let law = InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(truth, i1, i2));
    solved_frames(&law, &STRETCHES, element_size_mm, GRID_STEP_MM)
}

/// Each virtual field's force under the true law is its arm's grip force up to the finite-
/// element solution's own discretisation error, which vanishes as the mesh is refined (the
/// equation of the virtual fields method holds for the mechanics, not only for homogeneous
/// states); the fit then gives the law back to that accuracy. Cuts see only the arms, whose
/// states barely depend on C01; the tapered ramps reach the equibiaxial centre.
///
/// Measured when written (Mooney-Rivlin, C10 0.3, C01 0.05 MPa, 1 mm grid): worst gap 3.8e-3
/// with the default 10 mm elements, 1.5e-4 with 5 mm; on 5 mm, cuts alone give C10 to 1.5e-4
/// and C01 to 1.9e-3 (condition 20.7), cuts and ramps C10 to 1.6e-4 and C01 to 5.4e-4
/// (condition 7.9). Issue 25's 1e-4 on every parameter is then a matter of the reference
/// solution's own accuracy (its gap), not of the method.
#[test]
fn virtual_fields_balance_the_grip_forces_and_the_law_comes_back() {
    let model = Model::Mooney;
    let truth = [0.3, 0.05];
    let (coarse_mesh, coarse) = frames_of(&model, &truth, 10.0);
    let (mesh, fine) = frames_of(&model, &truth, 5.0);
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
}
