//! The virtual fields method on the specimen as a structure, noise-free: the default cruciform
//! (100 mm arms, 20 mm fillets) solved by finite elements under a known law at equibiaxial and
//! biaxial grip stretches, its deformation gradient sampled on a 1 mm grid over ±80 mm (the
//! central square, the fillets and the roots of the arms, as a camera would see it), one section
//! cut across each arm beyond the fillets, and each arm's grip force from the solution.

use identifier::models::Model;
use identifier::section_cut::{cut_force, ArmAxis, FieldGrid, SectionCut};
use identifier::vfm::{fit, CutObservation};
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::{InvariantDerivatives, Membrane, NewtonSettings, Probe, Wrinkling};

const HALF_VIEW_MM: f64 = 80.0;
const GRID_STEP_MM: f64 = 1.0;

/// The grip stretches of the test: equibiaxial, then biaxial (the arms reach other states).
const STRETCHES: [(f64, f64); 6] = [
    (1.1, 1.1),
    (1.2, 1.2),
    (1.35, 1.35),
    (1.5, 1.5),
    (1.4, 1.1),
    (1.15, 1.45),
];

/// A band 6 mm long across each arm, beyond the fillets (which end 70 mm from the centre),
/// over the arm's whole width, and the grip that pulls that arm.
fn cuts() -> [(SectionCut, &'static str); 4] {
    let cut = |axis, from_mm, to_mm| SectionCut {
        axis,
        from_mm,
        to_mm,
        across_from_mm: -50.0,
        across_to_mm: 50.0,
    };
    [
        (cut(ArmAxis::X, 72.0, 78.0), "x+"),
        (cut(ArmAxis::X, -78.0, -72.0), "x-"),
        (cut(ArmAxis::Y, 72.0, 78.0), "y+"),
        (cut(ArmAxis::Y, -78.0, -72.0), "y-"),
    ]
}

/// The frames' fields and each arm's axial grip force (N), solved under `model` at `truth`.
fn solved_frames(model: &Model, truth: &[f64], element_size_mm: f64) -> Vec<(FieldGrid, [f64; 4])> {
    let specimen = CruciformGeometry {
        element_size_mm,
        ..CruciformGeometry::default()
    }
    .mesh()
    .unwrap();
    let law = InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(truth, i1, i2));
    let sheet = Membrane::new(
        &specimen.mesh,
        specimen.thickness_mm,
        &law,
        Wrinkling::default(),
    )
    .unwrap();
    let probe = Probe::new(&specimen.mesh);
    let n = (2.0 * HALF_VIEW_MM / GRID_STEP_MM).round() as usize + 1;
    STRETCHES
        .iter()
        .map(|&(x, y)| {
            let clamps = specimen.clamps_at(membrane::GripStretch { x, y });
            let solved = membrane::solve(&sheet, &clamps, NewtonSettings::default()).unwrap();
            let gradients = (0..n * n)
                .map(|k| {
                    let point = [
                        -HALF_VIEW_MM + (k % n) as f64 * GRID_STEP_MM,
                        -HALF_VIEW_MM + (k / n) as f64 * GRID_STEP_MM,
                    ];
                    probe.sample(&solved.displacement_mm, point).map(|s| s.f)
                })
                .collect();
            let grid = FieldGrid {
                cols: n,
                rows: n,
                x0_mm: -HALF_VIEW_MM,
                y0_mm: -HALF_VIEW_MM,
                step_mm: GRID_STEP_MM,
                gradients,
            };
            let forces = cuts().map(|(_, name)| {
                let grip = specimen.grip(name).unwrap();
                let f = solved.grip_force_n(&grip.nodes);
                f[0] * grip.axis[0] + f[1] * grip.axis[1]
            });
            (grid, forces)
        })
        .collect()
}

fn observations(frames: &[(FieldGrid, [f64; 4])]) -> Vec<CutObservation<'_>> {
    frames
        .iter()
        .flat_map(|(grid, forces)| {
            cuts()
                .into_iter()
                .zip(forces)
                .map(move |((cut, _), &force_n)| CutObservation {
                    grid,
                    cut,
                    thickness_mm: 2.0,
                    force_n,
                })
        })
        .collect()
}

/// The worst relative gap between a cut's force under the true law and its arm's grip force.
fn worst_gap(model: &Model, truth: &[f64], obs: &[CutObservation]) -> f64 {
    obs.iter()
        .map(|o| {
            let computed = cut_force(o.grid, &o.cut, model, truth, o.thickness_mm)
                .unwrap()
                .force_n;
            ((computed - o.force_n) / o.force_n).abs()
        })
        .fold(0.0, f64::max)
}

/// Each cut's force under the true law is its arm's grip force up to the finite-element
/// solution's own discretisation error, which vanishes as the mesh is refined (the equation of
/// the virtual fields method holds for the mechanics, not only for homogeneous states); the fit
/// then gives the law back to that accuracy.
///
/// Measured when written (Mooney-Rivlin, C10 0.3, C01 0.05 MPa): gap 3.8e-3 with the default
/// 10 mm elements, 1.5e-4 with 5 mm (1.9e-3 relative on C01, 1.5e-4 on C10), 5.2e-5 with 2.5 mm
/// (C01 still 1.2e-3: an arm's state barely depends on C01, and cuts see only the arms). Issue
/// 25's 1e-4 on every parameter needs virtual fields that reach the equibiaxial centre, not
/// cuts alone.
#[test]
fn cut_forces_are_the_grip_forces_and_the_law_comes_back() {
    let model = Model::Mooney;
    let truth = [0.3, 0.05];
    let coarse = solved_frames(&model, &truth, 10.0);
    let fine = solved_frames(&model, &truth, 5.0);
    let (coarse_obs, fine_obs) = (observations(&coarse), observations(&fine));
    let (coarse_gap, fine_gap) = (
        worst_gap(&model, &truth, &coarse_obs),
        worst_gap(&model, &truth, &fine_obs),
    );
    let fit = fit(&model, &fine_obs, &[0.0, 0.0]).unwrap();
    let errors: Vec<f64> = fit
        .params
        .iter()
        .zip(&truth)
        .map(|(got, want)| ((got - want) / want).abs())
        .collect();
    println!(
        "{model}: worst cut force gap {coarse_gap:.2e} (10 mm elements), {fine_gap:.2e} (5 mm); \
         identified on 5 mm {:?} against {truth:?} (relative errors {errors:?}), force rms \
         {:.2e} N, condition {:.1}, {} equations",
        fit.params, fit.rms_n, fit.condition, fit.equations
    );
    assert!(coarse_gap < 5e-3, "{coarse_gap}");
    assert!(
        fine_gap < coarse_gap / 8.0,
        "{fine_gap} against {coarse_gap}"
    );
    assert!(errors[0] < 1e-3 && errors[1] < 5e-3, "{errors:?}");
}
