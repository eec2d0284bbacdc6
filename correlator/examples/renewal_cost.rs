//! The automatic reference on a uniaxial ramp, as the live bench loads its specimen: per frame
//! the correlation time, whether the reference was renewed, and the integer FFT searches run
//! (a predicted node that its first windowed correlation confirms runs none). Prints each
//! frame, then the renewals, the medians of renewing and other frames, and the searches of the
//! frames right after a renewal.
//!
//! `cargo run --release -p correlator --example renewal_cost -- [SIZE] [FRAMES] [STRETCH] [METHOD] [DEFORMATION] [PATH]`
//! (defaults 1024, 120, 2.0, correli, the automatic reference's default deformation limit
//! (`-` for it), `eager`): the ramp goes from λ 1 to STRETCH in FRAMES frames about
//! the image centre (the live bench's ramp at 12 frames/s: 1024², 120 frames to λ 2), then
//! back to λ 1 five times faster (the bench's unloading). PATH `eager` correlates with
//! `Correlator::correlate` (a renewing frame measures its bases against the origin at once);
//! `live` as the live process does: `correlate_field`, then `renew_reference`, then a quarter
//! of the pending bases per frame (`measure_pending_bases`, `ORIGIN_PASS_FRAMES`),
//! each part timed: a frame's cost is the sum of the three.

use correlator::settings::{Method, ReferenceKind};
use correlator::{Correlator, CorrelatorSettings, NodeStatus, ReferenceMode};
use producer::motion::Affine;
use producer::{CameraModel, FastRenderer, Motion, Speckle, SpeckleParams};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or(default.into());
    let size: usize = arg(0, "1024").parse().expect("SIZE");
    let frames: usize = arg(1, "120").parse().expect("FRAMES");
    let final_stretch: f64 = arg(2, "2.0").parse().expect("STRETCH");
    let method: Method = arg(3, "correli").parse().expect("METHOD");
    let live = match arg(5, "eager").as_str() {
        "eager" => false,
        "live" => true,
        other => panic!("PATH {other:?}: eager or live"),
    };
    let reference = match args.get(4).filter(|a| *a != "-") {
        Some(px) => ReferenceMode::Auto {
            max_deformation_px: px.parse().expect("DEFORMATION"),
            min_mean_score: 0.5,
        },
        None => ReferenceMode::of_kind(ReferenceKind::Auto, method),
    };
    let c = (size as f64 - 1.0) / 2.0;
    let margin = (final_stretch.sqrt() - 1.0) * c + 32.0;
    let extent = [-margin, size as f64 + margin];
    let speckle = Speckle::new(SpeckleParams::default(), extent, extent);
    let renderer = FastRenderer::new(&speckle, extent, extent, 4, 2);
    // The ramp, then the unloading five times faster.
    let unload = frames.div_ceil(5);
    let stretch_at = |k: usize| {
        let loaded = if k <= frames {
            k as f64 / frames as f64
        } else {
            1.0 - (k - frames) as f64 / unload as f64
        };
        1.0 + (final_stretch - 1.0) * loaded
    };
    let render = |k: usize| {
        let stretch = stretch_at(k);
        let motion = Motion::Affine(Affine {
            f: [[stretch, 0.0], [0.0, 1.0 / stretch.sqrt()]],
            translation_px: [0.0, 0.0],
            centre_px: [c, c],
        });
        let mut pattern = vec![0f32; size * size];
        renderer.render(&motion, size, &mut pattern);
        let camera = CameraModel::read_noise_only_16bit(0.01, k as u64 + 1);
        camera.exposed(k as u64, &pattern, size, 2)
    };
    let settings = CorrelatorSettings {
        method,
        zoi_px: if method.is_icgn() { 33 } else { 32 },
        reference,
        ..CorrelatorSettings::default()
    };
    let mut correlator = Correlator::new(settings, size, size).expect("settings");
    correlator.set_reference(&render(0)).expect("reference");
    let (mut renewing, mut others, mut after) = (Vec::new(), Vec::new(), Vec::new());
    let mut renewed_before = false;
    let (mut worst_gauge, mut worst_node, mut error_sum, mut error_count) =
        (0.0f64, 0.0f64, 0.0, 0);
    // Each frame's cost and whether it renewed.
    let mut costs = Vec::new();
    let ms_since = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    for k in 1..=frames + unload {
        let pixels = render(k);
        let searches = correlator.fft_searches();
        let t = Instant::now();
        let (mut renew_ms, mut origin_ms) = (0.0, 0.0);
        let field_ms;
        if live {
            correlator.correlate_field(&pixels, 1).expect("correlate");
            field_ms = ms_since(t);
            let t = Instant::now();
            correlator.renew_reference(&pixels).expect("renew");
            renew_ms = ms_since(t);
            let t = Instant::now();
            correlator.measure_pending_bases();
            origin_ms = ms_since(t);
        } else {
            correlator.correlate(&pixels).expect("correlate");
            field_ms = ms_since(t);
        }
        let ms = ms_since(t);
        let searched = correlator.fft_searches() - searches;
        let field = correlator.field();
        let renewed = field.reference_updated;
        // The truth: u = (λ − 1)(x − c), v = (1/√λ − 1)(y − c) at each node.
        let stretch = stretch_at(k);
        let (mut sum, mut worst, mut count) = (0.0f64, 0.0f64, 0usize);
        for node in field.nodes.iter().filter(|n| n.status == NodeStatus::Ok) {
            let u = (stretch - 1.0) * (node.x_px - c);
            let v = (1.0 / stretch.sqrt() - 1.0) * (node.y_px - c);
            let error = (node.u_px - u).hypot(node.v_px - v);
            sum += error;
            worst = worst.max(error);
            count += 1;
        }
        let gauge_error = (field.gauge.log.exx - stretch.ln()).abs();
        worst_gauge = worst_gauge.max(gauge_error);
        error_sum += sum;
        error_count += count;
        worst_node = worst_node.max(worst);
        println!(
            "frame {k:4}: {ms:7.1} ms (field {field_ms:.1}, renewal {renew_ms:.1}, origin {origin_ms:.1}), {searched:5} FFT searches, {} of {} valid, log exx {:.4} (error {gauge_error:.1e}), node error mean {:.4} worst {worst:.3} px{}",
            field.valid,
            field.nodes.len(),
            field.gauge.log.exx,
            sum / count.max(1) as f64,
            if renewed { ", renewed" } else { "" }
        );
        if renewed_before {
            after.push(searched);
        }
        if renewed {
            renewing.push(ms);
        } else {
            others.push(ms);
        }
        renewed_before = renewed;
        costs.push((ms, renewed));
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    // A renewing frame and the three after it (those that do not renew themselves).
    let after_ms: Vec<f64> = (0..4)
        .map(|d| {
            let mut v: Vec<f64> = (0..costs.len())
                .filter(|&i| costs[i].1 && i + d < costs.len() && (d == 0 || !costs[i + d].1))
                .map(|i| costs[i + d].0)
                .collect();
            median(&mut v)
        })
        .collect();
    println!(
        "median cost of a renewing frame and of the next three: {:.1}, {:.1}, {:.1}, {:.1} ms ({} path)",
        after_ms[0],
        after_ms[1],
        after_ms[2],
        after_ms[3],
        if live { "live" } else { "eager" }
    );
    let renewals = renewing.len();
    println!(
        "{method} {size}² to λ {final_stretch} in {frames} frames: {renewals} renewals; median frame {:.1} ms renewing, {:.1} ms otherwise; node error mean {:.4} px, worst {worst_node:.3} px; worst gauge log exx error {worst_gauge:.1e}; FFT searches in the frames after a renewal: {:?}",
        median(&mut renewing),
        median(&mut others),
        error_sum / error_count.max(1) as f64,
        after
    );
}
