//! The camera image as the page shows it: a frame of `u16` pixels reduced by a box filter to at
//! most [`MAX_SIDE_PX`] on its longer side, scaled to 8 bits by its bit depth, and encoded as a
//! grey PNG. Pure; runs on the monitoring side at a capped rate (see `state.rs`), never in the
//! camera or the correlator.

/// Longest side of the image sent to viewers (px): about 60 kB of PNG for a speckle image.
pub const MAX_SIDE_PX: usize = 384;

/// A downsampled 8-bit image.
#[derive(Clone, Debug, PartialEq)]
pub struct Thumbnail {
    pub width_px: usize,
    pub height_px: usize,
    /// Full-resolution pixels per thumbnail pixel (on each side).
    pub factor: usize,
    pub pixels: Vec<u8>,
}

/// The reduction factor that brings `width` x `height` within `max_side` px.
pub fn factor_for(width_px: usize, height_px: usize, max_side_px: usize) -> usize {
    width_px.max(height_px).div_ceil(max_side_px.max(1)).max(1)
}

/// Box-filters `pixels` (`width_px` wide, row-major) by the factor that fits `max_side_px`,
/// keeping the top `8` of `bit_depth` bits. Incomplete blocks at the right and bottom edges are
/// dropped. `None` for an empty or inconsistent frame.
pub fn downsample(
    pixels: &[u16],
    width_px: usize,
    height_px: usize,
    bit_depth: u32,
    max_side_px: usize,
) -> Option<Thumbnail> {
    if width_px == 0 || height_px == 0 || pixels.len() != width_px * height_px {
        return None;
    }
    let factor = factor_for(width_px, height_px, max_side_px);
    let (w, h) = (width_px / factor, height_px / factor);
    if w == 0 || h == 0 {
        return None;
    }
    let shift = bit_depth.clamp(8, 16) - 8;
    let area = (factor * factor) as u64;
    let mut out = vec![0u8; w * h];
    let mut sums = vec![0u64; w];
    for ty in 0..h {
        sums.iter_mut().for_each(|s| *s = 0);
        for row in pixels[ty * factor * width_px..][..factor * width_px].chunks_exact(width_px) {
            for (tx, sum) in sums.iter_mut().enumerate() {
                *sum += row[tx * factor..][..factor]
                    .iter()
                    .map(|&p| u64::from(p))
                    .sum::<u64>();
            }
        }
        for (o, s) in out[ty * w..][..w].iter_mut().zip(&sums) {
            *o = ((s / area) >> shift).min(255) as u8;
        }
    }
    Some(Thumbnail {
        width_px: w,
        height_px: h,
        factor,
        pixels: out,
    })
}

/// The thumbnail as a grey 8-bit PNG.
pub fn encode_png(thumbnail: &Thumbnail) -> Result<Vec<u8>, String> {
    use image::ImageEncoder as _;
    let mut png = Vec::with_capacity(thumbnail.pixels.len() / 2);
    image::codecs::png::PngEncoder::new_with_quality(
        &mut png,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Sub,
    )
    .write_image(
        &thumbnail.pixels,
        thumbnail.width_px as u32,
        thumbnail.height_px as u32,
        image::ExtendedColorType::L8,
    )
    .map_err(|e| format!("encoding the dashboard image: {e}"))?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_frame_fits_the_cap_and_keeps_its_mean() {
        let (w, h) = (1024, 600);
        let pixels: Vec<u16> = (0..w * h).map(|i| ((i % 7) * 4096) as u16).collect();
        let t = downsample(&pixels, w, h, 16, MAX_SIDE_PX).unwrap();
        assert_eq!(t.factor, 3);
        assert_eq!((t.width_px, t.height_px), (341, 200));
        assert!(t.width_px <= MAX_SIDE_PX && t.height_px <= MAX_SIDE_PX);
        let mean = t.pixels.iter().map(|&p| f64::from(p)).sum::<f64>() / t.pixels.len() as f64;
        // The frame's mean, 3 * 4096 / 256 = 48 in 8 bits, within the truncation.
        assert!((mean - 48.0).abs() < 1.5, "{mean}");
    }

    #[test]
    fn bit_depth_scales_to_eight_bits_and_bad_frames_are_refused() {
        let t = downsample(&[1023; 16], 4, 4, 10, 4).unwrap();
        assert_eq!((t.factor, t.pixels[0]), (1, 255));
        assert!(downsample(&[0; 15], 4, 4, 16, 4).is_none());
        assert!(downsample(&[], 0, 0, 16, 4).is_none());
    }

    #[test]
    fn the_png_decodes_to_the_thumbnail() {
        let t = downsample(
            &(0..64 * 32).map(|i| i as u16).collect::<Vec<_>>(),
            64,
            32,
            12,
            64,
        )
        .unwrap();
        let png = encode_png(&t).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        let back = image::load_from_memory(&png).unwrap().to_luma8();
        assert_eq!(back.as_raw(), &t.pixels);
    }
}
