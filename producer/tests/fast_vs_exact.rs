//! How far the `fast` renderer is from the `exact` one, in displacement terms:
//! δ = Σ (I_fast - I_exact) ∇I / Σ |∇I|² (px), over the interior pixels, for each scenario.

use producer::{ExactRenderer, FastRenderer, Scenario, Speckle, SpeckleParams, SCENARIO_NAMES};

const W: usize = 256;
const H: usize = 256;
const MARGIN_PX: f64 = 32.0;

fn displacement_equivalent_error(fast: &[f32], exact: &[f32]) -> ([f64; 2], f64) {
    let (mut num, mut den) = ([0.0f64; 2], [0.0f64; 2]);
    let mut sq = 0.0;
    let mut n = 0.0;
    for y in 1..H - 1 {
        for x in 1..W - 1 {
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
        let (delta, rms) = displacement_equivalent_error(&a, &b);
        eprintln!(
            "fast vs exact, {name:>16}: delta = ({:+.5}, {:+.5}) px, rms intensity error {:.2e} (of range 1)",
            delta[0], delta[1], rms
        );
        worst = worst.max(delta[0].abs()).max(delta[1].abs());
    }
    eprintln!("fast vs exact: worst |delta| = {worst:.5} px");
    assert!(worst < 0.002, "fast renderer biased by {worst} px");
}
