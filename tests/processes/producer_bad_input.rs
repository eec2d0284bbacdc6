//! Bad input to `dicstream producer` and `dicstream tap`, through the command line: each ends
//! with a non-zero exit and a message naming the input and what was expected.

use crate::common;

use common::Run;
use std::path::Path;

fn write_speckle_png(path: &Path, side: u32, seed: u32) {
    // Busy pixels, so that the compressed data is long and a truncation cuts into it.
    let img = image::GrayImage::from_fn(side, side, |x, y| {
        let h = (x.wrapping_mul(2_654_435_761) ^ y.wrapping_mul(40_503) ^ seed).wrapping_mul(97);
        image::Luma([(h >> 13) as u8])
    });
    img.save(path).expect("write test image");
}

/// Runs `producer --replay DIR` (at an unpaced rate) and returns its stderr after checking it
/// failed.
fn replay_fails(run: &mut Run, dir: &Path) -> String {
    let instance = run.name().to_string();
    let (status, _, stderr) = run.run_to_end(
        "producer",
        &[
            "producer",
            "--replay",
            dir.to_str().unwrap(),
            "--fps",
            "0",
            "--instance",
            &instance,
        ],
    );
    assert!(!status.success(), "bad replay accepted; stderr:\n{stderr}");
    assert!(stderr.contains("dicstream: error:"), "{stderr}");
    stderr
}

#[test]
fn replay_of_a_truncated_file_names_it() {
    let mut run = Run::new("bad_truncated");
    let dir = run.dir.join("images");
    std::fs::create_dir_all(&dir).unwrap();
    for k in 1..=3 {
        write_speckle_png(&dir.join(format!("frame_{k}.png")), 64, k);
    }
    let victim = dir.join("frame_2.png");
    let bytes = std::fs::read(&victim).unwrap();
    std::fs::write(&victim, &bytes[..bytes.len() / 2]).unwrap();
    let stderr = replay_fails(&mut run, &dir);
    assert!(stderr.contains("frame_2.png"), "{stderr}");
    assert!(stderr.contains("cannot decode image"), "{stderr}");
}

#[test]
fn replay_of_a_file_of_another_size_names_it_and_the_expected_size() {
    let mut run = Run::new("bad_size");
    let dir = run.dir.join("images");
    std::fs::create_dir_all(&dir).unwrap();
    write_speckle_png(&dir.join("frame_1.png"), 64, 1);
    write_speckle_png(&dir.join("frame_2.png"), 48, 2);
    let stderr = replay_fails(&mut run, &dir);
    assert!(
        stderr.contains("frame_2.png is 48x48 at 8 bit, expected 64x64 at 8 bit"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("producer: ready"),
        "checked before publishing"
    );
}

#[test]
fn replay_of_a_non_image_names_it() {
    let mut run = Run::new("bad_non_image");
    let dir = run.dir.join("images");
    std::fs::create_dir_all(&dir).unwrap();
    write_speckle_png(&dir.join("frame_1.png"), 32, 1);
    std::fs::write(dir.join("frame_2.png"), "not an image, only text\n").unwrap();
    let stderr = replay_fails(&mut run, &dir);
    assert!(stderr.contains("frame_2.png"), "{stderr}");
    assert!(stderr.contains("cannot decode image"), "{stderr}");
}

#[test]
fn replay_of_an_empty_folder_says_what_was_expected() {
    let mut run = Run::new("bad_empty");
    let dir = run.dir.join("images");
    std::fs::create_dir_all(&dir).unwrap();
    let stderr = replay_fails(&mut run, &dir);
    assert!(
        stderr.contains(&format!("no image found in {}", dir.display())),
        "{stderr}"
    );
    assert!(stderr.contains(".png, .tif, .tiff or .bmp"), "{stderr}");
}

#[test]
fn unknown_scenario_lists_the_known_ones() {
    let mut run = Run::new("bad_scenario");
    let instance = run.name().to_string();
    let (status, _, stderr) = run.run_to_end(
        "producer",
        &["producer", "--scenario", "wobble", "--instance", &instance],
    );
    assert!(!status.success());
    assert!(stderr.contains("unknown scenario 'wobble'"), "{stderr}");
    for name in producer::SCENARIO_NAMES {
        assert!(stderr.contains(name), "{name} not listed: {stderr}");
    }
}

/// A frame side of 0 or 3 px is an error naming it, not a panic (it was: rc 101).
#[test]
fn a_frame_side_out_of_range_is_refused() {
    let mut run = Run::new("bad_side");
    let instance = run.name().to_string();
    let out = std::env::temp_dir().join(format!("bad_side_{}", std::process::id()));
    let out = out.to_str().unwrap().to_string();
    for args in [
        vec!["synth", "--width", "0", "--frames", "1", "--out", &out],
        vec![
            "producer",
            "--height",
            "3",
            "--frames",
            "1",
            "--instance",
            &instance,
        ],
    ] {
        let (status, _, stderr) = run.run_to_end("producer", &args);
        assert_eq!(status.code(), Some(1), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(
            stderr.contains("expected a frame side in [8, 16384] px"),
            "{stderr}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// The frame service must fit in `/dev/shm`: a size that does not is refused at start, before
/// the camera is built (no "ready"), with the free and needed space. The size is chosen from
/// the machine's actual free space.
#[test]
fn frames_larger_than_dev_shm_are_refused_at_start() {
    let free = wire::shm::free_bytes(wire::shm::SHM_PATH).expect("statvfs /dev/shm");
    let side = [2048u32, 4096, 8192, 12288, 16384]
        .into_iter()
        .find(|&side| producer::stream::frames_shm_bytes(side, side) > free);
    let Some(side) = side else {
        eprintln!(
            "skipped: /dev/shm has {free} bytes free, more than the largest frame service needs"
        );
        return;
    };
    let mut run = Run::new("bad_shm");
    let instance = run.name().to_string();
    let side_text = side.to_string();
    for extra in [&[][..], &["--follow-rig"][..]] {
        let mut args = vec![
            "producer",
            "--scenario",
            "static",
            "--width",
            &side_text,
            "--height",
            &side_text,
            "--instance",
            &instance,
        ];
        if !extra.is_empty() {
            args.retain(|a| *a != "--scenario" && *a != "static");
            args.extend_from_slice(extra);
        }
        let (status, _, stderr) = run.run_to_end("producer", &args);
        assert!(!status.success(), "{side}x{side} accepted: {stderr}");
        assert!(stderr.contains("/dev/shm has"), "{stderr}");
        assert!(
            stderr.contains("MiB free but the services need"),
            "{stderr}"
        );
        assert!(!stderr.contains("producer: ready"), "{stderr}");
    }
    // What fits is accepted by the same check.
    producer::stream::check_shm_for_frames(256, 256).expect("a 256x256 service fits");
}

#[test]
fn tap_of_an_unknown_service_lists_the_known_ones() {
    let mut run = Run::new("bad_tap");
    let instance = run.name().to_string();
    let (status, _, stderr) = run.run_to_end("tap", &["tap", "framez", "--instance", &instance]);
    assert!(!status.success());
    assert!(
        stderr.contains(
            "unknown service \"framez\": expected one of frames, fields, rig/state, identification"
        ),
        "{stderr}"
    );
}
