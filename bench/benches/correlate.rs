//! Correlator throughput: 1024x1024 speckle (producer), ZOI 32, step 16 (3969 ZOIs), fixed
//! reference, a 0.37 / -0.21 px translation, 1 and 2 threads. Reports the median of several
//! frames in ZOIs/s and frames/s, then the time split (FFT, window, peak, shift) measured on
//! separate profiled frames (profiling reads the clock in the hot loop, so it is off for timing).
//! FFT: the integer step's transforms; peak: the 3x3 windowed correlation values (direct sums)
//! and the quadratic fit; shift: the Fourier shift (phase ramp and inverse transform).
//! `dicstream bench correlate` measures the same and adds a plain 2-D FFT timing and --json.

use correlator::{Correlator, CorrelatorSettings, GuessMode};
use producer::motion::Affine;
use producer::{CameraModel, FastRenderer, Motion, Speckle, SpeckleParams};
use std::time::Instant;

const SIZE: usize = 1024;
const FRAMES: usize = 9;

fn render(renderer: &FastRenderer, motion: Motion, seed: u64) -> Vec<u16> {
    let mut pattern = vec![0f32; SIZE * SIZE];
    renderer.render(&motion, SIZE, &mut pattern);
    CameraModel::read_noise_only_16bit(0.01, seed).exposed(seed, &pattern, SIZE, 2)
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn main() {
    let extent = [-16.0, SIZE as f64 + 16.0];
    let speckle = Speckle::new(SpeckleParams::default(), extent, extent);
    let renderer = FastRenderer::new(&speckle, extent, extent, 4, 2);
    let reference = render(&renderer, Motion::IDENTITY, 1);
    let moved = Motion::Affine(Affine {
        translation_px: [0.37, -0.21],
        ..Affine::IDENTITY
    });
    let deformed = render(&renderer, moved, 2);
    println!("correlate: {SIZE}x{SIZE} px, ZOI 32 px, step 16 px, median of {FRAMES} frames");
    for guess in [GuessMode::Predict, GuessMode::Correli] {
        for threads in [1, 2] {
            let settings = CorrelatorSettings {
                zoi_px: 32,
                step_px: 16,
                threads,
                guess,
                ..Default::default()
            };
            let mut correlator = Correlator::new(settings, SIZE, SIZE).expect("settings");
            let t = Instant::now();
            correlator.set_reference(&reference).expect("reference");
            let reference_ms = t.elapsed().as_secs_f64() * 1e3;
            let nodes = correlator
                .correlate(&deformed)
                .expect("warm-up")
                .nodes
                .len();
            let mut seconds: Vec<f64> = (0..FRAMES)
                .map(|_| {
                    let t = Instant::now();
                    let field = correlator.correlate(&deformed).expect("frame");
                    assert!(field.valid > nodes * 9 / 10);
                    t.elapsed().as_secs_f64()
                })
                .collect();
            let frame_s = median(&mut seconds);
            let iterations: f64 = correlator
                .field()
                .nodes
                .iter()
                .map(|n| n.iterations as f64)
                .sum::<f64>()
                / nodes as f64;
            println!(
                "  guess {guess:?}, {threads} thread(s): {:8.0} ZOIs/s, {:6.2} frames/s, {:6.2} ms/frame, mean iterations {iterations:.2}, set_reference {reference_ms:.1} ms",
                nodes as f64 / frame_s,
                1.0 / frame_s,
                frame_s * 1e3
            );
            if threads == 1 {
                correlator.set_profiling(true);
                for _ in 0..3 {
                    correlator.correlate(&deformed).expect("frame");
                }
                let split = correlator.time_split();
                let total = (split.fft_ns
                    + split.window_ns
                    + split.peak_ns
                    + split.shift_ns
                    + split.other_ns) as f64;
                let pct = |ns: u64| 100.0 * ns as f64 / total;
                println!(
                    "    split (1 thread, profiled): FFT {:.0} %, window {:.0} %, peak {:.0} %, shift {:.0} %, extract {:.0} %; {:.1} µs per ZOI",
                    pct(split.fft_ns),
                    pct(split.window_ns),
                    pct(split.peak_ns),
                    pct(split.shift_ns),
                    pct(split.other_ns),
                    total / 1e3 / (3 * nodes) as f64
                );
                correlator.set_profiling(false);
            }
        }
    }
}
