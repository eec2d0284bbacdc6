//! `dicstream correlator` as a real process: the test is the camera (speckle rendered by the
//! producer crate with exact ground truth in the header) and the field reader.
//! Accuracy against the truth, ids and times copied through, bursts dropped (counted) instead of
//! queued, bad frames logged and skipped, signals, --reference, --max-frames, restart after
//! SIGKILL with --state-dir.

use crate::common;

use common::camera::{
    affine, final_line, number_after, render, translation, unrelated_speckle, Bench, FieldCopy,
};
use wire::{FrameHeader, NodeStatus, StrainMeasure};

const W: usize = 256;
const H: usize = 256;

fn assert_copied_through(field: &FieldCopy, frame: &FrameHeader) {
    let h = &field.header;
    assert_eq!(h.layout_version, wire::LAYOUT_VERSION);
    assert_eq!(h.frame_id, frame.frame_id);
    assert_eq!(h.rig_sample_id, frame.rig_sample_id);
    assert_eq!(h.t_capture_ns, frame.t_capture_ns);
    assert_eq!(h.has_truth, frame.has_truth);
    assert_eq!(h.truth, frame.truth);
    assert!(h.t_received_ns >= h.t_capture_ns, "{h:?}");
    assert!(h.t_published_ns >= h.t_received_ns, "{h:?}");
    assert!(h.correlate_ns > 0);
    assert_eq!(field.nodes.len(), h.node_count());
    // The header's means are the means of the valid nodes.
    let ok: Vec<_> = field
        .nodes
        .iter()
        .filter(|n| n.status == NodeStatus::Ok as u32)
        .collect();
    assert_eq!(ok.len(), h.valid_nodes as usize);
    if !ok.is_empty() {
        let mean_u = ok.iter().map(|n| n.u_px as f64).sum::<f64>() / ok.len() as f64;
        assert!(
            (mean_u - h.u_mean_px).abs() < 1e-4,
            "{mean_u} {}",
            h.u_mean_px
        );
    }
}

/// Sub-pixel translations measured live within the accuracy (|mean error| <= 0.01 px,
/// std <= 0.02 px), ids and times copied through; SIGINT ends the process with status 0.
#[test]
fn live_translation_matches_the_truth() {
    let mut bench = Bench::new("translation", W * H);
    let p = bench.spawn_correlator(&["--zoi", "32", "--step", "16", "--threads", "2"]);
    bench.proc(p).wait_line("correlator: ready");
    let shifts = [
        (0.0, 0.0),
        (0.1, 0.25),
        (0.37, -0.21),
        (0.5, 0.5),
        (0.73, -0.9),
        (1.25, 0.6),
    ];
    eprintln!("frame   u_true  v_true   mean_err_u std_u    mean_err_v std_v   valid");
    for (id, &(u, v)) in shifts.iter().enumerate() {
        let (motion, truth) = translation(u, v);
        let pixels = render(W, H, &motion, 100 + id as u64);
        let header = Bench::header(id as u64, W, H, &pixels, Some(truth));
        assert_eq!(bench.send_frame(header, &pixels), 1, "one subscriber");
        let field = bench.next_field();
        assert_copied_through(&field, &header);
        let h = field.header;
        assert_eq!(h.reference_frame_id, 0);
        assert_eq!(h.frames_dropped, 0);
        // The default region: 256 px less half a ZOI (16 px) on each side, 224 px: 13 nodes.
        assert_eq!((h.mesh_cols, h.mesh_rows), (13, 13));
        assert_eq!((h.zoi_px, h.step_px), (32, 16));
        assert_eq!(h.strain_measure, StrainMeasure::Log as u32);
        assert_eq!(h.valid_nodes as usize, field.nodes.len(), "all nodes valid");
        let [(mu, su), (mv, sv)] = field.error_stats(&truth);
        eprintln!(
            "{id:5} {u:7.2} {v:7.2}   {mu:+.5}   {su:.5}  {mv:+.5}   {sv:.5}  {}/{}",
            h.valid_nodes,
            field.nodes.len()
        );
        assert!(mu.abs() <= 0.01 && mv.abs() <= 0.01, "bias {mu} {mv}");
        assert!(su <= 0.02 && sv <= 0.02, "std {su} {sv}");
        // A translation has no strain.
        for g in h.gauge {
            assert!(g.exx.abs() < 2e-4 && g.eyy.abs() < 2e-4 && g.exy.abs() < 2e-4);
        }
    }
    let proc = bench.proc(p);
    proc.signal(libc::SIGINT);
    let status = proc.wait_exit();
    assert!(status.success(), "exit status {status:?}");
    let last = final_line(proc);
    assert!(last.contains("stopped (SIGINT)"), "{last}");
    assert_eq!(number_after(&last, "correlated"), 6, "{last}");
    assert_eq!(number_after(&last, "dropped"), 0, "{last}");
    bench.finish();
}

/// A homogeneous stretch against a reference image file: gauge strains of all four measures
/// against the exact ones; the process stops by itself after --max-frames.
#[test]
fn stretch_against_a_reference_file() {
    let mut bench = Bench::new("stretch", W * H);
    let dir = bench.temp_dir("files");
    let centre = [(W as f64 - 1.0) / 2.0, (H as f64 - 1.0) / 2.0];
    let (motion0, _) = translation(0.0, 0.0);
    let reference = render(W, H, &motion0, 1);
    let reference_path = dir.join("reference.png");
    let dims = producer::FrameDims {
        width: W as u32,
        height: H as u32,
        bit_depth: 16,
    };
    producer::write_frame(
        &reference_path,
        dims,
        &reference,
        producer::ImageFormatOut::Png16,
        &mut Vec::new(),
    )
    .unwrap();
    let p = bench.spawn_correlator(&[
        "--reference",
        reference_path.to_str().unwrap(),
        "--strain",
        "green",
        "--max-frames",
        "3",
    ]);
    let ready = bench.proc(p).wait_line("correlator: ready");
    assert!(ready.contains("reference image"), "{ready}");
    let stretches = [(0.01, -0.004), (0.02, -0.008), (0.03, 0.015)];
    for (k, &(ex, ey)) in stretches.iter().enumerate() {
        let id = 10 + k as u64;
        let (motion, truth) = affine([[1.0 + ex, 0.0], [0.0, 1.0 + ey]], [0.2, -0.1], centre);
        let pixels = render(W, H, &motion, 50 + k as u64);
        let header = Bench::header(id, W, H, &pixels, Some(truth));
        bench.send_frame(header, &pixels);
        let field = bench.next_field();
        assert_copied_through(&field, &header);
        let h = field.header;
        assert_eq!(h.reference_frame_id, correlator::state::REFERENCE_FROM_FILE);
        assert_eq!(h.strain_measure, StrainMeasure::Green as u32);
        let [(mu, su), (mv, sv)] = field.error_stats(&truth);
        let (lx, ly) = (1.0 + ex, 1.0 + ey);
        let exact = [
            (StrainMeasure::Small, ex, ey),
            (
                StrainMeasure::Green,
                0.5 * (lx * lx - 1.0),
                0.5 * (ly * ly - 1.0),
            ),
            (StrainMeasure::Nominal, ex, ey),
            (StrainMeasure::Log, lx.ln(), ly.ln()),
        ];
        eprintln!(
            "frame {id}: stretch {ex:+.3} {ey:+.3}: u error {mu:+.4} ± {su:.4}, v error {mv:+.4} ± {sv:.4} px, valid {}/{}",
            h.valid_nodes,
            field.nodes.len()
        );
        for (measure, exx, eyy) in exact {
            let g = h.gauge_of(measure);
            eprintln!(
                "  gauge {:7} exx {:+.5} (exact {exx:+.5}) eyy {:+.5} (exact {eyy:+.5}) exy {:+.1e}",
                measure.name(),
                g.exx,
                g.eyy,
                g.exy
            );
            assert!(
                (g.exx - exx).abs() < 3e-4 && (g.eyy - eyy).abs() < 3e-4,
                "{measure:?} {g:?}"
            );
            assert!(g.exy.abs() < 2e-4, "{measure:?} {g:?}");
        }
        assert!(mu.abs() <= 0.02 && mv.abs() <= 0.02);
        // Node strains are of the chosen measure (green), finite everywhere.
        let green_x = 0.5 * (lx * lx - 1.0);
        let inner: Vec<f64> = field
            .nodes
            .iter()
            .filter(|n| n.status == NodeStatus::Ok as u32)
            .map(|n| n.exx as f64)
            .collect();
        let mean = inner.iter().sum::<f64>() / inner.len() as f64;
        assert!(
            (mean - green_x).abs() < 1e-3,
            "node mean green exx {mean} vs {green_x}"
        );
    }
    let proc = bench.proc(p);
    let status = proc.wait_exit();
    assert!(status.success(), "{status:?}");
    let last = final_line(proc);
    assert!(last.contains("--max-frames"), "{last}");
    bench.finish();
}

/// The published node gradients (layout 4) of a homogeneous stretch with a little shear
/// against the exact F − I, with IC-GN (its own gradient) and CORRELI (the neighbours'
/// least-squares fit), and the header's `gradient_source` naming which.
#[test]
fn published_gradient_of_a_stretch_matches_the_truth() {
    let centre = [(W as f64 - 1.0) / 2.0, (H as f64 - 1.0) / 2.0];
    let cases = [
        ("icgn1", "33", wire::GradientSource::Icgn1, 5e-4, 5e-3),
        (
            "correli",
            "32",
            wire::GradientSource::NeighbourFit,
            5e-4,
            8e-3,
        ),
    ];
    eprintln!("method  frame  F-I truth (xx xy yx yy)           mean error (xx xy yx yy)            max |error|  valid");
    for (method, zoi, source, mean_margin, node_margin) in cases {
        let mut bench = Bench::new(&format!("gradient_{method}"), W * H);
        let p = bench.spawn_correlator(&[
            "--method",
            method,
            "--zoi",
            zoi,
            "--step",
            "16",
            "--threads",
            "2",
        ]);
        bench.proc(p).wait_line("correlator: ready");
        let stretches = [
            (0.0, 0.0, 0.0),
            (0.03, -0.01, 0.01),
            (0.06, -0.02, 0.02),
            (0.10, -0.03, 0.03),
        ];
        for (id, &(ex, ey, shear)) in stretches.iter().enumerate() {
            let f = [[1.0 + ex, shear], [0.0, 1.0 + ey]];
            let (motion, truth) = affine(f, [0.3, -0.2], centre);
            let pixels = render(W, H, &motion, 700 + id as u64);
            let header = Bench::header(id as u64, W, H, &pixels, Some(truth));
            bench.send_frame(header, &pixels);
            let field = bench.next_field();
            assert_copied_through(&field, &header);
            let h = field.header;
            assert_eq!(h.origin_frame_id, 0);
            assert_eq!(h.gradient_source, source as u32, "{method}");
            let exact = [f[0][0] - 1.0, f[0][1], f[1][0], f[1][1] - 1.0];
            let ok: Vec<_> = field
                .nodes
                .iter()
                .filter(|n| n.status == NodeStatus::Ok as u32)
                .collect();
            assert!(
                ok.len() * 4 >= field.nodes.len() * 3,
                "{method} frame {id}: {} ok",
                ok.len()
            );
            let (mut mean, mut worst) = ([0.0f64; 4], 0.0f64);
            for n in &ok {
                let g = [n.du_dx, n.du_dy, n.dv_dx, n.dv_dy];
                for c in 0..4 {
                    let e = f64::from(g[c]) - exact[c];
                    mean[c] += e / ok.len() as f64;
                    worst = worst.max(e.abs());
                }
            }
            // Most nodes are ok (at 10 % the border ones left the image); refused nodes carry no
            // gradient.
            for n in field
                .nodes
                .iter()
                .filter(|n| n.status != NodeStatus::Ok as u32)
            {
                assert_eq!([n.du_dx, n.du_dy, n.dv_dx, n.dv_dy], [0.0; 4]);
            }
            eprintln!(
                "{method:7} {id:5}  {:+.3} {:+.3} {:+.3} {:+.3}   {:+.1e} {:+.1e} {:+.1e} {:+.1e}   {worst:.1e}      {}/{}",
                exact[0], exact[1], exact[2], exact[3], mean[0], mean[1], mean[2], mean[3],
                ok.len(),
                field.nodes.len()
            );
            assert!(
                mean.iter().all(|m| m.abs() <= mean_margin),
                "{method} frame {id}: mean error {mean:?}"
            );
            assert!(
                worst <= node_margin,
                "{method} frame {id}: node error {worst}"
            );
        }
        bench.finish();
    }
}

/// Frames much faster than the correlator: it always works on the newest, the camera's queue
/// overflows instead of growing (frames lost), superseded frames are skipped, and every field
/// says how many frames were dropped so far; the totals agree with the final line.
#[test]
fn a_burst_is_dropped_and_counted_never_queued() {
    let mut bench = Bench::new("burst", W * H);
    // Step 2 px: 12769 ZOIs per frame, a long correlation next to a publish (a memcpy).
    let p = bench.spawn_correlator(&["--step", "2", "--guess", "correli"]);
    bench.proc(p).wait_line("correlator: ready");
    const LAST: u64 = 30;
    let frames: Vec<(Vec<u16>, wire::GroundTruth)> = (0..=LAST)
        .map(|k| {
            let (motion, truth) = translation(0.02 * k as f64, -0.01 * k as f64);
            (render(W, H, &motion, 300 + k), truth)
        })
        .collect();
    let header = Bench::header(0, W, H, &frames[0].0, Some(frames[0].1));
    bench.send_frame(header, &frames[0].0);
    let first = bench.next_field();
    assert_eq!(first.header.frame_id, 0);
    for (k, (pixels, truth)) in frames.iter().enumerate().skip(1) {
        let header = Bench::header(k as u64, W, H, pixels, Some(*truth));
        // The camera is never blocked: every publish returns at once.
        bench.send_frame(header, pixels);
    }
    let fields = bench.fields_until(LAST);
    let ids: Vec<u64> = fields.iter().map(|f| f.header.frame_id).collect();
    let dropped: Vec<u64> = fields.iter().map(|f| f.header.frames_dropped).collect();
    eprintln!("fields after the burst: frame ids {ids:?}, frames_dropped {dropped:?}");
    assert!(ids.windows(2).all(|w| w[0] < w[1]), "frame ids increase");
    // Every frame id not correlated up to a field is counted in that field's frames_dropped.
    for (i, f) in fields.iter().enumerate() {
        let correlated_so_far = 2 + i as u64; // frame 0 and the fields up to this one
        assert_eq!(
            f.header.frames_dropped,
            f.header.frame_id + 1 - correlated_so_far,
            "field {i}: {:?}",
            f.header
        );
        let [(mu, _), (mv, _)] = f.error_stats(&f.header.truth);
        assert!(mu.abs() < 0.01 && mv.abs() < 0.01);
    }
    assert!(
        fields.len() < LAST as usize,
        "some frames must have been dropped"
    );
    let proc = bench.proc(p);
    proc.signal(libc::SIGTERM);
    assert!(proc.wait_exit().success());
    let last = final_line(proc);
    let received = number_after(&last, "frames in");
    let correlated = number_after(&last, "correlated");
    let dropped_total = number_after(&last, "dropped");
    let skipped = number_after(&last, "skipped");
    let lost = number_after(&last, "lost");
    eprintln!("{last}");
    assert_eq!(correlated, 1 + fields.len() as u64, "{last}");
    assert_eq!(dropped_total, LAST + 1 - correlated, "{last}");
    assert_eq!(dropped_total, skipped + lost, "{last}");
    assert_eq!(received, correlated + skipped, "{last}");
    // Bounded queue: frames were lost in the camera's queue (safe overflow) instead of all
    // 31 reaching the correlator late.
    assert!(lost > 0 && received < LAST + 1, "{last}");
    assert_eq!(*dropped.last().unwrap(), dropped_total);
    bench.finish();
}

/// Bad frames over the wire are logged errors, never a crash: a header whose size disagrees
/// with its payload, an unknown bit depth, an old layout version, another size than the
/// reference. A flat first frame is not taken as the reference; a flat frame later gives a
/// field of low-contrast nodes, no NaN; a frame of other material a field with no node ok;
/// both are warnings.
#[test]
fn bad_frames_are_logged_and_skipped() {
    let mut bench = Bench::new("bad_input", W * H);
    let p = bench.spawn_correlator(&[]);
    bench.proc(p).wait_line("correlator: ready");
    let (still, truth0) = translation(0.0, 0.0);
    let reference = render(W, H, &still, 7);
    let flat = vec![1000u16; W * H];

    // 0. A flat first frame (lens cap on) is not taken as the reference.
    bench.send_frame(Bench::header(100, W, H, &flat, None), &flat);
    let line = bench.proc(p).wait_line("frame 100 rejected");
    assert!(line.contains("flat"), "{line}");

    // 1. Header says 256 x 257, the payload holds 256 x 256.
    let mut lying = Bench::header(101, W, H, &reference, Some(truth0));
    lying.height_px = H as u32 + 1;
    bench.send_frame(lying, &reference);
    let line = bench.proc(p).wait_line("frame 101 rejected");
    assert!(line.contains("payload holds 65536"), "{line}");
    // 2. Bit depth 9.
    let mut odd = Bench::header(102, W, H, &reference, Some(truth0));
    odd.bit_depth = 9;
    bench.send_frame(odd, &reference);
    let line = bench.proc(p).wait_line("frame 102 rejected");
    assert!(line.contains("bit depth 9"), "{line}");
    // 3. Another layout version.
    let mut old = Bench::header(103, W, H, &reference, Some(truth0));
    old.layout_version = 0;
    bench.send_frame(old, &reference);
    bench.proc(p).wait_line("frame 103 rejected");
    // 4. A good frame: the reference.
    let header = Bench::header(104, W, H, &reference, Some(truth0));
    bench.send_frame(header, &reference);
    let field = bench.next_field();
    assert_eq!(field.header.frame_id, 104);
    assert_eq!(field.header.reference_frame_id, 104);
    // 5. A consistent frame of another size.
    let small = render(128, 128, &still, 8);
    bench.send_frame(Bench::header(105, 128, 128, &small, None), &small);
    let line = bench.proc(p).wait_line("frame 105 rejected");
    assert!(
        line.contains("128x128 px but the reference is 256x256 px"),
        "{line}"
    );
    // 6. A flat frame: every node low contrast, no node value NaN, a warning.
    bench.send_frame(Bench::header(106, W, H, &flat, None), &flat);
    let line = bench.proc(p).wait_line("frame 106: only 0 of");
    assert!(line.contains("low_contrast"), "{line}");
    let field = bench.next_field();
    assert_eq!(field.header.frame_id, 106);
    assert_eq!(field.header.valid_nodes, 0);
    assert!(field
        .nodes
        .iter()
        .all(|n| n.status == NodeStatus::LowContrast as u32));
    assert!(field
        .nodes
        .iter()
        .all(|n| [n.u_px, n.v_px, n.exx, n.eyy, n.exy, n.score]
            .iter()
            .all(|v| v.is_finite())));
    let h = field.header;
    assert!(h.u_mean_px.is_finite() && h.v_mean_px.is_finite());
    // The control gauge has no valid node: no reading, NaN (never a silent 0 a strain loop
    // would close on; it holds instead).
    assert!(h
        .gauge
        .iter()
        .all(|g| g.exx.is_nan() && g.eyy.is_nan() && g.exy.is_nan()));
    // 7. A frame of other material: the correlation finds a best match everywhere, the
    // final check refuses every one; nothing is published as ok.
    let other = unrelated_speckle(W, H, 10);
    bench.send_frame(Bench::header(107, W, H, &other, None), &other);
    bench.proc(p).wait_line("frame 107: only 0 of");
    let field = bench.next_field();
    assert_eq!(field.header.frame_id, 107);
    assert_eq!(field.header.valid_nodes, 0);
    assert!(field
        .nodes
        .iter()
        .all(|n| n.status != NodeStatus::Ok as u32));
    // 8. The process is still measuring.
    let (moved, truth) = translation(0.4, -0.3);
    let pixels = render(W, H, &moved, 9);
    bench.send_frame(Bench::header(108, W, H, &pixels, Some(truth)), &pixels);
    let field = bench.next_field();
    assert_eq!(field.header.frame_id, 108);
    let [(mu, _), (mv, _)] = field.error_stats(&truth);
    assert!(mu.abs() < 0.01 && mv.abs() < 0.01);
    let proc = bench.proc(p);
    proc.signal(libc::SIGTERM);
    assert!(proc.wait_exit().success());
    let last = final_line(proc);
    assert_eq!(number_after(&last, "rejected"), 5, "{last}");
    assert_eq!(number_after(&last, "correlated"), 4, "{last}");
    bench.finish();
}

/// --idle-timeout-s: the process stops by itself when no frame comes, with status 0.
#[test]
fn idle_timeout_ends_the_process() {
    let mut bench = Bench::new("idle", W * H);
    let p = bench.spawn_correlator(&["--idle-timeout-s", "0.5"]);
    let proc = bench.proc(p);
    proc.wait_line("correlator: ready");
    assert!(proc.wait_exit().success());
    let last = final_line(proc);
    assert!(last.contains("idle timeout"), "{last}");
    assert_eq!(number_after(&last, "frames in"), 0, "{last}");
    bench.finish();
}

/// A new frame sequence (the next test on a new specimen) starts from a new reference: its
/// first frame becomes reference and origin, and displacements count from it.
#[test]
fn a_new_frame_sequence_takes_a_new_reference() {
    let mut bench = Bench::new("sequence", W * H);
    let p = bench.spawn_correlator(&["--zoi", "32", "--step", "16", "--threads", "2"]);
    bench.proc(p).wait_line("correlator: ready");
    // Sequence 0: reference at rest, then a 0.4 px move.
    // Sequence 1: starts displaced by 0.4 px (a new reference there), then moves 0.3 px more.
    let frames = [(0u32, 0.0), (0, 0.4), (1, 0.4), (1, 0.7)];
    for (id, &(sequence, u)) in frames.iter().enumerate() {
        let (motion, truth) = translation(u, 0.0);
        let pixels = render(W, H, &motion, 300 + id as u64);
        let mut header = Bench::header(id as u64, W, H, &pixels, Some(truth));
        header.sequence_id = sequence;
        bench.send_frame(header, &pixels);
        let field = bench.next_field();
        let h = field.header;
        assert_eq!(h.sequence_id, sequence);
        let (origin, expected_u) = match id {
            0 | 1 => (0, u),
            _ => (2, u - 0.4),
        };
        assert_eq!(h.origin_frame_id, origin, "frame {id}");
        assert_eq!(h.reference_frame_id, origin, "frame {id}");
        assert!(
            (h.u_mean_px - expected_u).abs() < 0.01,
            "frame {id}: u {} expected {expected_u}",
            h.u_mean_px
        );
    }
    let line = bench.proc(p).wait_line("starts frame sequence 1");
    assert!(line.contains("frame 2"), "{line}");
    bench.finish();
}
