//! Replay: natural order, size/depth checks, and the bad inputs (truncated file, other size,
//! non-image, empty folder), each error naming the file.

use std::path::{Path, PathBuf};

use producer::{natural_cmp, read_image, FrameSource, ProducerError, Replay};

/// A fresh empty folder under the system temp dir, unique per test and process.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("producer-replay-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

fn write_gray8(path: &Path, width: u32, height: u32, seed: u8) {
    let img = image::GrayImage::from_fn(width, height, |x, y| {
        image::Luma([(x as u8).wrapping_mul(7) ^ (y as u8).wrapping_add(seed)])
    });
    img.save(path).expect("write test image");
}

fn write_gray16(path: &Path, width: u32, height: u32) {
    let img: image::ImageBuffer<image::Luma<u16>, Vec<u16>> =
        image::ImageBuffer::from_fn(width, height, |x, y| image::Luma([(x * 1000 + y) as u16]));
    img.save(path).expect("write test image");
}

#[test]
fn natural_sort_orders_numbers_by_value() {
    let mut names = vec![
        "frame10.png",
        "frame2.png",
        "frame1.png",
        "frame002b.png",
        "a.png",
    ];
    names.sort_by(|a, b| natural_cmp(a, b));
    assert_eq!(
        names,
        [
            "a.png",
            "frame1.png",
            "frame2.png",
            "frame002b.png",
            "frame10.png"
        ]
    );
}

#[test]
fn replays_folder_in_natural_order_with_exact_pixels() {
    let dir = temp_dir("order");
    for (k, name) in ["frame10.png", "frame2.png", "frame1.png"]
        .iter()
        .enumerate()
    {
        write_gray8(&dir.join(name), 8, 5, k as u8);
    }
    std::fs::write(dir.join("notes.txt"), "ignored: not an image extension").unwrap();
    let mut replay = Replay::open(&dir).expect("open replay");
    let names: Vec<_> = replay
        .files()
        .iter()
        .map(|p| p.file_name().unwrap().to_str().unwrap().to_owned())
        .collect();
    assert_eq!(names, ["frame1.png", "frame2.png", "frame10.png"]);
    let dims = replay.dims();
    assert_eq!((dims.width, dims.height, dims.bit_depth), (8, 5, 8));
    let mut out = vec![0u16; dims.len_px()];
    for k in 0..3u64 {
        let info = replay.next_frame(&mut out).unwrap().expect("a frame");
        assert_eq!(info.index, k);
        assert!(info.truth.is_none());
        let expected = read_image(&replay.files()[k as usize]).unwrap();
        assert_eq!(out, expected.pixels);
    }
    assert!(replay.next_frame(&mut out).unwrap().is_none());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn reads_16_bit_and_glob() {
    let dir = temp_dir("glob16");
    write_gray16(&dir.join("img_1.png"), 6, 4);
    write_gray16(&dir.join("img_2.tif"), 6, 4);
    write_gray8(&dir.join("other_1.png"), 3, 3, 0);
    let image = read_image(dir.join("img_2.tif")).unwrap();
    assert_eq!((image.width, image.height, image.bit_depth), (6, 4, 16));
    assert_eq!(image.pixels[6 + 5], 5001);
    let replay = Replay::open(dir.join("img_*")).expect("glob");
    assert_eq!(replay.files().len(), 2);
    assert_eq!(replay.dims().bit_depth, 16);
    std::fs::remove_dir_all(&dir).unwrap();
}

fn message(error: ProducerError) -> String {
    error.to_string()
}

#[test]
fn empty_folder_is_a_clear_error() {
    let dir = temp_dir("empty");
    let error = message(Replay::open(&dir).unwrap_err());
    assert!(error.contains("no image found"), "{error}");
    assert!(error.contains(dir.to_str().unwrap()), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn other_size_names_the_file() {
    let dir = temp_dir("size");
    write_gray8(&dir.join("a1.png"), 8, 5, 0);
    write_gray8(&dir.join("a2.png"), 9, 5, 0);
    let error = message(Replay::open(&dir).unwrap_err());
    assert!(error.contains("a2.png") && error.contains("9x5"), "{error}");
    assert!(error.contains("expected 8x5"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn other_depth_names_the_file() {
    let dir = temp_dir("depth");
    write_gray8(&dir.join("a1.png"), 6, 4, 0);
    write_gray16(&dir.join("a2.png"), 6, 4);
    let error = message(Replay::open(&dir).unwrap_err());
    assert!(
        error.contains("a2.png") && error.contains("16 bit"),
        "{error}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn non_image_names_the_file() {
    let dir = temp_dir("nonimage");
    write_gray8(&dir.join("a1.png"), 8, 5, 0);
    std::fs::write(dir.join("a2.png"), "this is text, not a PNG").unwrap();
    let error = message(Replay::open(&dir).unwrap_err());
    assert!(error.contains("a2.png"), "{error}");
    let error = message(read_image(dir.join("a2.png")).unwrap_err());
    assert!(
        error.contains("cannot decode image") && error.contains("a2.png"),
        "{error}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn truncated_file_names_the_file() {
    let dir = temp_dir("truncated");
    write_gray8(&dir.join("a1.png"), 64, 64, 0);
    write_gray8(&dir.join("a2.png"), 64, 64, 1);
    let full = std::fs::read(dir.join("a2.png")).unwrap();
    std::fs::write(dir.join("a2.png"), &full[..full.len() / 2]).unwrap();
    // The header survives, so the error comes when the pixels are decoded.
    let mut replay = Replay::open(&dir).expect("headers are intact");
    let mut out = vec![0u16; replay.dims().len_px()];
    replay.next_frame(&mut out).expect("first frame is fine");
    let error = message(replay.next_frame(&mut out).unwrap_err());
    assert!(error.contains("a2.png"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A file rewritten with another size while the replay runs: named, with the size it has and
/// the one expected (the message was "frame buffer holds 4096 pixels, expected 2304").
#[test]
fn a_file_rewritten_with_another_size_is_named() {
    let dir = temp_dir("rewritten");
    write_gray8(&dir.join("a1.png"), 64, 64, 0);
    write_gray8(&dir.join("a2.png"), 64, 64, 1);
    let mut replay = Replay::open(&dir).unwrap();
    let mut out = vec![0u16; replay.dims().len_px()];
    replay.next_frame(&mut out).expect("first frame is fine");
    write_gray8(&dir.join("a2.png"), 48, 48, 1);
    let error = message(replay.next_frame(&mut out).unwrap_err());
    assert!(
        error.contains("a2.png") && error.contains("48x48") && error.contains("64x64"),
        "{error}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn missing_file_names_the_file() {
    let error = message(read_image("/nonexistent/frame.png").unwrap_err());
    assert!(error.contains("/nonexistent/frame.png"), "{error}");
}

#[test]
fn wrong_buffer_is_an_error() {
    let dir = temp_dir("buffer");
    write_gray8(&dir.join("a1.png"), 8, 5, 0);
    let mut replay = Replay::open(&dir).unwrap();
    let mut out = vec![0u16; 3];
    let error = message(replay.next_frame(&mut out).unwrap_err());
    assert!(error.contains("expected 40"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn replays_dic_challenge_sample5_when_present() {
    let Some(dir) = testkit::shared_data("dic-challenge/sample5") else {
        return;
    };
    let mut replay = Replay::open(&dir).expect("sample5 replays");
    let dims = replay.dims();
    assert_eq!((dims.width, dims.height, dims.bit_depth), (512, 512, 8));
    assert_eq!(replay.files().len(), 3);
    let mut out = vec![0u16; dims.len_px()];
    let mut frames = 0;
    while let Some(info) = replay.next_frame(&mut out).unwrap() {
        assert_eq!(info.index, frames);
        assert!(out.iter().all(|&p| p < 256));
        frames += 1;
    }
    assert_eq!(frames, 3);
}

#[test]
fn looping_replay_starts_again_and_keeps_counting() {
    let dir = temp_dir("loop");
    write_gray8(&dir.join("f1.png"), 4, 3, 1);
    write_gray8(&dir.join("f2.png"), 4, 3, 2);
    let mut replay = Replay::open(&dir).expect("open replay");
    replay.set_looping(true);
    assert_eq!(replay.frames_total(), None);
    let mut out = vec![0u16; replay.dims().len_px()];
    let first = read_image(&replay.files()[0]).unwrap().pixels;
    let second = read_image(&replay.files()[1]).unwrap().pixels;
    for k in 0..5u64 {
        let info = replay
            .next_frame(&mut out)
            .unwrap()
            .expect("a looping replay never ends");
        assert_eq!(info.index, k);
        assert_eq!(&out, if k % 2 == 0 { &first } else { &second });
    }
    replay.set_looping(false);
    assert_eq!(replay.frames_total(), Some(2));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A PNG of a few dozen bytes that declares `width` x `height` px of 8-bit grey (signature,
/// IHDR, an empty IDAT, IEND; CRCs computed here).
fn png_header_only(width: u32, height: u32) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = 0xFFFF_FFFFu32;
        for &b in bytes {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 == 1 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
    let mut out = vec![0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];
    let mut chunk = |kind: &[u8; 4], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]); // 8 bit, grey, deflate, no filter, no interlace
    chunk(b"IHDR", &ihdr);
    chunk(b"IDAT", &[]);
    chunk(b"IEND", &[]);
    out
}

/// A tiny file declaring 100000 x 100000 px is refused from its header, naming the file and
/// the limit, before anything the size of the declared image is allocated.
#[test]
fn a_gigapixel_header_is_refused_at_once() {
    let dir = temp_dir("gigapixel");
    let path = dir.join("huge.png");
    std::fs::write(&path, png_header_only(100_000, 100_000)).unwrap();
    let error = read_image(&path).unwrap_err();
    assert!(
        matches!(error, ProducerError::ImageTooLarge { width: 100_000, .. }),
        "{error:?}"
    );
    let text = error.to_string();
    assert!(
        text.contains("huge.png") && text.contains("16384"),
        "{text}"
    );
    // A header within the limit is still read (and then fails on its missing data, not on
    // its size).
    std::fs::write(&path, png_header_only(64, 48)).unwrap();
    let error = read_image(&path).unwrap_err();
    assert!(
        !matches!(error, ProducerError::ImageTooLarge { .. }),
        "{error:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
