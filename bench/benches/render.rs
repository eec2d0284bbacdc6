//! Render time per 1024x1024 frame for the `fast` and `exact` renderers (5° rotation, the
//! default pattern), medians of several runs; plus the one-off texture build and a whole
//! simulated-camera frame (render + 8-bit exposure with noise).
//!
//! Run: `cargo bench -p bench --bench render` (options: `-- --threads N --exact-runs N`).

use bench::{arg_value, median, ms};
use std::time::{Duration, Instant};

use producer::{
    CameraModel, ExactRenderer, FastRenderer, FrameSource, Scenario, ScenarioTimeline,
    SimulatedCamera, SimulatedConfig, Speckle, SpeckleParams,
};

const SIDE_PX: usize = 1024;
const MARGIN_PX: f64 = 72.0;

fn main() {
    let threads = arg_value("--threads", producer::parallel::default_threads());
    let fast_runs = arg_value("--fast-runs", 15);
    let exact_runs = arg_value("--exact-runs", 3);
    let side = SIDE_PX as f64;
    let range = [-MARGIN_PX, side - 1.0 + MARGIN_PX];
    let scenario = Scenario::parse("rotation:angle_deg=5", SIDE_PX as u32, SIDE_PX as u32)
        .expect("rotation scenario");
    let motion = scenario.motion_at(1, 2);
    let mut out = vec![0f32; SIDE_PX * SIDE_PX];

    let started = Instant::now();
    let speckle = Speckle::new(SpeckleParams::default(), range, range);
    let pattern_time = started.elapsed();
    let started = Instant::now();
    let fast = FastRenderer::new(&speckle, range, range, 4, threads);
    let texture_time = started.elapsed();
    println!(
        "render bench: {SIDE_PX}x{SIDE_PX}, 5° rotation, {} spots, {threads} threads",
        speckle.spots().len()
    );
    println!(
        "  setup: pattern {:.1} ms, fast texture (4x oversampled, {:.0} MB) {:.1} ms",
        ms(pattern_time),
        fast.texture_bytes() as f64 / 1e6,
        ms(texture_time)
    );

    let fast_samples: Vec<Duration> = (0..fast_runs)
        .map(|_| {
            let t = Instant::now();
            fast.render(&motion, SIDE_PX, &mut out);
            t.elapsed()
        })
        .collect();
    let fast_median = median(fast_samples);
    println!(
        "  fast : median {:8.2} ms per frame over {fast_runs} runs ({:.0} frames/s)",
        ms(fast_median),
        1.0 / fast_median.as_secs_f64()
    );

    let exact = ExactRenderer {
        gauss_order: 4,
        threads,
    };
    let exact_samples: Vec<Duration> = (0..exact_runs)
        .map(|_| {
            let t = Instant::now();
            exact.render(&speckle, &motion, SIDE_PX, &mut out);
            t.elapsed()
        })
        .collect();
    println!(
        "  exact: median {:8.2} ms per frame over {exact_runs} runs (4x4 Gauss-Legendre points per pixel)",
        ms(median(exact_samples))
    );

    // A whole simulated-camera frame: fast render + 8-bit exposure with shot and read noise.
    let mut config = SimulatedConfig::new(SIDE_PX as u32, SIDE_PX as u32);
    config.camera = CameraModel::with_bit_depth(8);
    config.threads = threads;
    let frames = fast_runs as u64 + 1;
    let mut camera = SimulatedCamera::new(config, Box::new(ScenarioTimeline { scenario, frames }))
        .expect("simulated camera");
    let mut pixels = vec![0u16; SIDE_PX * SIDE_PX];
    camera.next_frame(&mut pixels).expect("warm-up frame");
    let frame_samples: Vec<Duration> = (0..fast_runs)
        .map(|_| {
            let t = Instant::now();
            camera.next_frame(&mut pixels).expect("frame");
            t.elapsed()
        })
        .collect();
    println!(
        "  camera frame (fast render + exposure with noise): median {:8.2} ms over {fast_runs} runs",
        ms(median(frame_samples))
    );
}
