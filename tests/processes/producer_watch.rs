//! `dicstream producer --watch DIR` with real processes: a writer thread writes images slowly
//! into a folder (chunk by chunk with pauses, by rename from a temporary name, a pause longer
//! than the settle time mid-file, a truncated file, a garbage file, a file of another size)
//! while the producer runs and this test, subscribed to `frames` before the producer starts,
//! receives every frame. Each image published once, in natural order, never torn (the header's
//! checksum and the pixels equal the file's), the bad files reported and skipped; files present
//! at start ignored without `--from-start`; SIGINT ends the watch cleanly; a missing folder is
//! refused at start.
//!
//! Timeouts only guard against a hang; no assertion on a wall-clock time.

use crate::common;

use std::fmt::Debug;
use std::fs::File;
use std::io::{Cursor, Write};
use std::path::Path;
use std::time::{Duration, Instant};

use common::{Proc, Run};
use iceoryx2::prelude::*;
use image::{ImageBuffer, ImageFormat, Luma};
use wire::pubsub::SliceSubscriber;
use wire::services::ServiceSpec;
use wire::{services, FieldHeader, FieldNode, FrameHeader, Instance};

/// The producer's settle time in these tests, ms; pauses inside a file are shorter, except the
/// one long pause that is meant to outlast it.
const SETTLE_MS: u64 = 300;
const WIDTH: u32 = 160;
const HEIGHT: u32 = 120;

/// Starts `dicstream producer --watch <input> --instance <the run's> EXTRA` as `producer`.
fn start_producer<'a>(run: &'a mut Run, input: &Path, extra: &[&str]) -> &'a mut Proc {
    let instance = run.name().to_string();
    let input = input.to_str().expect("UTF-8 scratch path").to_string();
    let mut args = vec!["producer", "--watch", &input, "--instance", &instance];
    args.extend_from_slice(extra);
    run.spawn("producer", &args)
}

/// A sample as received: its header and a copy of its payload (copied at once, so the test
/// keeps up with the producer and never holds a sample).
struct Received<T, H> {
    header: H,
    payload: Vec<T>,
}

/// This test as a consumer of a service (`frames`, `fields`), subscribed before the publisher
/// exists.
struct Consumer<T: Debug + ZeroCopySend + Copy + 'static, H: Debug + ZeroCopySend + 'static> {
    _node: Node<ipc::Service>,
    subscriber: SliceSubscriber<T, H>,
    received: Vec<Received<T, H>>,
}

impl<T, H> Consumer<T, H>
where
    T: Debug + ZeroCopySend + Copy + 'static,
    H: Debug + ZeroCopySend + Default + Copy + 'static,
{
    fn new(instance: &Instance, spec: &ServiceSpec) -> Self {
        let (node, _) = instance.create_node("test").expect("test node");
        let subscriber = SliceSubscriber::create(&node, spec).expect("subscriber");
        Consumer {
            _node: node,
            subscriber,
            received: Vec::new(),
        }
    }

    /// Receives until `until` says stop (checked after every wake-up or 100 ms).
    fn receive_until(&mut self, mut until: impl FnMut(&[Received<T, H>]) -> bool) {
        let Consumer {
            subscriber,
            received,
            ..
        } = self;
        common::notified::wait_notified(subscriber.listener(), || {
            drain(subscriber, received);
            (!until(received)).then(|| format!("{} samples received", received.len()))
        });
        drain(subscriber, received);
    }
}

fn drain<T, H>(subscriber: &SliceSubscriber<T, H>, received: &mut Vec<Received<T, H>>)
where
    T: Debug + ZeroCopySend + Copy + 'static,
    H: Debug + ZeroCopySend + Default + Copy + 'static,
{
    subscriber.clear_events();
    while let Some(sample) = subscriber.receive().unwrap() {
        received.push(Received {
            header: *sample.user_header(),
            payload: sample.payload().to_vec(),
        });
    }
}

/// Pixels of test image `seed`: 16-bit values from a hash of seed and position, all different
/// images, nothing a decoder could guess.
fn pixels(seed: u64, width: u32, height: u32) -> Vec<u16> {
    (0..u64::from(width) * u64::from(height))
        .map(|i| {
            let mut z = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ i.wrapping_add(0xD1B5);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as u16
        })
        .collect()
}

/// The bytes of a 16-bit grayscale image file of `format`.
fn encode(pixels: &[u16], width: u32, height: u32, format: ImageFormat) -> Vec<u8> {
    let buffer: ImageBuffer<Luma<u16>, Vec<u16>> =
        ImageBuffer::from_raw(width, height, pixels.to_vec()).unwrap();
    let mut bytes = Cursor::new(Vec::new());
    buffer.write_to(&mut bytes, format).unwrap();
    bytes.into_inner()
}

/// Writes `bytes` to `path` in `chunks` pieces with `pause` after each but the last.
fn write_slowly(path: &Path, bytes: &[u8], chunks: usize, pause: Duration) {
    let mut file = File::create(path).unwrap();
    let size = bytes.len().div_ceil(chunks);
    for (k, chunk) in bytes.chunks(size).enumerate() {
        file.write_all(chunk).unwrap();
        file.flush().unwrap();
        if k + 1 < chunks {
            std::thread::sleep(pause);
        }
    }
}

/// The `--log` CSV rows: (frame id, file name, renamed).
fn log_rows(path: &Path) -> Vec<(u64, String, bool)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("frame_id,file,modified_unix_ns,size_bytes,renamed")
    );
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 5, "{line}");
            assert!(f[2].parse::<i128>().unwrap() > 0, "{line}");
            (
                f[0].parse().unwrap(),
                f[1].to_string(),
                f[4].parse().unwrap(),
            )
        })
        .collect()
}

#[test]
fn images_written_slowly_are_published_once_whole_in_natural_order_and_bad_files_skipped() {
    let mut run = Run::new("watch_slow");
    let input = run.temp_dir("in");
    let short = Duration::from_millis(SETTLE_MS / 4);
    let image = |seed: u64| pixels(seed, WIDTH, HEIGHT);
    let tiff = move |seed: u64| encode(&image(seed), WIDTH, HEIGHT, ImageFormat::Tiff);
    let png = move |seed: u64| encode(&image(seed), WIDTH, HEIGHT, ImageFormat::Png);

    // Present at start: published with --from-start, 9 before 10 (natural, not byte order).
    std::fs::write(input.join("img_10.tif"), tiff(10)).unwrap();
    std::fs::write(input.join("img_9.tif"), tiff(9)).unwrap();

    let mut consumer: Consumer<u16, FrameHeader> = Consumer::new(&run.instance, &services::FRAMES);
    let log = run.dir.join("frames_log.csv");
    start_producer(
        &mut run,
        &input,
        &[
            "--from-start",
            "--settle-ms",
            &SETTLE_MS.to_string(),
            "--idle-timeout-s",
            "3",
            "--log",
            log.to_str().unwrap(),
        ],
    );

    let writer_dir = input.clone();
    let writer = std::thread::spawn(move || {
        let dir = writer_dir;
        // Chunk by chunk, every pause shorter than the settle time.
        write_slowly(&dir.join("img_11.tif"), &tiff(11), 6, short);
        // A pause longer than the settle time mid-file: the half file looks complete, fails
        // to decode, and must not be published; the rest comes, then the whole file.
        let bytes = tiff(12);
        let mut file = File::create(dir.join("img_12.tif")).unwrap();
        file.write_all(&bytes[..bytes.len() / 2]).unwrap();
        file.flush().unwrap();
        std::thread::sleep(Duration::from_millis(SETTLE_MS * 3));
        file.write_all(&bytes[bytes.len() / 2..]).unwrap();
        drop(file);
        // Written slowly under temporary names, then renamed: complete at the rename.
        write_slowly(&dir.join("img_13.png.part"), &png(13), 4, short);
        std::thread::sleep(short);
        std::fs::rename(dir.join("img_13.png.part"), dir.join("img_13.png")).unwrap();
        write_slowly(&dir.join(".img_14.tif"), &tiff(14), 4, short);
        std::thread::sleep(short);
        std::fs::rename(dir.join(".img_14.tif"), dir.join("img_14.tif")).unwrap();
        // Garbage, a truncated TIFF, another size: reported and skipped.
        std::fs::write(
            dir.join("img_15.tif"),
            b"this is not an image at all".repeat(50),
        )
        .unwrap();
        let whole = tiff(16);
        std::fs::write(dir.join("img_16.tif"), &whole[..whole.len() / 3]).unwrap();
        let other = encode(&pixels(17, 64, 48), 64, 48, ImageFormat::Tiff);
        std::fs::write(dir.join("img_17.tif"), other).unwrap();
        // A temporary file never renamed, and a file of another kind: never read.
        std::fs::write(dir.join("img_18.tif.tmp"), tiff(18)).unwrap();
        std::fs::write(dir.join("notes.txt"), b"not an image").unwrap();
        // At once, in one write.
        std::fs::write(dir.join("img_19.png"), png(19)).unwrap();
    });

    consumer.receive_until(|_| !run.child("producer").is_running());
    writer.join().unwrap();
    let (status, stdout, stderr) = run.child("producer").wait();
    assert!(status.success(), "producer: {status}\n{stdout}\n{stderr}");
    // Shown with --nocapture: what the producer said.
    eprintln!("{stderr}\n{stdout}");
    assert!(
        stdout.contains("7 image(s) published, 3 skipped")
            && stdout.contains("without a new image"),
        "{stdout}"
    );

    // Published: each once, in natural order, with its name and mtime in the log.
    let expected = [
        "img_9.tif",
        "img_10.tif",
        "img_11.tif",
        "img_12.tif",
        "img_13.png",
        "img_14.tif",
        "img_19.png",
    ];
    let rows = log_rows(&log);
    let names: Vec<&str> = rows.iter().map(|(_, name, _)| name.as_str()).collect();
    assert_eq!(names, expected, "published files, in order\n{stderr}");
    assert_eq!(
        consumer.received.len(),
        expected.len(),
        "frames received\n{stderr}"
    );
    for (k, (frame, (id, name, renamed))) in consumer.received.iter().zip(&rows).enumerate() {
        let h = &frame.header;
        assert_eq!(h.frame_id, k as u64, "ids consecutive from 0");
        assert_eq!(*id, h.frame_id, "log row {k}");
        assert_eq!((h.width_px, h.height_px, h.bit_depth), (WIDTH, HEIGHT, 16));
        assert_eq!(h.has_truth, 0, "frame {k}: a watched file has no truth");
        assert_eq!(
            wire::frame::pixel_checksum(&frame.payload),
            h.pixel_checksum,
            "frame {k} ({name}) torn"
        );
        let seed: u64 = name[4..name.find('.').unwrap()].parse().unwrap();
        assert!(
            frame.payload == image(seed),
            "frame {k}: pixels are not those of {name}"
        );
        let on_disk = producer::read_image(input.join(name)).unwrap();
        assert!(
            frame.payload == on_disk.pixels,
            "frame {k} vs {name} on disk"
        );
        if name == "img_13.png" || name == "img_14.tif" {
            assert!(renamed, "{name} arrived by a rename\n{stderr}");
        }
    }

    // The bad files, reported and skipped, each named; the temporary file never read.
    for (name, why) in [
        ("img_15.tif", "cannot decode"),
        ("img_16.tif", "cannot decode"),
        ("img_17.tif", "64x48"),
    ] {
        assert!(
            stderr.lines().any(
                |l| l.contains(&format!("skipped {}", input.join(name).display()))
                    && l.contains(why)
            ),
            "{name} not reported as skipped ({why})\n{stderr}"
        );
    }
    assert!(stderr.contains("like the first frame"), "{stderr}");
    assert!(!stderr.contains("img_18"), "{stderr}");
    assert!(!stderr.contains("notes.txt"), "{stderr}");
}

#[test]
fn files_present_at_start_are_ignored_and_sigint_stops_the_watch_cleanly() {
    let mut run = Run::new("watch_sigint");
    let input = run.temp_dir("in");
    let tiff = |seed: u64| {
        encode(
            &pixels(seed, WIDTH, HEIGHT),
            WIDTH,
            HEIGHT,
            ImageFormat::Tiff,
        )
    };
    std::fs::write(input.join("old_1.tif"), tiff(1)).unwrap();
    let mut consumer: Consumer<u16, FrameHeader> = Consumer::new(&run.instance, &services::FRAMES);
    let settle_ms = SETTLE_MS.to_string();
    let producer = start_producer(&mut run, &input, &["--settle-ms", &settle_ms]);
    // The producer has looked at the folder once it says it is watching.
    producer.wait_line("producer: watching");
    std::fs::write(input.join("new_2.tif"), tiff(2)).unwrap();
    consumer.receive_until(|frames| !frames.is_empty());
    run.child("producer").signal(libc::SIGINT);
    consumer.receive_until(|_| !run.child("producer").is_running());
    let (status, stdout, stderr) = run.child("producer").wait();
    assert!(
        status.success(),
        "SIGINT is a clean stop\n{stdout}\n{stderr}"
    );
    assert!(stdout.contains("stopped by signal"), "{stdout}");
    assert_eq!(consumer.received.len(), 1, "{stderr}");
    assert!(consumer.received[0].payload == pixels(2, WIDTH, HEIGHT));
    assert!(stderr.contains("frame 0 <- new_2.tif"), "{stderr}");
    assert!(!stderr.contains("old_1"), "{stderr}");
}

/// The DIC Challenge's sample 5 (testdata/), 512 x 512, 8 bit: reference, u = v = 0,
/// u = v = +0.1 px (another noise realisation and contrast each).
const SAMPLE5: [&str; 3] = [
    "Sample5 Reference.tif",
    "Sample5-000 X0.00 Y0.00 N2 C75 R10.tif",
    "Sample5-001 X0.10 Y0.10 N2 C100 R20.tif",
];

#[test]
fn a_live_correlator_measures_dic_challenge_images_written_slowly_into_the_folder() {
    let Some(sample5) = testkit::shared_data("dic-challenge/sample5") else {
        return;
    };
    let mut run = Run::new("watch_correlator");
    let input = run.temp_dir("in");
    let mut fields: Consumer<FieldNode, FieldHeader> =
        Consumer::new(&run.instance, &services::FIELDS);
    let instance = run.name().to_string();
    run.spawn(
        "correlator",
        &["correlator", "--threads", "1", "--instance", &instance],
    )
    .wait_line("correlator: ready");
    // --from-start: the writer may begin before the producer's first look at the folder.
    start_producer(
        &mut run,
        &input,
        &[
            "--from-start",
            "--settle-ms",
            &SETTLE_MS.to_string(),
            "--idle-timeout-s",
            "3",
        ],
    );
    let writer = std::thread::spawn(move || {
        // Named so that natural order is the sequence order; each written in 8 chunks, the
        // last by rename from a temporary name.
        for (k, name) in SAMPLE5.iter().enumerate() {
            let bytes = std::fs::read(sample5.join(name)).unwrap();
            let target = input.join(format!("sample5_{}.tif", k + 1));
            if k == 2 {
                let temporary = input.join("sample5_3.tif.part");
                write_slowly(&temporary, &bytes, 8, Duration::from_millis(SETTLE_MS / 4));
                std::fs::rename(temporary, target).unwrap();
            } else {
                write_slowly(&target, &bytes, 8, Duration::from_millis(SETTLE_MS / 4));
            }
        }
    });
    fields.receive_until(|_| !run.child("producer").is_running());
    writer.join().unwrap();
    // The last field may come after the producer ended: wait for it (bounded, a hang guard).
    let give_up = Instant::now() + Duration::from_secs(30);
    fields.receive_until(|received| {
        received.iter().any(|f| f.header.frame_id == 2) || Instant::now() > give_up
    });
    let correlator_proc = run.child("correlator");
    correlator_proc.signal(libc::SIGTERM);
    let (correlator_status, _, correlator) = correlator_proc.wait();
    assert!(correlator_status.success(), "{correlator}");
    let (status, stdout, stderr) = run.child("producer").wait();
    assert!(status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("3 image(s) published, 0 skipped"),
        "{stdout}\n{stderr}"
    );
    eprintln!("{stderr}\n{stdout}");

    let ids: Vec<u64> = fields.received.iter().map(|f| f.header.frame_id).collect();
    assert!(
        ids.contains(&2),
        "no field of the last frame: {ids:?}\n{correlator}\n{stderr}"
    );
    assert!(
        ids.windows(2).all(|w| w[0] < w[1]),
        "each frame correlated once, in order: {ids:?}"
    );
    for field in &fields.received {
        eprintln!(
            "field of frame {}: mean u {:.4} px, v {:.4} px, {} of {} nodes valid",
            field.header.frame_id,
            field.header.u_mean_px,
            field.header.v_mean_px,
            field.header.valid_nodes,
            field.payload.len()
        );
        let h = &field.header;
        assert_eq!(h.has_truth, 0);
        assert_eq!(h.reference_frame_id, 0, "{correlator}");
        let expected_px = [0.0, 0.0, 0.1][h.frame_id as usize];
        assert!(
            h.valid_nodes as usize * 2 > field.payload.len(),
            "frame {}: {} of {} nodes valid\n{correlator}",
            h.frame_id,
            h.valid_nodes,
            field.payload.len()
        );
        for (axis, mean) in [("u", h.u_mean_px), ("v", h.v_mean_px)] {
            assert!(
                (mean - expected_px).abs() < 0.02,
                "frame {}: mean {axis} {mean:.4} px, imposed {expected_px} px",
                h.frame_id
            );
        }
    }
}

#[test]
fn a_missing_folder_is_refused_at_start() {
    let mut run = Run::new("watch_missing");
    // Never created.
    let input = run.dir.join("in");
    let (status, _, stderr) = start_producer(&mut run, &input, &["--idle-timeout-s", "1"]).wait();
    assert!(!status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("cannot watch {}", input.display())),
        "{stderr}"
    );
}
