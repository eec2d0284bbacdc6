//! Writing frames (PNG 8/16, TIFF) and reading them back gives the same pixels; png8 refuses a
//! deeper camera; writes leave no temporary file behind.

use producer::{read_image, write_frame, FrameDims, ImageFormatOut};

#[test]
fn frames_round_trip_through_every_format() {
    let dir = std::env::temp_dir().join(format!("producer-image-out-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = (20u32, 12u32);
    let mut encoded = Vec::new();
    for (format, bits, expected_depth) in [
        (ImageFormatOut::Png8, 8u8, 8u8),
        (ImageFormatOut::Png16, 12, 16),
        (ImageFormatOut::Tiff, 8, 8),
        (ImageFormatOut::Tiff, 16, 16),
    ] {
        let max = (1u32 << bits) - 1;
        let pixels: Vec<u16> = (0..w * h).map(|i| ((i * 37) % (max + 1)) as u16).collect();
        let path = dir.join(format!("f{bits}.{}", format.extension()));
        let dims = FrameDims {
            width: w,
            height: h,
            bit_depth: bits,
        };
        write_frame(&path, dims, &pixels, format, &mut encoded).unwrap();
        let back = read_image(&path).unwrap();
        assert_eq!(
            (back.width, back.height, back.bit_depth),
            (w, h, expected_depth)
        );
        assert_eq!(back.pixels, pixels, "{format:?} at {bits} bit");
    }
    let dims = FrameDims {
        width: w,
        height: h,
        bit_depth: 12,
    };
    let error = write_frame(
        &dir.join("x.png"),
        dims,
        &vec![0; (w * h) as usize],
        ImageFormatOut::Png8,
        &mut encoded,
    )
    .unwrap_err()
    .to_string();
    assert!(error.contains("png16 or tiff"), "{error}");
    let leftovers = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .contains(".tmp")
        })
        .count();
    assert_eq!(leftovers, 0);
    std::fs::remove_dir_all(&dir).unwrap();
}
