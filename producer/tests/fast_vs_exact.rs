//! How far the `fast` renderer is from the `exact` one, in displacement terms:
//! δ = Σ (I_fast - I_exact) ∇I / Σ |∇I|² (px), per axis, over the whole frame and over each
//! 32x32 window (a ZOI: position-dependent biases, as under rotation, do not cancel there).

use producer::{ExactRenderer, FastRenderer, Scenario, Speckle, SpeckleParams, SCENARIO_NAMES};

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
