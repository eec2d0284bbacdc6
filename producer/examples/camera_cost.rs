//! The simulated camera's cost per frame, split by stage, as the live bench runs it: 1024² (or
//! `--side N`), the rig-following camera, 8 bits, shot and read noise, the fast renderer, one
//! thread. Prints the median ms per frame of rendering (φ⁻¹ and bicubic sampling, the pattern
//! alone) and of exposure (noise, quantisation, into the frame buffer: the whole frame, rendered
//! and exposed row by row, minus the rendering), over `--frames N` frames of a
//! uniaxial stretch growing to 1.9 (or held at `--stretch-percent P` %).
//!
//! `cargo run --release -p producer --example camera_cost -- --frames 30`; under
//! `valgrind --tool=callgrind --collect-atstart=no --toggle-collect='camera_cost::whole_frame'`
//! with `--frames 3` for instruction counts per frame.

use producer::{RigCamera, RigFollowConfig, RigKinematics, SimulatedConfig};
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

/// One whole frame (render and expose) into `frame`: the function callgrind counts
/// (`--toggle-collect='camera_cost::whole_frame'`).
#[inline(never)]
fn whole_frame(camera: &mut RigCamera, motion: &producer::RigMotion, frame: &mut [u16]) {
    camera.render(motion, frame).expect("a frame");
}

fn main() {
    let frames = arg("--frames", 30);
    let side = arg("--side", 1024) as u32;
    let fixed_stretch_percent = arg("--stretch-percent", 0);
    let mut config = SimulatedConfig::new(side, side);
    config.threads = arg("--threads", 1);
    let mut follow = RigFollowConfig::default();
    follow.envelope.max_stretch = 2.1;
    let started = Instant::now();
    let mut camera = RigCamera::new(config, follow).expect("a valid camera");
    println!(
        "setup (pattern and texture) {:.0} ms",
        started.elapsed().as_secs_f64() * 1e3
    );
    let mut frame = vec![0u16; side as usize * side as usize];
    let (mut render_ms, mut expose_ms, mut total_ms) = (vec![], vec![], vec![]);
    for k in 0..frames {
        let stretch = match fixed_stretch_percent {
            0 => 1.0 + 0.9 * k as f64 / frames.max(1) as f64,
            percent => percent as f64 / 100.0,
        };
        camera.push_kinematics(RigKinematics {
            stretch_x: stretch,
            stretch_y: 1.0 / stretch.sqrt(),
            rotation_rad: 0.3f64.to_radians(),
            centre_offset_mm: [0.05, -0.02],
            ..RigKinematics::at_rest(k as u64)
        });
        let producer::NextMotion::Ready(motion) = camera.next_motion() else {
            panic!("motion outside the envelope");
        };
        let t0 = Instant::now();
        camera.render_pattern(&motion);
        let t1 = Instant::now();
        whole_frame(&mut camera, &motion, &mut frame);
        let t2 = Instant::now();
        let render = (t1 - t0).as_secs_f64() * 1e3;
        let whole = (t2 - t1).as_secs_f64() * 1e3;
        render_ms.push(render);
        expose_ms.push(whole - render);
        total_ms.push(whole);
    }
    println!(
        "{side}x{side}, {frames} frames, median ms per frame: render {:.2}, expose {:.2}, whole frame {:.2}",
        median(render_ms),
        median(expose_ms),
        median(total_ms)
    );
    // A fingerprint of the last frame, to compare builds: equal sums, most likely equal frames.
    let sum: u64 = frame.iter().map(|&v| u64::from(v)).sum();
    let weighted: u64 = frame
        .iter()
        .enumerate()
        .map(|(k, &v)| (k as u64 % 65_521) * u64::from(v))
        .sum();
    println!("last frame: sum {sum}, weighted sum {weighted}");
}
