//! The grey-level image every stage of the correlator reads.

/// A grey-level image borrowed as row-major u16.
#[derive(Clone, Copy)]
pub struct Image<'a> {
    pub pixels: &'a [u16],
    pub width_px: usize,
    pub height_px: usize,
}

impl Image<'_> {
    /// True when the n x n block with top-left (x0, y0) lies inside the image.
    #[inline]
    pub fn contains_block(&self, x0: i64, y0: i64, n: usize) -> bool {
        x0 >= 0 && y0 >= 0 && x0 as usize + n <= self.width_px && y0 as usize + n <= self.height_px
    }
}
