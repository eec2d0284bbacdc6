//! What filming the specimen as a structure costs: the fast renderer under a solved
//! finite-element cruciform (equibiaxial grip stretch `--stretch-percent`, default 150 %,
//! Smactane™), 1024² (or `--side N`) seen at `--um-per-px` (default 160 µm/px: the central
//! square and the roots of the four arms), one thread (`--threads N`). Prints the median ms of
//! preparing a state (`FieldMotion::new`: the deformed mesh and its element grid), of rendering
//! it (and, alone, the walk that finds X = φ⁻¹(x) for every pixel), and, in the same run, of rendering the homogeneous motion of the same mean stretch (the
//! affine path): their ratio is what the heterogeneous field costs.
//!
//! `cargo run --release -p producer --example field_cost -- --frames 20`

use membrane::specimens::cruciform::CruciformGeometry;
use producer::field_motion::CellRows;
use producer::{
    Affine, FastRenderer, FieldMotion, Motion, ReferenceMesh, Speckle, SpeckleParams, View,
};
use std::time::Instant;

fn arg(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1))
        .map_or(default, |v| v.parse().expect("a whole number"))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let frames = arg("--frames", 20);
    let side = arg("--side", 1024);
    let threads = arg("--threads", 1);
    let stretch = arg("--stretch-percent", 150) as f64 / 100.0;
    let mm_per_px = arg("--um-per-px", 160) as f64 / 1000.0;

    let specimen = CruciformGeometry::default()
        .mesh()
        .expect("the default cruciform");
    let law = material::InvariantLaw::smactane();
    let started = Instant::now();
    let solved = specimen
        .solve_at(
            &law,
            membrane::GripStretch {
                x: stretch,
                y: stretch,
            },
        )
        .expect("a converged state");
    println!(
        "cruciform at grip stretch {stretch}: {} nodes, solved from rest in {:.0} ms",
        specimen.mesh.nodes_mm.len(),
        started.elapsed().as_secs_f64() * 1e3
    );
    let centre = (side as f64 - 1.0) / 2.0;
    let view = View {
        mm_per_px,
        centre_px: [centre, centre],
        centre_mm: [0.0, 0.0],
    };
    let reference = ReferenceMesh::new(specimen.mesh.clone());

    // The pattern covers the reference points the frame can show.
    let range = [-0.5 * side as f64, 1.5 * side as f64];
    let speckle = Speckle::new(SpeckleParams::default(), range, range);
    let fast = FastRenderer::new(&speckle, range, range, 4, threads);
    // The homogeneous comparison: the mean stretch of the central square (its edge midpoints).
    let probe = membrane::Probe::new(&specimen.mesh);
    let mean_stretch = (probe
        .sample(&solved.displacement_mm, [50.0, 0.0])
        .expect("material")
        .displacement_mm[0]
        - probe
            .sample(&solved.displacement_mm, [-50.0, 0.0])
            .expect("material")
            .displacement_mm[0])
        / 100.0
        + 1.0;
    let affine = Motion::Affine(Affine {
        f: [[mean_stretch, 0.0], [0.0, mean_stretch]],
        translation_px: [0.0, 0.0],
        centre_px: [centre, centre],
    });

    let mut out = vec![0f32; side * side];
    let (mut prepare_ms, mut field_ms, mut affine_ms, mut walk_ms) =
        (vec![], vec![], vec![], vec![]);
    let mut off_specimen = 0;
    for _ in 0..frames {
        let t0 = Instant::now();
        let field = FieldMotion::new(reference.clone(), solved.displacement_mm.clone(), view)
            .expect("a valid state");
        let t1 = Instant::now();
        fast.render_field(&field, side, &mut out);
        let t2 = Instant::now();
        fast.render(&affine, side, &mut out[..]);
        let t3 = Instant::now();
        let mut sum = 0.0;
        let mut cells = CellRows::new(side);
        for y in 0..side {
            cells.walk_row(&field, y, |_, points| {
                sum += points.iter().flatten().map(|p| p[0]).sum::<f64>();
            });
        }
        let t4 = Instant::now();
        walk_ms.push((t4 - t3).as_secs_f64() * 1e3);
        std::hint::black_box(sum);
        prepare_ms.push((t1 - t0).as_secs_f64() * 1e3);
        field_ms.push((t2 - t1).as_secs_f64() * 1e3);
        affine_ms.push((t3 - t2).as_secs_f64() * 1e3);
        if off_specimen == 0 {
            fast.render_field(&field, side, &mut out);
            off_specimen = out.iter().filter(|&&v| v == producer::BACKDROP).count();
        }
    }
    let (prepare, field, affine) = (median(prepare_ms), median(field_ms), median(affine_ms));
    println!(
        "{side}x{side} at {mm_per_px} mm/px, {threads} thread(s), {frames} frames, median ms: prepare a state {prepare:.2}, render the field {field:.2} (of which finding X for every pixel alone {:.2}), render the homogeneous stretch {mean_stretch:.3} {affine:.2} (field / homogeneous {:.2}); {:.1} % of the frame off the specimen",
        median(walk_ms),
        field / affine,
        100.0 * off_specimen as f64 / (side * side) as f64
    );
}
