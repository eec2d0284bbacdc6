//! The specimen as a structure, noise-free, as the virtual-fields tests see it: the default
//! cruciform (100 mm arms, 20 mm fillets) solved by finite elements under a known law along a
//! path of grip stretches, its deformation gradient sampled on a regular grid over ±80 mm (the
//! central square, the fillets and the roots of the arms, as a camera would see it), one section
//! cut across each arm beyond the fillets and tapered ramps through the centre, and each arm's
//! grip force from the solution.

// Each test file compiles this module and uses part of it.
#![allow(dead_code)]

use identifier::measured_displacement::DisplacementGrid;
use identifier::models::Model;
use identifier::section_cut::{ArmAxis, FieldGrid, SectionCut};
use identifier::tapered_ramp::{RampQuadrature, TaperedRamp};
use identifier::vfm::{CutObservation, VirtualField};
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::{Membrane, NewtonSettings, Probe, SheetLaw, Wrinkling};

pub const HALF_VIEW_MM: f64 = 80.0;
/// The camera's grid step, mm.
pub const GRID_STEP_MM: f64 = 1.0;
pub const THICKNESS_MM: f64 = 2.0;

/// A band 6 mm long across each arm, beyond the fillets (which end 70 mm from the centre),
/// over the arm's whole width, and the grip that pulls that arm.
pub fn cuts() -> [(SectionCut, &'static str); 4] {
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
pub fn ramps() -> Vec<(TaperedRamp, &'static str)> {
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

/// A frame: the measured field (its gradients, and its displacements on the same nodes) and
/// each arm's axial grip force (N) by grip name.
pub struct Frame {
    pub grid: FieldGrid,
    pub displacements: DisplacementGrid,
    pub forces: Vec<(&'static str, f64)>,
}

impl Frame {
    pub fn force(&self, grip: &str) -> f64 {
        self.forces.iter().find(|(g, _)| *g == grip).unwrap().1
    }
}

/// The cruciform meshed with `element_size_mm`, solved under `law` along `stretches` (each
/// solve warm-started from the previous equilibrium), its field sampled every `grid_step_mm`.
pub fn solved_frames<L: SheetLaw + ?Sized>(
    law: &L,
    stretches: &[(f64, f64)],
    element_size_mm: f64,
    grid_step_mm: f64,
) -> (membrane::Mesh, Vec<Frame>) {
    let (mesh, mut frames) = solved_frames_on(law, stretches, element_size_mm, &[grid_step_mm]);
    (mesh, frames.remove(0))
}

/// [`solved_frames`] with the same solutions sampled on grids of each of `grid_steps_mm`
/// (frames by grid, then by stretch).
pub fn solved_frames_on<L: SheetLaw + ?Sized>(
    law: &L,
    stretches: &[(f64, f64)],
    element_size_mm: f64,
    grid_steps_mm: &[f64],
) -> (membrane::Mesh, Vec<Vec<Frame>>) {
    let specimen = CruciformGeometry {
        element_size_mm,
        ..CruciformGeometry::default()
    }
    .mesh()
    .unwrap();
    let sheet = Membrane::new(
        &specimen.mesh,
        specimen.thickness_mm,
        law,
        Wrinkling::default(),
    )
    .unwrap();
    let probe = Probe::new(&specimen.mesh);
    // Each grid's size, and where each of its nodes lies in the mesh, found once for every
    // frame.
    let grids: Vec<_> = grid_steps_mm
        .iter()
        .map(|&step| {
            let n = (2.0 * HALF_VIEW_MM / step).round() as usize + 1;
            let locations: Vec<_> = (0..n * n)
                .map(|k| {
                    probe.locate([
                        -HALF_VIEW_MM + (k % n) as f64 * step,
                        -HALF_VIEW_MM + (k / n) as f64 * step,
                    ])
                })
                .collect();
            (step, n, locations)
        })
        .collect();
    let mut analysis = membrane::Analysis::default();
    let mut displacement_mm = vec![0.0; 2 * specimen.mesh.nodes_mm.len()];
    let mut frames: Vec<Vec<Frame>> = grids.iter().map(|_| vec![]).collect();
    // Two load steps a solve (halved where one fails): the path's stretches are close enough.
    let settings = NewtonSettings {
        load_steps: 2,
        ..NewtonSettings::default()
    };
    for &(x, y) in stretches {
        let clamps = specimen.clamps_at(membrane::GripStretch { x, y });
        let outcome =
            membrane::solve_from(&sheet, &clamps, &displacement_mm, settings, &mut analysis)
                .unwrap();
        if let Some(stopped) = outcome.stopped {
            panic!("grip stretches ({x}, {y}): {stopped}");
        }
        let solved = outcome.reached;
        let forces: Vec<_> = specimen
            .grips
            .iter()
            .map(|grip| {
                let f = solved.grip_force_n(&grip.nodes);
                (grip.name, f[0] * grip.axis[0] + f[1] * grip.axis[1])
            })
            .collect();
        for ((step, n, locations), frames) in grids.iter().zip(&mut frames) {
            let samples: Vec<_> = locations
                .iter()
                .map(|at| membrane::sample_at(&specimen.mesh, &solved.displacement_mm, (*at)?))
                .collect();
            let grid = FieldGrid {
                cols: *n,
                rows: *n,
                x0_mm: -HALF_VIEW_MM,
                y0_mm: -HALF_VIEW_MM,
                step_mm: *step,
                gradients: samples.iter().map(|s| s.map(|s| s.f)).collect(),
            };
            let displacements = DisplacementGrid {
                cols: *n,
                rows: *n,
                x0_mm: -HALF_VIEW_MM,
                y0_mm: -HALF_VIEW_MM,
                step_mm: *step,
                displacements_mm: samples
                    .iter()
                    .map(|s| s.map(|s| s.displacement_mm))
                    .collect(),
            };
            frames.push(Frame {
                grid,
                displacements,
                forces: forces.clone(),
            });
        }
        displacement_mm = solved.displacement_mm;
    }
    (specimen.mesh, frames)
}

/// Each frame's tapered ramps, by their quadrature over its field (`material`: the specimen's
/// outline), with the grip each balances.
pub fn ramp_quadratures(
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
pub fn observations<'a>(
    frames: &'a [Frame],
    ramps: Option<&'a [Vec<(RampQuadrature, &'static str)>]>,
) -> Vec<CutObservation<'a>> {
    let mut obs = vec![];
    for (k, frame) in frames.iter().enumerate() {
        for (cut, grip) in cuts() {
            obs.push(CutObservation {
                grid: &frame.grid,
                cut: VirtualField::Cut(cut),
                thickness_mm: THICKNESS_MM,
                force_n: frame.force(grip),
            });
        }
        for (quadrature, grip) in ramps.map_or(&[][..], |r| &r[k][..]) {
            obs.push(CutObservation {
                grid: &frame.grid,
                cut: VirtualField::Ramp(quadrature),
                thickness_mm: THICKNESS_MM,
                force_n: frame.force(grip),
            });
        }
    }
    obs
}

/// The worst relative gap between a virtual field's force under the true law and its arm's
/// grip force.
pub fn worst_gap(model: &Model, truth: &[f64], obs: &[CutObservation]) -> f64 {
    obs.iter()
        .map(|o| {
            let computed = o.cut.force_n(o.grid, model, truth, o.thickness_mm).unwrap();
            ((computed - o.force_n) / o.force_n).abs()
        })
        .fold(0.0, f64::max)
}

pub fn relative_errors(got: &[f64], truth: &[f64]) -> Vec<f64> {
    got.iter()
        .zip(truth)
        .map(|(got, want)| ((got - want) / want).abs())
        .collect()
}

/// The worst relative gap between `model`'s nominal stress at `params` and Smactane's over
/// (1, top] of each case: `tops` uniaxial, equibiaxial, pure shear (50 stretches each).
pub fn smactane_gaps(model: &Model, params: &[f64], tops: [f64; 3]) -> [f64; 3] {
    use identifier::data::LoadCase;
    let law = material::InvariantLaw::smactane();
    let cases = [
        LoadCase::Uniaxial,
        LoadCase::Equibiaxial,
        LoadCase::PureShear,
    ];
    std::array::from_fn(|k| {
        let (case, top) = (cases[k], tops[k]);
        (1..=50)
            .map(|i| {
                let stretch = 1.0 + (top - 1.0) * i as f64 / 50.0;
                let want = match case {
                    LoadCase::Uniaxial => law.uniaxial_nominal_stress_mpa(stretch),
                    LoadCase::PureShear => law.pure_shear_nominal_stress_mpa(stretch),
                    LoadCase::Equibiaxial => law.equibiaxial_nominal_stress_mpa(stretch),
                };
                let got = model.nominal_stress_mpa(params, case, stretch).unwrap();
                ((got - want) / want).abs()
            })
            .fold(0.0, f64::max)
    })
}
