//! Camera model: range per bit depth, saturation, seed reproducibility, noise standard
//! deviation; the simulated camera as a frame source.

use producer::{
    CameraModel, FrameSource, Scenario, ScenarioTimeline, SimulatedCamera, SimulatedConfig,
    BIT_DEPTHS,
};

const W: usize = 128;
const H: usize = 96;

fn ramp_pattern() -> Vec<f32> {
    (0..W * H)
        .map(|i| (i % W) as f32 / (W - 1) as f32)
        .collect()
}

#[test]
fn values_stay_in_range_for_every_bit_depth() {
    for bits in BIT_DEPTHS {
        let camera = CameraModel::with_bit_depth(bits);
        camera.validate().unwrap();
        let mut out = vec![0u16; W * H];
        camera.expose(0, &ramp_pattern(), W, &mut out, 2);
        let max = u32::from(*out.iter().max().unwrap());
        assert!(max < 1 << bits, "{bits} bit: {max}");
        // White (p = 1) near 90 % of full scale, black near 5 %.
        let full = f64::from((1u32 << bits) - 1);
        assert!(
            f64::from(max) > 0.85 * full && f64::from(max) < 0.97 * full,
            "{bits}: {max}"
        );
    }
    assert!(CameraModel::with_bit_depth(9).validate().is_err());
}

#[test]
fn saturation_clips_to_full_scale() {
    let camera = CameraModel {
        gain_dn_per_e: 1.0,
        ..CameraModel::with_bit_depth(12)
    };
    let mut out = vec![0u16; W * H];
    camera.expose(0, &ramp_pattern(), W, &mut out, 1);
    assert_eq!(*out.iter().max().unwrap(), 4095);
    assert!(out.iter().filter(|&&v| v == 4095).count() > W * H / 2);
    let dark = CameraModel {
        offset_dn: -1000.0,
        ..CameraModel::noiseless(12)
    };
    dark.expose(0, &ramp_pattern(), W, &mut out, 1);
    assert_eq!(*out.iter().min().unwrap(), 0);
}

#[test]
fn noise_is_reproducible_and_thread_independent() {
    let camera = CameraModel::with_bit_depth(16);
    let pattern = ramp_pattern();
    let mut a = vec![0u16; W * H];
    let mut b = vec![0u16; W * H];
    camera.expose(3, &pattern, W, &mut a, 1);
    camera.expose(3, &pattern, W, &mut b, 3);
    assert_eq!(a, b, "same seed and frame, other thread count");
    camera.expose(4, &pattern, W, &mut b, 1);
    assert_ne!(a, b, "another frame has another noise");
    let other = CameraModel { seed: 2, ..camera };
    other.expose(3, &pattern, W, &mut b, 1);
    assert_ne!(a, b, "another seed has another noise");
}

#[test]
fn noise_standard_deviation_matches_the_model() {
    let p = 0.5f32;
    let pattern = vec![p; W * H];
    let mut out = vec![0u16; W * H];
    for (shot, read) in [(false, 20.0), (true, 0.0), (true, 20.0)] {
        let camera = CameraModel {
            shot_noise: shot,
            read_noise_dn: read,
            ..CameraModel::with_bit_depth(16)
        };
        camera.expose(0, &pattern, W, &mut out, 2);
        let n = out.len() as f64;
        let mean = out.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let var = out
            .iter()
            .map(|&v| (f64::from(v) - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        let electrons = camera.illumination_e * f64::from(p);
        let expected_mean = camera.offset_dn + camera.gain_dn_per_e * electrons;
        let shot_var = if shot {
            camera.gain_dn_per_e.powi(2) * electrons
        } else {
            0.0
        };
        let expected_std = (shot_var + read * read + 1.0 / 12.0).sqrt();
        let std = var.sqrt();
        eprintln!("shot {shot}, read {read} DN: std {std:.3} DN, model {expected_std:.3} DN");
        let mean_tolerance = 0.5 + 4.0 * expected_std / n.sqrt();
        assert!(
            (mean - expected_mean).abs() < mean_tolerance,
            "mean {mean} vs {expected_mean}"
        );
        assert!(
            (std / expected_std - 1.0).abs() < 0.05,
            "std {std} vs {expected_std}"
        );
    }
}

#[test]
fn simulated_camera_streams_frames_with_truth() {
    let scenario = Scenario::parse("rotation:angle_deg=2", W as u32, H as u32).unwrap();
    let mut config = SimulatedConfig::new(W as u32, H as u32);
    config.camera = CameraModel::with_bit_depth(10);
    config.threads = 2;
    config.camera.blur_sigma_px = 0.7;
    let timeline = ScenarioTimeline {
        scenario,
        frames: 3,
    };
    let mut camera = SimulatedCamera::new(config, Box::new(timeline)).unwrap();
    assert_eq!(camera.dims().bit_depth, 10);
    assert_eq!(camera.frames_total(), Some(3));
    let mut out = vec![0u16; W * H];
    let mut frames = Vec::new();
    while let Some(info) = camera.next_frame(&mut out).unwrap() {
        let truth = info.truth.expect("simulated frames carry truth");
        assert_eq!(truth.scenario_id, 2);
        assert!(truth.homogeneous);
        assert!(out.iter().all(|&v| v < 1024));
        frames.push((info.index, truth.f[1][0], out.clone()));
    }
    assert_eq!(frames.len(), 3);
    assert_eq!(frames[0].1, 0.0);
    assert!((frames[2].1 - 2f64.to_radians().sin()).abs() < 1e-15);
    assert_ne!(frames[0].2, frames[2].2);
    // Reproducible from the seeds.
    let timeline = ScenarioTimeline {
        scenario,
        frames: 3,
    };
    let mut again = SimulatedCamera::new(config, Box::new(timeline)).unwrap();
    again.next_frame(&mut out).unwrap();
    assert_eq!(out, frames[0].2);
    // A wrong buffer is an error, not a panic.
    let mut small = vec![0u16; 10];
    assert!(again.next_frame(&mut small).is_err());
}

/// Shot and read noise drawn as one normal per pixel: at a constant pattern value, the
/// standardised grey levels have the normal's tails (fraction beyond 2σ and 3σ within 5
/// binomial standard deviations of 4.55 % and 0.27 %), no skew, and the read-noise-only camera
/// is the same realisation whether or not shot noise is modelled at zero illumination.
#[test]
fn combined_noise_has_normal_tails() {
    let (w, h) = (512, 512);
    let p = 0.5f32;
    let pattern = vec![p; w * h];
    let mut out = vec![0u16; w * h];
    let camera = CameraModel {
        read_noise_dn: 40.0,
        ..CameraModel::with_bit_depth(16)
    };
    camera.expose(7, &pattern, w, &mut out, 2);
    let electrons = camera.illumination_e * f64::from(p);
    let mean = camera.offset_dn + camera.gain_dn_per_e * electrons;
    let std = (camera.gain_dn_per_e.powi(2) * electrons + 40.0f64.powi(2) + 1.0 / 12.0).sqrt();
    let n = out.len() as f64;
    let z: Vec<f64> = out.iter().map(|&v| (f64::from(v) - mean) / std).collect();
    let skew = z.iter().map(|z| z.powi(3)).sum::<f64>() / n;
    assert!(skew.abs() < 5.0 * (6.0 / n).sqrt(), "skewness {skew}");
    for (k, expected) in [(2.0, 0.045_500_26), (3.0, 0.002_699_80)] {
        let beyond = z.iter().filter(|z| z.abs() > k).count() as f64 / n;
        let tolerance = 5.0 * (expected * (1.0 - expected) / n).sqrt();
        assert!(
            (beyond - expected).abs() < tolerance,
            "beyond {k} sigma: {beyond} vs {expected}"
        );
    }
    // Read noise alone: one draw per pixel, as before shot noise was folded in.
    let read_only = CameraModel {
        shot_noise: false,
        ..camera
    };
    let mut a = vec![0u16; w * h];
    read_only.expose(7, &vec![0.0; w * h], w, &mut a, 1);
    let mut b = vec![0u16; w * h];
    camera.expose(7, &vec![0.0; w * h], w, &mut b, 1);
    assert_eq!(a, b, "no electrons, no shot noise: the same read noise");
}

/// The noise is independent between pixels and frames: at a constant pattern value, the
/// correlation of each pixel's noise with its neighbour along the row (lags 1 to 3), in the
/// next row, and with the same pixel in the next frame is within 5 of its standard error
/// (1/√n, 0.0039 here) of zero, and its mean and standard deviation are the model's. A stream
/// shared by two rows or two frames (a key that forgot them) correlates them fully.
#[test]
fn noise_is_independent_between_pixels_and_frames() {
    let (w, h) = (256, 256);
    let p = 0.5f32;
    let pattern = vec![p; w * h];
    let camera = CameraModel {
        read_noise_dn: 20.0,
        ..CameraModel::with_bit_depth(16)
    };
    let electrons = camera.illumination_e * f64::from(p);
    let mean = camera.offset_dn + camera.gain_dn_per_e * electrons;
    let std = (camera.gain_dn_per_e.powi(2) * electrons + 20.0f64.powi(2) + 1.0 / 12.0).sqrt();
    let residuals = |frame: u64| -> Vec<f64> {
        let mut out = vec![0u16; w * h];
        camera.expose(frame, &pattern, w, &mut out, 2);
        out.iter().map(|&v| f64::from(v) - mean).collect()
    };
    let (a, b) = (residuals(11), residuals(12));
    let n = a.len() as f64;
    let a_mean = a.iter().sum::<f64>() / n;
    let a_std = (a.iter().map(|r| r * r).sum::<f64>() / n).sqrt();
    assert!(
        a_mean.abs() < 0.5 + 5.0 * std / n.sqrt(),
        "mean off the model by {a_mean} DN"
    );
    assert!((a_std / std - 1.0).abs() < 0.02, "std {a_std} vs {std} DN");
    // Correlation of the pairs (index, index + offset) that `pair` keeps.
    let correlation = |x: &[f64], y: &[f64], pairs: &[(usize, usize)]| {
        let (mut xy, mut xx, mut yy) = (0.0, 0.0, 0.0);
        for &(i, j) in pairs {
            xy += x[i] * y[j];
            xx += x[i] * x[i];
            yy += y[j] * y[j];
        }
        (xy / (xx * yy).sqrt(), pairs.len() as f64)
    };
    let along_row = |lag: usize| -> Vec<(usize, usize)> {
        (0..h)
            .flat_map(|y| (0..w - lag).map(move |x| (y * w + x, y * w + x + lag)))
            .collect()
    };
    let next_row: Vec<(usize, usize)> = (0..(h - 1) * w).map(|i| (i, i + w)).collect();
    let same_pixel: Vec<(usize, usize)> = (0..w * h).map(|i| (i, i)).collect();
    let cases = [
        ("along the row, lag 1", correlation(&a, &a, &along_row(1))),
        ("along the row, lag 2", correlation(&a, &a, &along_row(2))),
        ("along the row, lag 3", correlation(&a, &a, &along_row(3))),
        ("next row", correlation(&a, &a, &next_row)),
        ("next frame", correlation(&a, &b, &same_pixel)),
    ];
    for (name, (rho, pairs)) in cases {
        eprintln!("noise correlation {name}: {rho:.5} over {pairs} pairs");
        assert!(
            rho.abs() < 5.0 / pairs.sqrt(),
            "noise correlated {name}: {rho}"
        );
    }
}

/// Without blur the camera renders and exposes row by row (the pattern never stored): the
/// same grey levels as the pattern rendered whole and then exposed, for an affine and a
/// heterogeneous motion, on 1 and 3 threads.
#[test]
fn row_by_row_frames_equal_the_whole_pattern_exposed() {
    use producer::{Bulge, Motion};
    let motions = [
        Scenario::parse("rotation:angle_deg=3", W as u32, H as u32)
            .unwrap()
            .motion_at_fraction(1.0),
        Motion::Bulge(Bulge {
            strain: 0.1,
            width_px: 30.0,
            centre_px: [60.0, 50.0],
        }),
    ];
    for threads in [1, 3] {
        let mut config = SimulatedConfig::new(W as u32, H as u32);
        config.threads = threads;
        let mut camera = SimulatedCamera::for_reach(config, 20.0).unwrap();
        for (k, motion) in motions.iter().enumerate() {
            let mut fused = vec![0u16; W * H];
            camera.render_frame(motion, k as u64, &mut fused).unwrap();
            let pattern = camera.render_pattern(motion).to_vec();
            let whole = config.camera.exposed(k as u64, &pattern, W, 1);
            assert_eq!(fused, whole, "motion {k}, {threads} thread(s)");
        }
    }
}
