//! What `dicstream bench correlate` prints: one line per run as it ends, then the time split,
//! the FFT timing, the keypoint guess and the frame rate the correlation alone allows, as text,
//! or everything as one JSON object.

use super::correlate::{CorrelateBench, KeypointTiming, ThreadRun, BASELINE_ZOI_PX, SHIFT_PX};
use anyhow::Result;
use correlator::timing::FftTimings;
use correlator::TimeSplit;

/// Everything the benchmark measured.
pub(super) struct Measured {
    pub runs: Vec<ThreadRun>,
    /// The one-thread time split and the ZOIs it profiled.
    pub split: (TimeSplit, usize),
    /// The CORRELI-GD baseline of an IC-GN run per thread count, with the time per ZOI ratio.
    pub baseline: Vec<(ThreadRun, f64)>,
    pub keypoints: KeypointTiming,
    pub fft: FftTimings,
}

impl Measured {
    /// The time split's parts (name, ns).
    fn parts(&self) -> [(&'static str, u64); 8] {
        let split = &self.split.0;
        [
            ("fft", split.fft_ns),
            ("window", split.window_ns),
            ("peak", split.peak_ns),
            ("shift", split.shift_ns),
            ("other", split.other_ns),
            ("coefficients", split.coefficients_ns),
            ("iterations", split.iterations_ns),
            ("check", split.check_ns),
        ]
    }

    fn total_ns(&self) -> u64 {
        self.parts().iter().map(|p| p.1).sum()
    }

    /// One real n x n forward plus inverse transform, the unit of a ZOI's cost (µs, this run).
    fn fft_pair_us(&self) -> f64 {
        (self.fft.real_forward_ns + self.fft.real_inverse_ns) / 1e3
    }

    /// The benchmarked ZOI's cost in one-thread wall-clock time (µs, unprofiled) and in FFT
    /// pairs of this run; None without a one-thread run.
    fn zoi_cost(&self) -> Option<(f64, f64)> {
        let one = self.runs.iter().find(|r| r.threads == 1)?;
        let us = one.median_s * 1e6 / one.nodes as f64;
        Some((us, us / self.fft_pair_us()))
    }

    /// The run of the shortest frame time.
    fn fastest(&self) -> Option<&ThreadRun> {
        self.runs
            .iter()
            .min_by(|a, b| a.median_s.total_cmp(&b.median_s))
    }
}

fn zois_per_s(run: &ThreadRun) -> f64 {
    run.nodes as f64 / run.median_s
}

impl CorrelateBench {
    pub(super) fn print_json(&self, m: &Measured) -> Result<()> {
        let args = &self.args;
        let total_ns = m.total_ns();
        let profiled_zois = m.split.1;
        let json = serde_json::json!({
            "benchmark": "correlate",
            "image": [self.width_px(), self.height_px()],
            "method": args.method.name(),
            "zoi": args.zoi,
            "step": args.step,
            "guess": format!("{:?}", args.guess).to_lowercase(),
            "shift_px": SHIFT_PX,
            "frames_per_run": args.frames,
            "runs": m.runs.iter().map(run_json).collect::<Vec<_>>(),
            "baseline_correli": m.baseline.iter().map(|(r, ratio)| serde_json::json!({
                "threads": r.threads,
                "zoi": BASELINE_ZOI_PX,
                "zois_per_s": zois_per_s(r),
                "time_per_zoi_ratio": ratio,
            })).collect::<Vec<_>>(),
            "time_split_1_thread": {
                "zois_profiled": profiled_zois,
                "us_per_zoi": total_ns as f64 / 1e3 / profiled_zois as f64,
                "percent": m.parts().iter().map(|(name, ns)| (name.to_string(), serde_json::json!(100.0 * *ns as f64 / total_ns.max(1) as f64))).collect::<serde_json::Map<_, _>>(),
            },
            "zoi_cost_1_thread": m.zoi_cost().map(|(us, pairs)| serde_json::json!({
                "us_per_zoi": us,
                "fft_pairs_per_zoi": pairs,
                "fft_pair_us": m.fft_pair_us(),
            })),
            "keypoint_guess_2_threads": {
                "reference_ms": m.keypoints.reference_ms,
                "per_frame_ms": m.keypoints.per_frame_ms,
                "inliers": m.keypoints.inliers,
            },
            "fft_2d": {
                "n": m.fft.n,
                "complex_forward_us": m.fft.complex_forward_ns / 1e3,
                "real_forward_us": m.fft.real_forward_ns / 1e3,
                "real_inverse_us": m.fft.real_inverse_ns / 1e3,
            },
            "frame_rate": m.fastest().map(|r| serde_json::json!({
                "threads": r.threads,
                "frame_ms": r.median_s * 1e3,
                "frames_per_s": 1.0 / r.median_s,
            })),
        });
        println!("{}", serde_json::to_string_pretty(&json)?);
        Ok(())
    }

    pub(super) fn print_text(&self, m: &Measured) {
        print_split(m);
        println!(
            "  {n}x{n} 2-D FFT, one thread (median): complex forward {:.2} µs, real-to-complex forward {:.2} µs, inverse {:.2} µs",
            m.fft.complex_forward_ns / 1e3,
            m.fft.real_forward_ns / 1e3,
            m.fft.real_inverse_ns / 1e3,
            n = m.fft.n
        );
        if let Some((us, pairs)) = m.zoi_cost() {
            println!(
                "  cost per ZOI (1 thread, unprofiled median): {us:.2} µs = {pairs:.2} FFT pairs ({n}x{n} real forward + inverse: {:.2} µs in this run)",
                m.fft_pair_us(),
                n = m.fft.n
            );
        }
        self.print_keypoints(&m.keypoints);
        self.print_frame_rate(m.fastest());
    }

    fn print_keypoints(&self, keypoints: &KeypointTiming) {
        println!(
            "  keypoint guess (2 threads, median of {}): reference keypoints {:.1} ms once per reference, per frame (detect, match, RANSAC) {:.1} ms; {}",
            self.args.frames,
            keypoints.reference_ms,
            keypoints.per_frame_ms,
            match keypoints.inliers {
                Some(n) => format!("{n} inlier matches"),
                None => "no trustworthy map (unexpected on this pair)".into(),
            }
        );
    }

    fn print_frame_rate(&self, fastest: Option<&ThreadRun>) {
        if let Some(r) = fastest {
            println!(
                "  frame rate: a {}x{} frame ({} ZOIs) takes {:.1} ms on {} thread(s), up to {:.1} frames/s for the correlation alone (in a live run the camera shares the cores: `dicstream bench pipeline`)",
                self.width_px(),
                self.height_px(),
                r.nodes,
                r.median_s * 1e3,
                r.threads,
                1.0 / r.median_s
            );
        }
    }
}

fn run_json(r: &ThreadRun) -> serde_json::Value {
    serde_json::json!({
        "threads": r.threads,
        "zois": r.nodes,
        "valid": r.valid,
        "median_ms": r.median_s * 1e3,
        "min_ms": r.min_s * 1e3,
        "max_ms": r.max_s * 1e3,
        "zois_per_s": zois_per_s(r),
        "frames_per_s": 1.0 / r.median_s,
        "mean_iterations": r.mean_iterations,
        "second_order_runs": r.second_order_runs,
        "second_order_nodes": r.second_order_nodes,
        "mean_error_px": r.error_px,
        "set_reference_ms": r.set_reference_ms,
        "set_reference_again_ms": r.set_reference_again_ms,
        "first_frame_after_again_ms": r.first_frame_ms,
    })
}

/// The one-thread time split: each part's share and µs per ZOI.
fn print_split(m: &Measured) {
    let (total_ns, profiled_zois) = (m.total_ns(), m.split.1);
    let pct = |ns: u64| 100.0 * ns as f64 / total_ns.max(1) as f64;
    let us = |ns: u64| ns as f64 / 1e3 / profiled_zois as f64;
    let listed = m
        .parts()
        .iter()
        .filter(|(_, ns)| *ns > 0)
        .map(|(name, ns)| format!("{name} {:.0} % ({:.2} µs)", pct(*ns), us(*ns)))
        .collect::<Vec<_>>()
        .join(", ");
    println!(
        "  time split (1 thread, profiled, {profiled_zois} ZOIs; µs per ZOI): {listed}; {:.1} µs per ZOI",
        us(total_ns)
    );
}

pub(super) fn print_run(r: &ThreadRun) {
    // Image files carry no truth: no mean error then.
    let error = if r.error_px[0].is_finite() {
        format!(
            "mean error u {:+.4} v {:+.4} px",
            r.error_px[0], r.error_px[1]
        )
    } else {
        "no truth for image files".to_owned()
    };
    // Method `icgn`: how many nodes its second order re-ran (the others' results are icgn1's).
    let second_order = if r.second_order_runs > 0 || r.second_order_nodes > 0 {
        format!(
            "; second order: {} ZOIs re-run ({:.1} %), {} kept",
            r.second_order_runs,
            100.0 * r.second_order_runs as f64 / r.nodes.max(1) as f64,
            r.second_order_nodes
        )
    } else {
        String::new()
    };
    println!(
        "  {} thread(s): {:8.0} ZOIs/s, {:6.2} frames/s, {:7.2} ms/frame (min {:.2}, max {:.2}); {} ZOIs, {} valid, {:.2} iterations/ZOI, {error}; set_reference {:.1} ms (again, running: {:.1} ms, then its first frame {:.1} ms){second_order}",
        r.threads,
        zois_per_s(r),
        1.0 / r.median_s,
        r.median_s * 1e3,
        r.min_s * 1e3,
        r.max_s * 1e3,
        r.nodes,
        r.valid,
        r.mean_iterations,
        r.set_reference_ms,
        r.set_reference_again_ms,
        r.first_frame_ms
    );
}
