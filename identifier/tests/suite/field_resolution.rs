//! The field route at the live bench's resolution, noise-free (issue 25): the default
//! cruciform solved by finite elements under Smactane's law at equibiaxial grip stretches to
//! 1.25 (the live field route test's reach: λ1 ≈ 1.35-1.45 at the fillets, λ2 ≈ 1.08-1.10 in
//! the centre), its field on the live test's grid (16 px steps at 0.36 mm/px: 5.76 mm), fitted
//! by the field route itself (`FieldRoute`: its own virtual fields and ranking) three ways:
//! - exact: the finite-element gradient at every node on the specimen;
//! - edge lost: as the correlator loses them, no node whose ZOI (32 px: 11.52 mm) runs off the
//!   specimen (the virtual fields borrow those squares' measurement from the nearest node);
//! - ZOI: on those nodes, the gradient a first-order subset measures, the least-squares plane
//!   through the displacement over the ZOI (9 x 9 points).
//!
//! What it shows: the grid and the ZOI alone do not make the route prefer Hart-Smith (which
//! ranked first in half of the live runs, `tests/field_route.rs`); the edge's loss cost
//! Mooney-Rivlin's fit its equibiaxial accuracy while the central ramps' ∇u* reached the
//! fillets, and costs it under 1 % once their taper clears them.

use crate::cruciform::{smactane_gaps, THICKNESS_MM};
use identifier::field_layout::{ArmLayout, GRIPS};
use identifier::field_route::{FieldFits, FieldRoute, FieldRouteConfig};
use identifier::field_stress::Mat2;
use identifier::models::Model;
use identifier::online::OnlineConfig;
use identifier::section_cut::FieldGrid;
use material::InvariantLaw;
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::{Membrane, NewtonSettings, Probe, Wrinkling};

/// The live test's view (`tests/field_route.rs`: 512 px at 0.36 mm/px).
const HALF_VIEW_MM: f64 = 92.0;
const STEP_MM: f64 = 5.76;
const ZOI_MM: f64 = 11.52;
/// Points per side of the ZOI's lattice.
const ZOI_POINTS: usize = 9;

/// The ways the field is measured, in the order `measure` returns them.
const WAYS: [&str; 3] = ["exact", "edge lost", "ZOI"];

/// Each way's fits over grip stretches 1.025 to 1.25.
fn fits_by_way() -> Vec<FieldFits> {
    let law = InvariantLaw::smactane();
    let specimen = CruciformGeometry::default().mesh().unwrap();
    let sheet = Membrane::new(
        &specimen.mesh,
        specimen.thickness_mm,
        &law,
        Wrinkling::default(),
    )
    .unwrap();
    let probe = Probe::new(&specimen.mesh);
    let n = (2.0 * HALF_VIEW_MM / STEP_MM).round() as usize + 1;
    let node_mm = |k: usize| {
        [
            -HALF_VIEW_MM + (k % n) as f64 * STEP_MM,
            -HALF_VIEW_MM + (k / n) as f64 * STEP_MM,
        ]
    };
    let lattice = |i: usize| ZOI_MM * (i as f64 / (ZOI_POINTS - 1) as f64 - 0.5);
    let offsets: Vec<[f64; 2]> = (0..ZOI_POINTS * ZOI_POINTS)
        .map(|k| [lattice(k % ZOI_POINTS), lattice(k / ZOI_POINTS)])
        .collect();
    let nodes: Vec<_> = (0..n * n).map(|k| probe.locate(node_mm(k))).collect();
    // A ZOI with a point off the specimen is lost (None).
    let zois: Vec<Option<Vec<_>>> = (0..n * n)
        .map(|k| {
            let c = node_mm(k);
            offsets
                .iter()
                .map(|o| probe.locate([c[0] + o[0], c[1] + o[1]]))
                .collect()
        })
        .collect();
    let config = FieldRouteConfig {
        layout: ArmLayout {
            arm_width_mm: 100.0,
            fillet_radius_mm: 20.0,
        },
        thickness_mm: THICKNESS_MM,
        models: OnlineConfig::default().models,
        min_level_increment: 1e-3,
        max_frames: 64,
        min_frames_to_fit: 2,
        central_ramps: true,
    };
    let mut routes: Vec<_> = WAYS
        .iter()
        .map(|_| FieldRoute::new(config.clone()))
        .collect();
    let material = |x: [f64; 2]| probe.locate(x).is_some();
    let mut analysis = membrane::Analysis::default();
    let mut displacement_mm = vec![0.0; 2 * specimen.mesh.nodes_mm.len()];
    let settings = NewtonSettings {
        load_steps: 2,
        ..NewtonSettings::default()
    };
    for step in 1..=10 {
        let stretch = 1.0 + 0.025 * step as f64;
        let clamps = specimen.clamps_at(membrane::GripStretch {
            x: stretch,
            y: stretch,
        });
        let solved =
            membrane::solve_from(&sheet, &clamps, &displacement_mm, settings, &mut analysis)
                .unwrap()
                .reached;
        let mut forces_n = [0.0; 4];
        for grip in &specimen.grips {
            let f = solved.grip_force_n(&grip.nodes);
            let k = GRIPS.iter().position(|g| *g == grip.name).unwrap();
            forces_n[k] = f[0] * grip.axis[0] + f[1] * grip.axis[1];
        }
        let sample = |at| membrane::sample_at(&specimen.mesh, &solved.displacement_mm, at);
        let exact: Vec<Option<Mat2>> = nodes.iter().map(|l| Some(sample((*l)?)?.f)).collect();
        let edge_lost: Vec<_> = exact
            .iter()
            .zip(&zois)
            .map(|(f, zoi)| zoi.as_ref().and(*f))
            .collect();
        let zoi: Vec<_> = zois
            .iter()
            .map(|zoi| subset_gradient(zoi.as_ref()?, &offsets, &sample))
            .collect();
        for (route, gradients) in routes.iter_mut().zip([exact, edge_lost, zoi]) {
            let grid = FieldGrid {
                cols: n,
                rows: n,
                x0_mm: -HALF_VIEW_MM,
                y0_mm: -HALF_VIEW_MM,
                step_mm: STEP_MM,
                gradients,
            };
            route
                .push(step, Some(grid), Some(forces_n), stretch - 1.0, &material)
                .unwrap();
        }
        displacement_mm = solved.displacement_mm;
    }
    routes.iter().map(|r| r.fit().unwrap()).collect()
}

/// The least-squares plane u = a + G (X − c) through the displacements at the ZOI's points
/// (a lattice symmetric about c: G = Σ u oᵀ / Σ o_x²), as I + G.
fn subset_gradient(
    locations: &[membrane::Location],
    offsets: &[[f64; 2]],
    sample: &dyn Fn(membrane::Location) -> Option<membrane::PointSample>,
) -> Option<Mat2> {
    let (mut g, mut sum_sq) = ([[0.0; 2]; 2], 0.0);
    for (at, o) in locations.iter().zip(offsets) {
        let u = sample(*at)?.displacement_mm;
        for (row, u_a) in g.iter_mut().zip(u) {
            row[0] += u_a * o[0];
            row[1] += u_a * o[1];
        }
        sum_sq += o[0] * o[0];
    }
    Some([
        [1.0 + g[0][0] / sum_sq, g[0][1] / sum_sq],
        [g[1][0] / sum_sq, 1.0 + g[1][1] / sum_sq],
    ])
}

/// Measured when written (BIC, and Mooney-Rivlin's worst gaps uniaxial / equibiaxial / pure
/// shear) on the ±80 mm view: exact, reach λ1 1.70, Mooney-Rivlin −165 against Hart-Smith −118,
/// gaps 3.2 / 0.19 / 1.8 %; edge lost, λ1 1.45, −173 against −97, 1.6 / 1.9 / 2.3 %; ZOI, λ1
/// 1.46, −205 against −108, 1.3 / 2.3 / 2.1 %. Filling the lost nodes by a plane through their
/// measured neighbours instead of borrowing the nearest changed nothing (2.0 and 2.4 %
/// equibiaxial). On the live test's ±92 mm view, with the central ramps tapered from the
/// square's edge: exact 0.59 / 0.29 / 1.2 %, edge lost 0.47 / 1.5 / 1.2 %, ZOI 1.4 / 1.7 /
/// 0.99 %; tapered beyond the fillets (`field_layout::place_fields`, the lost band along the
/// fillets out of the integrals): exact 0.60 / 0.53 / 0.93 %, edge lost 0.51 / 0.56 / 0.52 %,
/// ZOI 0.78 / 0.74 / 0.74 %, Mooney-Rivlin's BIC −94, −86, −92 against Hart-Smith's −24, −12,
/// −21.
#[test]
fn at_the_live_resolution_mooney_rivlin_ranks_above_hart_smith_and_fits_within_1_2_percent() {
    for (way, fits) in WAYS.iter().zip(fits_by_way()) {
        let of = |model: Model| {
            let found = fits.fits.iter().find(|f| f.model == model);
            found.unwrap_or_else(|| panic!("{way}: {model} not fitted {:?}", fits.refused))
        };
        let (mooney, hart_smith) = (of(Model::Mooney), of(Model::HartSmith));
        let reach = fits.reach.max_stretches;
        // Uniaxial and pure shear to the largest major stretch, equibiaxial to the minor one.
        let gaps = smactane_gaps(
            &mooney.model,
            &mooney.fit.params,
            [reach[0], reach[1], reach[0]],
        );
        println!(
            "{way}: reach {:.3?}; BIC Mooney-Rivlin {:.1}, Hart-Smith {:.1}; Mooney-Rivlin's \
             worst gaps (uniaxial, equibiaxial, pure shear) {gaps:.4?}",
            fits.reach.max_stretches, mooney.bic, hart_smith.bic
        );
        assert!(mooney.ranked() && hart_smith.ranked(), "{way}");
        // Noise-free, the forces tell the two apart by far more than any noise could blur.
        assert!(mooney.bic < hart_smith.bic - 20.0, "{way}");
        // Within 1.2 % every way: the lost edge band costs nothing where ∇u* vanishes on it
        // (1.7 % equibiaxial when the central ramps tapered along the fillets).
        assert!(gaps.iter().all(|&g| g < 0.012), "{way}: {gaps:?}");
    }
}
