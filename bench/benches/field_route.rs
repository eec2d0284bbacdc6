//! The field route's cost on line (issue 25's cost target): the identifier's work for one field
//! of 64 × 64 nodes of the default cruciform, against the correlator's work for a field of the
//! same 64 × 64 nodes on one thread, in the same run. The identifier's work per field is
//! `FieldFeed::offer` (the level, the virtual fields placed on the grid, their quadrature over
//! the specimen's outline and the stresses' equations compiled for every model); the refit of
//! all kept frames runs on a thread of its own between fields, and is timed too.
//!
//! The fields are the finite-element solution's (`membrane::solve_path`, Mooney-Rivlin C10 0.3,
//! C01 0.05 MPa, equibiaxial grip stretches to 1.3), sampled at the nodes a camera of the run's
//! view would have (1040 px square over ±80 mm, ZOI 32 px, step 16 px: 64 × 64 nodes); the
//! correlator's field is a rendered speckle pair of that size, with the default method.
//!
//! Run: `cargo bench -p bench --bench field_route` (options: `-- --frames N --runs N`).

use bench::{arg_value, median, ms};
use std::time::{Duration, Instant};

use correlator::{Correlator, CorrelatorSettings, Region, Roi};
use identifier::field_layout::GRIPS;
use identifier::models::Model;
use identifier::online::OnlineConfig;
use identifier::process::{FieldFeed, FieldRouteSettings};
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::{ElementGrid, GripStretch, InvariantDerivatives, Membrane, NewtonSettings};
use producer::motion::{Affine, Motion};
use producer::{CameraModel, FastRenderer, Speckle, SpeckleParams, View};

const SIDE_PX: u32 = 1040;
const VIEW_MM: f64 = 160.0;
const ZOI_PX: usize = 32;
const STEP_PX: usize = 16;
const NODES: usize = 64;
const TRUTH: [f64; 2] = [0.3, 0.05];
const LAST_STRETCH: f64 = 1.3;

/// One field as the identifier receives it: each node's F (None off the specimen), and each
/// grip's axial force in [`GRIPS`] order.
struct SolvedField {
    gradients: Vec<Option<[[f64; 2]; 2]>>,
    forces_n: [f64; 4],
}

/// The cruciform solved at `frames` equibiaxial grip stretches up to [`LAST_STRETCH`], its F
/// at the camera's 64 × 64 nodes.
fn solved_fields(frames: usize, view: &View) -> Vec<SolvedField> {
    let geometry = CruciformGeometry::default();
    let specimen = geometry.mesh().expect("the default cruciform meshes");
    let law =
        InvariantDerivatives(|i1, i2| Model::Mooney.invariant_derivatives_mpa(&TRUTH, i1, i2));
    let sheet = Membrane::new(
        &specimen.mesh,
        specimen.thickness_mm,
        &law,
        membrane::Wrinkling::default(),
    )
    .expect("the membrane");
    let target = GripStretch {
        x: LAST_STRETCH,
        y: LAST_STRETCH,
    };
    let path = membrane::solve_path(&sheet, &specimen, target, frames, NewtonSettings::default());
    if let Some(stop) = path.stopped {
        panic!("the cruciform's path stopped: {stop}");
    }
    let elements = ElementGrid::new(&specimen.mesh);
    let locations: Vec<_> = (0..NODES * NODES)
        .map(|k| {
            let node_px = [
                (ZOI_PX / 2 + STEP_PX * (k % NODES)) as f64,
                (ZOI_PX / 2 + STEP_PX * (k / NODES)) as f64,
            ];
            elements.locate(&specimen.mesh, view.to_mm(node_px))
        })
        .collect();
    path.states
        .iter()
        .map(|state| {
            let u = &state.equilibrium.displacement_mm;
            let gradients = locations
                .iter()
                .map(|at| membrane::sample_at(&specimen.mesh, u, (*at)?).map(|s| s.f))
                .collect();
            let forces = &state.figures.grip_axial_force_n;
            SolvedField {
                gradients,
                forces_n: GRIPS.map(|grip| forces[grip]),
            }
        })
        .collect()
}

/// The identifier's time per field offered (median) and the refit's (median of `runs`), with
/// the frames kept.
fn field_route(fields: &[SolvedField], runs: usize) -> (Duration, Duration, usize) {
    let settings = FieldRouteSettings {
        mm_per_px: VIEW_MM / f64::from(SIDE_PX),
        width_px: SIDE_PX,
        height_px: SIDE_PX,
        cruciform: CruciformGeometry::default(),
        min_level_increment: FieldRouteSettings::DEFAULT_LEVEL_INCREMENT,
        max_frames: FieldRouteSettings::DEFAULT_MAX_FRAMES,
    };
    let mut feed = FieldFeed::new(&settings, &OnlineConfig::default().models).expect("the feed");
    let first_px = [(ZOI_PX / 2) as f64; 2];
    let offers = fields
        .iter()
        .enumerate()
        .map(|(k, field)| {
            let grid = feed.grid(
                first_px,
                STEP_PX as f64,
                (NODES, NODES),
                field.gradients.clone(),
            );
            let t = Instant::now();
            let outcome = feed
                .offer(k as u64, 0, Some(grid), Some(field.forces_n))
                .expect("the view crosses the arms");
            let elapsed = t.elapsed();
            assert_eq!(
                outcome,
                identifier::field_route::FrameOutcome::Kept,
                "frame {k}"
            );
            elapsed
        })
        .collect();
    let job = feed.route.fit_job().expect("enough frames to fit");
    let refits = (0..runs)
        .map(|_| {
            let t = Instant::now();
            let fits = job.run();
            let elapsed = t.elapsed();
            assert!(!fits.fits.is_empty(), "no model fitted");
            elapsed
        })
        .collect();
    (median(offers), median(refits), feed.route.frames().len())
}

/// The correlator's time for one 64 × 64 field on one thread (median of `runs` after a
/// warm-up), on a rendered speckle pair (0.4 px shift, 0.5 % stretch).
fn correlator_field(runs: usize) -> (Duration, usize) {
    let side = SIDE_PX as usize;
    let extent = [-16.0, side as f64 + 16.0];
    let speckle = Speckle::new(SpeckleParams::default(), extent, extent);
    let renderer = FastRenderer::new(&speckle, extent, extent, 4, 2);
    let render = |motion: Motion, seed: u64| {
        let mut pattern = vec![0f32; side * side];
        renderer.render(&motion, side, &mut pattern);
        CameraModel::read_noise_only_16bit(0.01, seed).exposed(seed, &pattern, side, 2)
    };
    let centre = (side as f64 - 1.0) / 2.0;
    let moved = Motion::Affine(Affine {
        f: [[1.005, 0.0], [0.0, 1.005]],
        translation_px: [0.4, 0.4],
        centre_px: [centre, centre],
    });
    let (reference, deformed) = (render(Motion::IDENTITY, 1), render(moved, 2));
    let settings = CorrelatorSettings {
        zoi_px: ZOI_PX,
        step_px: STEP_PX,
        region: Region::rect(Roi {
            x_px: 0,
            y_px: 0,
            width_px: side,
            height_px: side,
        }),
        threads: 1,
        ..CorrelatorSettings::default()
    };
    let mut correlator = Correlator::new(settings, side, side).expect("the correlator");
    correlator.set_reference(&reference).expect("reference");
    correlator.correlate(&deformed).expect("warm-up field");
    let times = (0..runs)
        .map(|_| {
            let t = Instant::now();
            correlator.correlate(&deformed).expect("field");
            t.elapsed()
        })
        .collect();
    (median(times), correlator.field().nodes.len())
}

fn main() {
    let frames = arg_value("--frames", 12);
    let runs = arg_value("--runs", 5);
    let view = View::centred(VIEW_MM / f64::from(SIDE_PX), SIDE_PX, SIDE_PX);
    let t = Instant::now();
    let fields = solved_fields(frames, &view);
    println!(
        "field_route: default cruciform, Mooney-Rivlin, {} equibiaxial states to {LAST_STRETCH} \
         solved in {:.1} s; {NODES} x {NODES} nodes every {STEP_PX} px of a {SIDE_PX} px view",
        fields.len(),
        t.elapsed().as_secs_f64()
    );
    let (offer, refit, kept) = field_route(&fields, runs);
    let (correlate, nodes) = correlator_field(runs);
    println!(
        "  identifier, one field offered (median of {}): {:>9.2} ms",
        fields.len(),
        ms(offer)
    );
    println!(
        "  correlator, one field of {nodes} nodes, 1 thread: {:>9.2} ms",
        ms(correlate)
    );
    println!(
        "  ratio identifier / correlator per field:     {:>9.3}",
        offer.as_secs_f64() / correlate.as_secs_f64()
    );
    println!(
        "  refit of {kept} kept frames, {} models (median of {runs}): {:>9.1} ms ({:.1} fields' \
         correlation)",
        OnlineConfig::default().models.len(),
        ms(refit),
        refit.as_secs_f64() / correlate.as_secs_f64()
    );
}
