//! `dicstream bench correlate`, the one benchmark of correlation (it replaced
//! `bench/benches/correlate.rs`), run small so that CI runs it: its JSON alone on stdout, one
//! run per thread count, the time split and the sub-pixel shift found. No time is asserted.

use crate::common;

use common::Run;

#[test]
fn bench_correlate_json_runs_every_thread_count() {
    let mut run = Run::new("bench_correlate");
    for guess in ["predict", "correli"] {
        let (status, stdout, stderr) = run.run_to_end(
            "bench",
            &[
                "bench",
                "correlate",
                "--width",
                "256",
                "--height",
                "256",
                "--threads",
                "1,2",
                "--frames",
                "2",
                "--guess",
                guess,
                "--json",
            ],
        );
        assert!(status.success(), "{stderr}");
        let json: serde_json::Value = serde_json::from_str(stdout.trim())
            .unwrap_or_else(|e| panic!("stdout is not JSON alone ({e}):\n{stdout}"));
        assert_eq!(json["guess"], guess, "{json}");
        let runs = json["runs"].as_array().expect("runs");
        assert_eq!(runs.len(), 2, "{json}");
        for r in runs {
            let (zois, valid) = (r["zois"].as_u64().unwrap(), r["valid"].as_u64().unwrap());
            assert!(valid > zois * 9 / 10, "{guess}: {r}");
            for (axis, error) in r["mean_error_px"].as_array().unwrap().iter().enumerate() {
                let error = error.as_f64().unwrap();
                assert!(
                    error.abs() < 0.05,
                    "{guess}: axis {axis} off by {error} px: {r}"
                );
            }
        }
        assert!(json["time_split_1_thread"]["zois_profiled"].as_u64() > Some(0));
    }
}
