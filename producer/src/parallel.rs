//! Row-parallel loops over a frame with `std::thread::scope`: the rows are split into
//! `threads` contiguous bands; no allocation beyond the threads themselves.

/// Calls `f(first_row, band)` for contiguous bands of whole rows of `out` (row length `width`),
/// on up to `threads` threads (1: the calling thread only).
pub fn for_row_bands<T: Send>(
    out: &mut [T],
    width: usize,
    threads: usize,
    f: impl Fn(usize, &mut [T]) + Sync,
) {
    assert!(
        width > 0 && out.len().is_multiple_of(width),
        "buffer is not whole rows of {width}"
    );
    let rows = out.len() / width;
    let threads = threads.clamp(1, rows.max(1));
    if threads == 1 {
        f(0, out);
        return;
    }
    let rows_per_band = rows.div_ceil(threads);
    std::thread::scope(|scope| {
        for (band_index, band) in out.chunks_mut(rows_per_band * width).enumerate() {
            let f = &f;
            scope.spawn(move || f(band_index * rows_per_band, band));
        }
    });
}

/// Threads to use by default: the available parallelism.
pub fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
