//! How far the `fast` renderer is from the `exact` one, in displacement terms:
//! δ = Σ (I_fast - I_exact) ∇I / Σ |∇I|² (px), per axis, over the whole frame and over each
//! 32x32 window (a ZOI: position-dependent biases, as under rotation, do not cancel there).

use membrane::specimens::cruciform::CruciformGeometry;
use producer::{
    Affine, ExactRenderer, FastRenderer, FieldMotion, Motion, ReferenceMesh, Scenario, Speckle,
    SpeckleParams, View, SCENARIO_NAMES,
};

const W: usize = 256;
const H: usize = 256;
const MARGIN_PX: f64 = 32.0;

/// Side of the windows of the local measure, px (a typical ZOI).
const WINDOW_PX: usize = 32;

/// δ over pixels [x0, x1) x [y0, y1) (inside the 1-px border), and the rms intensity error.
fn delta_over(
    fast: &[f32],
    exact: &[f32],
    (x0, x1): (usize, usize),
    (y0, y1): (usize, usize),
) -> ([f64; 2], f64) {
    let (mut num, mut den) = ([0.0f64; 2], [0.0f64; 2]);
    let mut sq = 0.0;
    let mut n = 0.0;
    for y in y0.max(1)..y1.min(H - 1) {
        for x in x0.max(1)..x1.min(W - 1) {
            let i = y * W + x;
            let gx = 0.5 * f64::from(exact[i + 1] - exact[i - 1]);
            let gy = 0.5 * f64::from(exact[i + W] - exact[i - W]);
            let d = f64::from(fast[i] - exact[i]);
            num[0] += d * gx;
            num[1] += d * gy;
            den[0] += gx * gx;
            den[1] += gy * gy;
            sq += d * d;
            n += 1.0;
        }
    }
    ([num[0] / den[0], num[1] / den[1]], (sq / n).sqrt())
}

/// Global δ over the whole frame, the worst local |δ| over 32x32 windows, and the rms error.
fn displacement_equivalent_error(fast: &[f32], exact: &[f32]) -> ([f64; 2], f64, f64) {
    let (global, rms) = delta_over(fast, exact, (0, W), (0, H));
    let mut worst_local: f64 = 0.0;
    for wy in (0..H).step_by(WINDOW_PX) {
        for wx in (0..W).step_by(WINDOW_PX) {
            let (d, _) = delta_over(fast, exact, (wx, wx + WINDOW_PX), (wy, wy + WINDOW_PX));
            worst_local = worst_local.max(d[0].abs()).max(d[1].abs());
        }
    }
    (global, worst_local, rms)
}

#[test]
fn fast_is_within_2_millipixels_of_exact() {
    let speckle = Speckle::new(
        SpeckleParams::default(),
        [-MARGIN_PX, W as f64 - 1.0 + MARGIN_PX],
        [-MARGIN_PX, H as f64 - 1.0 + MARGIN_PX],
    );
    let threads = 2;
    let fast = FastRenderer::new(
        &speckle,
        [-MARGIN_PX, W as f64 - 1.0 + MARGIN_PX],
        [-MARGIN_PX, H as f64 - 1.0 + MARGIN_PX],
        4,
        threads,
    );
    let exact = ExactRenderer {
        gauss_order: 4,
        threads,
    };
    let mut a = vec![0f32; W * H];
    let mut b = vec![0f32; W * H];
    let mut worst: f64 = 0.0;
    for name in SCENARIO_NAMES {
        let scenario = Scenario::parse(name, W as u32, H as u32).unwrap();
        let motion = scenario.motion_at(1, 2);
        fast.render(&motion, W, &mut a);
        exact.render(&speckle, &motion, W, &mut b);
        let (delta, local, rms) = displacement_equivalent_error(&a, &b);
        eprintln!(
            "fast vs exact, {name:>16}: global delta = ({:+.5}, {:+.5}) px, worst 32x32-window |delta| = {local:.5} px, rms intensity error {rms:.2e} (of range 1)",
            delta[0], delta[1]
        );
        worst = worst.max(delta[0].abs()).max(delta[1].abs()).max(local);
    }
    eprintln!("fast vs exact: worst |delta| (global and per window) = {worst:.5} px");
    assert!(worst < 0.002, "fast renderer biased by {worst} px");
}

/// The default cruciform's reference mesh seen at `mm_per_px`, its centre at the frame's centre,
/// under the nodal displacements `u` of `field` (mm).
fn cruciform_field(mm_per_px: f64, field: impl Fn([f64; 2]) -> [f64; 2]) -> FieldMotion {
    let reference = ReferenceMesh::new(CruciformGeometry::default().mesh().unwrap().mesh);
    let u = reference
        .mesh
        .nodes_mm
        .iter()
        .flat_map(|&x| field(x))
        .collect();
    let view = View {
        mm_per_px,
        centre_px: [(W as f64 - 1.0) / 2.0, (H as f64 - 1.0) / 2.0],
        centre_mm: [0.0, 0.0],
    };
    FieldMotion::new(reference, u, view).unwrap()
}

fn renderers(margin_px: f64) -> (Speckle, FastRenderer, ExactRenderer) {
    let x_range = [-margin_px, W as f64 - 1.0 + margin_px];
    let y_range = [-margin_px, H as f64 - 1.0 + margin_px];
    let speckle = Speckle::new(SpeckleParams::default(), x_range, y_range);
    let fast = FastRenderer::new(&speckle, x_range, y_range, 4, 2);
    let exact = ExactRenderer {
        gauss_order: 4,
        threads: 2,
    };
    (speckle, fast, exact)
}

/// A homogeneous finite-element field is its affine map: the camera films the central square
/// (all material) exactly as under the equivalent `Motion::Affine`, with either renderer.
#[test]
fn a_homogeneous_finite_element_field_renders_as_its_affine_motion() {
    let mm_per_px = 0.25; // 64 mm across: inside the 100 mm central square, stretched or not.
    let f = [[1.2, 0.03], [-0.01, 0.92]];
    let t_mm = [0.4, -0.3];
    let field = cruciform_field(mm_per_px, |x| {
        [
            (f[0][0] - 1.0) * x[0] + f[0][1] * x[1] + t_mm[0],
            f[1][0] * x[0] + (f[1][1] - 1.0) * x[1] + t_mm[1],
        ]
    });
    let motion = Motion::Affine(Affine {
        f,
        translation_px: [t_mm[0] / mm_per_px, t_mm[1] / mm_per_px],
        centre_px: field.view().centre_px,
    });
    let (speckle, fast, exact) = renderers(MARGIN_PX);
    let (mut a, mut b) = (vec![0f32; W * H], vec![0f32; W * H]);
    fast.render_field(&field, W, &mut a);
    fast.render(&motion, W, &mut b);
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max);
    assert!(worst < 1e-5, "fast: {worst}");
    exact.render_field(&speckle, &field, W, &mut a);
    exact.render(&speckle, &motion, W, &mut b);
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max);
    assert!(worst < 1e-5, "exact: {worst}");
}

/// On a solved cruciform (equibiaxial grip stretch 1.3, Smactane™: fillets, arm roots, the
/// room between the arms in view) the fast renderer stays within 2 millipixels of the exact
/// one, like on the analytic scenarios; pixels off the specimen are the backdrop in both.
#[test]
fn fast_is_within_2_millipixels_of_exact_on_a_solved_cruciform() {
    let specimen = CruciformGeometry::default().mesh().unwrap();
    let law = material::InvariantLaw::smactane();
    let solved = specimen
        .solve_at(&law, membrane::GripStretch { x: 1.3, y: 1.3 })
        .unwrap();
    let u = solved.displacement_mm;
    let reference = ReferenceMesh::new(specimen.mesh.clone());
    // 0.9 mm/px: 230 mm across, the central square and 65 mm of each arm before stretching.
    let view = View {
        mm_per_px: 0.9,
        centre_px: [(W as f64 - 1.0) / 2.0, (H as f64 - 1.0) / 2.0],
        centre_mm: [0.0, 0.0],
    };
    let field = FieldMotion::new(reference, u, view).unwrap();
    let (speckle, fast, exact) = renderers(MARGIN_PX);
    let (mut a, mut b) = (vec![0f32; W * H], vec![0f32; W * H]);
    fast.render_field(&field, W, &mut a);
    exact.render_field(&speckle, &field, W, &mut b);
    // The corner between two arms shows the backdrop in both.
    let corner = view.to_px([100.0, 100.0]);
    let i = corner[1] as usize * W + corner[0] as usize;
    assert_eq!((a[i], b[i]), (producer::BACKDROP, producer::BACKDROP));
    // δ over windows fully on the specimen (an edge pixel is a mixture in the exact renderer,
    // one or the other in the fast one: not a displacement).
    let on_specimen = |x0: usize, y0: usize| {
        (y0..y0 + WINDOW_PX)
            .all(|y| (x0..x0 + WINDOW_PX).all(|x| field.inverse([x as f64, y as f64]).is_some()))
    };
    let (mut worst, mut windows) = (0.0f64, 0);
    for wy in (0..H).step_by(WINDOW_PX) {
        for wx in (0..W).step_by(WINDOW_PX) {
            if !on_specimen(wx, wy) {
                continue;
            }
            let (d, _) = delta_over(&a, &b, (wx, wx + WINDOW_PX), (wy, wy + WINDOW_PX));
            worst = worst.max(d[0].abs()).max(d[1].abs());
            windows += 1;
        }
    }
    eprintln!("fast vs exact, solved cruciform: worst 32x32-window |delta| = {worst:.5} px over {windows} windows");
    assert!(windows >= 24, "{windows} windows on the specimen");
    assert!(worst < 0.002, "fast renderer biased by {worst} px");
}
