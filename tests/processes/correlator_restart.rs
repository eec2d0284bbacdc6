//! Restart: a correlator with --state-dir killed by SIGKILL and started again resumes against
//! the same reference and keeps measuring the same total displacement; it loses only the frames
//! it missed, also with its state saved off the frame path. Compared with an uninterrupted correlator fed the same frames (another instance).

use crate::common;

use common::camera::{final_line, render, translation, Bench, FieldCopy};
use common::HANG_GUARD;
use wire::NodeStatus;

const W: usize = 256;
const H: usize = 256;
const FRAMES: u64 = 7;

/// Frame k: a translation of (0.45 k, -0.3 k) px.
fn truth_of(k: u64) -> (f64, f64) {
    (0.45 * k as f64, -0.3 * k as f64)
}

fn send(bench: &Bench, frames: &[Vec<u16>], k: u64) -> usize {
    let (u, v) = truth_of(k);
    let (_, truth) = translation(u, v);
    let pixels = &frames[k as usize];
    bench.send_frame(Bench::header(k, W, H, pixels, Some(truth)), pixels)
}

fn largest_difference(a: &FieldCopy, b: &FieldCopy) -> f64 {
    let mut largest = 0.0f64;
    for (na, nb) in a.nodes.iter().zip(&b.nodes) {
        assert_eq!(na.status, nb.status);
        if na.status == NodeStatus::Ok as u32 {
            largest = largest
                .max((na.u_px - nb.u_px).abs() as f64)
                .max((na.v_px - nb.v_px).abs() as f64);
        }
    }
    largest
}

fn restart_resumes(mode: &str, test: &str) {
    let frames: Vec<Vec<u16>> = (0..FRAMES)
        .map(|k| {
            let (u, v) = truth_of(k);
            render(W, H, &translation(u, v).0, 40 + k)
        })
        .collect();
    // ROI inside the image: border ZOIs never leave it, so every node stays valid.
    let args = [
        "--reference-mode",
        mode,
        "--guess",
        "predict",
        "--roi",
        "32,32,192,192",
    ];

    // The uninterrupted run.
    let mut plain = Bench::new(&format!("{test}_u"), W * H);
    let p = plain.spawn_correlator(&args);
    plain.proc(p).wait_line("correlator: ready");
    let mut uninterrupted = Vec::new();
    for k in 0..FRAMES {
        send(&plain, &frames, k);
        uninterrupted.push(plain.next_field());
    }

    // The run killed after frame 3.
    let mut bench = Bench::new(&format!("{test}_r"), W * H);
    let state_dir = bench.temp_dir("state");
    let state = state_dir.to_str().unwrap().to_string();
    let with_state: Vec<&str> = args
        .iter()
        .copied()
        .chain(["--state-dir", &state])
        .collect();
    let first = bench.spawn_correlator(&with_state);
    bench.proc(first).wait_line("correlator: ready");
    for k in 0..=3 {
        send(&bench, &frames, k);
        let field = bench.next_field();
        assert_eq!(field.header.frame_id, k);
    }
    // The state is saved off the frame path (a writer thread): the reference field 3 left
    // behind reaches the folder soon after the field, an earlier one of the same origin until
    // then (the first frame's, the origin, before its field).
    assert!(state_dir.join("reference.state").is_file());
    let expected_reference = if mode == "fixed" { 0 } else { 3 };
    let wanted = format!("\"reference_frame_id\": {expected_reference},");
    let started = std::time::Instant::now();
    let summary = loop {
        let summary = std::fs::read_to_string(state_dir.join("state.json")).unwrap();
        if summary.contains(&wanted) {
            break summary;
        }
        assert!(started.elapsed() < HANG_GUARD, "{summary}");
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    eprintln!("state.json after frame 3:\n{summary}");
    bench.proc(first).signal(libc::SIGKILL);
    let status = bench.proc(first).wait_exit();
    assert!(!status.success(), "SIGKILL: {status:?}");
    // Frame 4 is sent while no correlator runs: the only frame this run loses (it may still
    // land in the dead subscriber's queue until the next node cleans the dead node).
    send(&bench, &frames, 4);

    // A settings change on the same folder is refused with the difference named.
    let other: Vec<&str> = with_state.iter().copied().chain(["--zoi", "64"]).collect();
    let refused = bench.spawn_correlator(&other);
    let status = bench.proc(refused).wait_exit();
    assert!(!status.success());
    let message = bench.proc(refused).stderr();
    assert!(message.contains("ZOI 32 px there, 64 px now"), "{message}");

    // The restart: cleans the dead node, resumes against the saved reference.
    let second = bench.spawn_correlator(&with_state);
    let ready = bench.proc(second).wait_line("correlator: ready");
    assert!(
        ready.contains(&format!("resumed frame {expected_reference} from")),
        "{ready}"
    );
    // The first node created after the kill (here the refused run) removed the dead one.
    let cleaned = bench.proc(refused).stderr() + &bench.proc(second).stderr();
    assert!(cleaned.contains("cleaned 1 dead node"), "{cleaned}");
    let mut resumed = Vec::new();
    for k in 5..FRAMES {
        send(&bench, &frames, k);
        resumed.push(bench.next_field());
    }
    eprintln!(
        "mode {mode}: frame  truth u  uninterrupted u  resumed u   largest node difference (px)"
    );
    for field in &resumed {
        let k = field.header.frame_id;
        let reference = &uninterrupted[k as usize];
        let difference = largest_difference(field, reference);
        eprintln!(
            "           {k}    {:+.3}   {:+.4}          {:+.4}     {difference:.4}",
            truth_of(k).0,
            reference.header.u_mean_px,
            field.header.u_mean_px
        );
        assert_eq!(field.header.valid_nodes as usize, field.nodes.len());
        // The same total displacement: within the correlator's accuracy of the truth and of
        // the uninterrupted run (fixed: same reference, the predictor's start differs;
        // incremental: the uninterrupted run took frame 4 as reference, so two noise draws).
        let [(mu, su), (mv, sv)] = field.error_stats(&field.header.truth);
        assert!(mu.abs() < 0.02 && mv.abs() < 0.02, "{mu} {mv}");
        assert!(su < 0.03 && sv < 0.03, "{su} {sv}");
        let tolerance = if mode == "fixed" { 0.02 } else { 0.06 };
        assert!(difference < tolerance, "{difference}");
        assert!(
            (field.header.u_mean_px - reference.header.u_mean_px).abs() < 0.01
                && (field.header.v_mean_px - reference.header.v_mean_px).abs() < 0.01
        );
    }
    assert_eq!(resumed[0].header.reference_frame_id, expected_reference);
    plain.proc(p).signal(libc::SIGTERM);
    assert!(plain.proc(p).wait_exit().success());
    bench.proc(second).signal(libc::SIGTERM);
    assert!(bench.proc(second).wait_exit().success());
    let last = final_line(bench.proc(second));
    assert!(last.contains("correlated 2"), "{last}");
    plain.finish();
    bench.finish();
}

#[test]
fn restart_after_sigkill_fixed_reference() {
    restart_resumes("fixed", "restart_fixed");
}

#[test]
fn restart_after_sigkill_incremental_reference() {
    restart_resumes("incremental", "restart_incr");
}
