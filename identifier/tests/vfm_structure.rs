//! The virtual fields method on the specimen as a structure, noise-free: the default cruciform
//! (100 mm arms, 20 mm fillets) solved by finite elements under a known law at equibiaxial and
//! biaxial grip stretches, its deformation gradient sampled on a 1 mm grid over ±80 mm (the
//! central square, the fillets and the roots of the arms, as a camera would see it), one section
//! cut across each arm beyond the fillets, and each arm's grip force from the solution.

use identifier::models::Model;
use identifier::section_cut::{ArmAxis, FieldGrid, SectionCut};
use identifier::tapered_ramp::{RampQuadrature, TaperedRamp};
use identifier::vfm::{fit, CutObservation, VirtualField};
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

/// Ramps tapered across, through the central square ([−10, 10] mm along the axis) and between
/// it and the fillets ([20, 40] mm), flat over the arm's width (±50 mm), zero from ±78 mm (the
/// other arms leave the ±80 mm field of view there), for each arm.
fn ramps() -> Vec<(TaperedRamp, &'static str)> {
    let mut ramps = vec![];
    for (from_mm, to_mm) in [(-10.0, 10.0), (20.0, 40.0)] {
        for (axis, plus, minus) in [(ArmAxis::X, "x+", "x-"), (ArmAxis::Y, "y+", "y-")] {
            for (mirrored, grip) in [(false, plus), (true, minus)] {
                ramps.push((
                    TaperedRamp {
                        axis,
                        from_mm,
                        to_mm,
                        centre_mm: 0.0,
                        flat_half_width_mm: 50.0,
                        zero_half_width_mm: 78.0,
                        mirrored,
                    },
                    grip,
                ));
            }
        }
    }
    ramps
}

/// A frame: the measured field and each arm's axial grip force (N) by grip name.
struct Frame {
    grid: FieldGrid,
    forces: Vec<(&'static str, f64)>,
}

impl Frame {
    fn force(&self, grip: &str) -> f64 {
        self.forces.iter().find(|(g, _)| *g == grip).unwrap().1
    }
}

/// The cruciform meshed with `element_size_mm` and its frames, solved under `model` at `truth`.
fn solved_frames(
    model: &Model,
    truth: &[f64],
    element_size_mm: f64,
) -> (membrane::Mesh, Vec<Frame>) {
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
    let frames = STRETCHES
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
            let forces = specimen
                .grips
                .iter()
                .map(|grip| {
                    let f = solved.grip_force_n(&grip.nodes);
                    (grip.name, f[0] * grip.axis[0] + f[1] * grip.axis[1])
                })
                .collect();
            Frame { grid, forces }
        })
        .collect();
    (specimen.mesh, frames)
}

/// Each frame's tapered ramps, by their quadrature over its field (`material`: the specimen's
/// outline), with the grip each balances.
fn ramp_quadratures(
    frames: &[Frame],
    material: &dyn Fn([f64; 2]) -> bool,
) -> Vec<Vec<(RampQuadrature, &'static str)>> {
    frames
        .iter()
        .map(|frame| {
            ramps()
                .into_iter()
                .map(|(ramp, grip)| (ramp.quadrature(&frame.grid, material).unwrap(), grip))
                .collect()
        })
        .collect()
}

/// The section cuts' equations, and the ramps' when given.
fn observations<'a>(
    frames: &'a [Frame],
    ramps: Option<&'a [Vec<(RampQuadrature, &'static str)>]>,
) -> Vec<CutObservation<'a>> {
    let mut obs = vec![];
    for (k, frame) in frames.iter().enumerate() {
        for (cut, grip) in cuts() {
            obs.push(CutObservation {
                grid: &frame.grid,
                cut: VirtualField::Cut(cut),
                thickness_mm: 2.0,
                force_n: frame.force(grip),
            });
        }
        for (quadrature, grip) in ramps.map_or(&[][..], |r| &r[k][..]) {
            obs.push(CutObservation {
                grid: &frame.grid,
                cut: VirtualField::Ramp(quadrature),
                thickness_mm: 2.0,
                force_n: frame.force(grip),
            });
        }
    }
    obs
}

/// The worst relative gap between a virtual field's force under the true law and its arm's
/// grip force.
fn worst_gap(model: &Model, truth: &[f64], obs: &[CutObservation]) -> f64 {
    obs.iter()
        .map(|o| {
            let computed = o.cut.force_n(o.grid, model, truth, o.thickness_mm).unwrap();
            ((computed - o.force_n) / o.force_n).abs()
        })
        .fold(0.0, f64::max)
}

fn relative_errors(got: &[f64], truth: &[f64]) -> Vec<f64> {
    got.iter()
        .zip(truth)
        .map(|(got, want)| ((got - want) / want).abs())
        .collect()
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
    let (coarse_mesh, coarse) = solved_frames(&model, &truth, 10.0);
    let (mesh, fine) = solved_frames(&model, &truth, 5.0);
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
