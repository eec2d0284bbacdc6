//! A ZOI that runs off the specimen onto a flat backdrop (the room behind a cruciform, between
//! its arms; a dark background behind any sample): one of its sides is a band with no texture.
//! Such a ZOI correlates the specimen's edge as much as its speckle and passes the final check
//! off by up to 2 px, so it is refused as [`wire::NodeStatus::LowContrast`] like a flat one.
//!
//! The test: the grey-level standard deviation of each of the four bands along the ZOI's sides,
//! [`band_depth_px`] deep, and of each of its four corner squares, twice that wide, against
//! the whole ZOI's (corners from [`MIN_CORNER_PX`]). The corners catch a ZOI by a rounded re-entrant edge (a cruciform's
//! fillet), whose backdrop fills a corner and no whole band: on the default cruciform filmed
//! at 0.25 mm/px they had the run's largest errors (up to 1.3 px, against 0.9 px for the
//! fillet nodes whose ZOI is all on the specimen). A camera's backdrop is flat to its read
//! noise (a fraction of a count), so its band's ratio is below 0.01; the sparsest real pattern
//! here, DIC Challenge sample 14 (SEM), has no 32 px ZOI with a 4 px band below 0.049 (4,410
//! ZOIs at step 16), its median 0.71. [`MIN_SIDE_RATIO`] lies between, nearer the backdrop.

/// A side band whose standard deviation is below this fraction of the ZOI's is flat.
pub const MIN_SIDE_RATIO: f32 = 0.02;

/// Smallest corner square tested, px: a smaller one fits in the gap between a sparse
/// pattern's dots (9 px dots with 21 px subsets, `tests/suite/icgn.rs`), a backdrop's corner does not
/// need it (ZOIs of 32 px and more).
pub const MIN_CORNER_PX: usize = 8;

/// Depth of the side bands for a ZOI of `n` px: an eighth of it, at least 2 px.
pub fn band_depth_px(n: usize) -> usize {
    (n / 8).max(2)
}

/// Whether a side of the `n` x `n` zero-mean ZOI `g` (row-major), whose standard deviation is
/// `std`, is a flat band.
pub fn has_flat_side(g: &[f32], n: usize, std: f32) -> bool {
    debug_assert_eq!(g.len(), n * n);
    let d = band_depth_px(n);
    if d >= n {
        return false;
    }
    let floor = MIN_SIDE_RATIO * std;
    let flat = |pixels: &mut dyn Iterator<Item = f32>| band_std(pixels, d * n) < floor;
    let rows = |r0: usize| g[r0 * n..(r0 + d) * n].iter().copied();
    let columns = |c0: usize| {
        g.chunks_exact(n)
            .flat_map(move |row| row[c0..c0 + d].iter().copied())
    };
    let c = 2 * d;
    let corner = |r0: usize, c0: usize| {
        band_std(
            &mut (r0..r0 + c).flat_map(|r| g[r * n + c0..r * n + c0 + c].iter().copied()),
            c * c,
        ) < floor
    };
    flat(&mut rows(0))
        || flat(&mut rows(n - d))
        || flat(&mut columns(0))
        || flat(&mut columns(n - d))
        || (c >= MIN_CORNER_PX
            && c < n
            && (corner(0, 0) || corner(0, n - c) || corner(n - c, 0) || corner(n - c, n - c)))
}

/// Standard deviation of `count` values about their own mean.
fn band_std(values: &mut dyn Iterator<Item = f32>, count: usize) -> f32 {
    let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
    for v in values {
        sum += f64::from(v);
        sum_sq += f64::from(v) * f64::from(v);
    }
    let mean = sum / count as f64;
    ((sum_sq / count as f64 - mean * mean).max(0.0)).sqrt() as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A speckle-like texture (sum of incommensurate sines), zero-mean over the ZOI.
    fn textured(n: usize, flat_columns: usize) -> (Vec<f32>, f32) {
        let mut g: Vec<f32> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32, (i / n) as f32);
                if (x as usize) < flat_columns {
                    0.0
                } else {
                    100.0
                        + 40.0 * (1.3 * x).sin() * (0.9 * y).cos()
                        + 25.0 * (0.7 * x + 1.7 * y).sin()
                }
            })
            .collect();
        let mean = g.iter().sum::<f32>() / g.len() as f32;
        g.iter_mut().for_each(|v| *v -= mean);
        let std = (g.iter().map(|v| v * v).sum::<f32>() / g.len() as f32).sqrt();
        (g, std)
    }

    #[test]
    fn a_zoi_with_a_side_on_the_backdrop_is_flat_sided_and_a_textured_one_is_not() {
        let n = 32;
        let (whole, std) = textured(n, 0);
        assert!(!has_flat_side(&whole, n, std));
        // The specimen's edge 4 px inside the ZOI: the left band is backdrop.
        let (edge, std) = textured(n, 4);
        assert!(has_flat_side(&edge, n, std));
        // 3 px of backdrop: the 4 px band still holds a column of texture.
        let (sliver, std) = textured(n, 3);
        assert!(!has_flat_side(&sliver, n, std));
        // Backdrop along the bottom (the transposed case).
        let transposed: Vec<f32> = (0..n * n).map(|i| edge[(i % n) * n + i / n]).collect();
        assert!(has_flat_side(&transposed, n, std));
        // A rounded re-entrant edge: backdrop inside a circle about a point beyond the top
        // right corner fills that corner and no whole band.
        let (mut fillet, _) = textured(n, 0);
        for (i, v) in fillet.iter_mut().enumerate() {
            let (x, y) = ((i % n) as f32, (i / n) as f32);
            if (x - 40.0).hypot(y + 8.0) < 24.0 {
                *v = -100.0;
            }
        }
        let mean = fillet.iter().sum::<f32>() / fillet.len() as f32;
        fillet.iter_mut().for_each(|v| *v -= mean);
        let std = (fillet.iter().map(|v| v * v).sum::<f32>() / fillet.len() as f32).sqrt();
        assert!(has_flat_side(&fillet, n, std));
        // The same ZOI textured to its corner is not.
        assert!(!has_flat_side(&whole, n, textured(n, 0).1));
        assert_eq!(band_depth_px(8), 2);
        assert_eq!(band_depth_px(48), 6);
    }
}
