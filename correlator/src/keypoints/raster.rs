//! Image work of the detector on row-split threads: resampling into the normalised frame and
//! separable Gaussian blur.

use super::*;

/// Splits 0..n into `threads` contiguous ranges and maps them in parallel.
pub(super) fn par_map<T: Send, F: Fn(usize, usize) -> T + Sync>(
    n: usize,
    threads: usize,
    f: F,
) -> Vec<T> {
    let t = threads.max(1).min(n.max(1));
    if t <= 1 {
        return vec![f(0, n)];
    }
    let per = n.div_ceil(t);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..t)
            .map(|k| {
                let f = &f;
                let (a, b) = ((k * per).min(n), ((k + 1) * per).min(n));
                s.spawn(move || f(a, b))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| match h.join() {
                Ok(v) => v,
                Err(e) => std::panic::resume_unwind(e),
            })
            .collect()
    })
}

/// Runs `f(row_index, row)` over the rows of `out` in parallel.
pub(super) fn par_rows<F: Fn(usize, &mut [f32]) + Sync>(
    out: &mut [f32],
    width: usize,
    threads: usize,
    f: F,
) {
    if width == 0 || out.is_empty() {
        return;
    }
    let rows = out.len() / width;
    let t = threads.max(1).min(rows.max(1));
    let per = rows.div_ceil(t);
    if t <= 1 {
        for (y, row) in out.chunks_mut(width).enumerate() {
            f(y, row);
        }
        return;
    }
    std::thread::scope(|s| {
        for (ci, chunk) in out.chunks_mut(per * width).enumerate() {
            let f = &f;
            s.spawn(move || {
                for (k, row) in chunk.chunks_mut(width).enumerate() {
                    f(ci * per + k, row);
                }
            });
        }
    });
}

/// Resamples the region into the normalised frame (bilinear); outside the region the value is
/// the region mean.
pub(super) fn resample(
    out: &mut Vec<f32>,
    image: Image,
    rect: (usize, usize, usize, usize),
    frame: &Frame,
    threads: usize,
) {
    let (x0, y0, x1, y1) = rect;
    let iw = image.width_px;
    let px = image.pixels;
    let mut sum = 0.0f64;
    for y in y0..y1 {
        sum += px[y * iw + x0..y * iw + x1]
            .iter()
            .map(|&v| v as u64)
            .sum::<u64>() as f64;
    }
    let mean = (sum / ((x1 - x0) * (y1 - y0)) as f64) as f32;
    out.clear();
    out.resize(frame.w * frame.h, 0.0);
    let (xmax, ymax) = ((x1 - 1) as f64, (y1 - 1) as f64);
    par_rows(out, frame.w, threads, |j, row| {
        let start = frame.image_point([0.0, j as f64]);
        let (sx, sy) = (frame.inv[0][0], frame.inv[1][0]);
        for (i, o) in row.iter_mut().enumerate() {
            let x = start[0] + sx * i as f64;
            let y = start[1] + sy * i as f64;
            if x < x0 as f64 || y < y0 as f64 || x >= xmax || y >= ymax {
                *o = mean;
                continue;
            }
            // x, y >= 0 here: truncation is floor.
            let (xi, yi) = (x as usize, y as usize);
            let fx = (x - xi as f64) as f32;
            let fy = (y - yi as f64) as f32;
            let k = yi * iw + xi;
            let (a, b) = (px[k] as f32, px[k + 1] as f32);
            let (c, d) = (px[k + iw] as f32, px[k + iw + 1] as f32);
            let top = a + fx * (b - a);
            let bot = c + fx * (d - c);
            *o = top + fy * (bot - top);
        }
    });
}

/// A row-major single-channel image, borrowed with its size.
#[derive(Clone, Copy)]
pub(super) struct Raster<'a> {
    pub pixels: &'a [f32],
    pub width_px: usize,
    pub height_px: usize,
}

/// Separable Gaussian blur of `src` (standard deviation `sigma` px) into `dst`, with clamped
/// borders; `tmp` holds the horizontal pass.
pub(super) fn gaussian_blur(
    src: Raster<'_>,
    sigma: f64,
    dst: &mut Vec<f32>,
    tmp: &mut Vec<f32>,
    threads: usize,
) {
    let (w, h) = (src.width_px, src.height_px);
    let src = src.pixels;
    let r = (3.0 * sigma).ceil() as usize;
    let mut k: Vec<f32> = (0..=2 * r)
        .map(|i| {
            let d = i as f64 - r as f64;
            (-d * d / (2.0 * sigma * sigma)).exp() as f32
        })
        .collect();
    let s: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= s);
    tmp.clear();
    tmp.resize(w * h, 0.0);
    dst.clear();
    dst.resize(w * h, 0.0);
    let k = &k;
    par_rows(tmp, w, threads, |y, row| {
        let srow = &src[y * w..(y + 1) * w];
        row.iter_mut().for_each(|v| *v = 0.0);
        if w > 2 * r {
            // Interior: accumulate tap by tap over the row (vectorises).
            for (i, kv) in k.iter().enumerate() {
                for (o, sv) in row[r..w - r].iter_mut().zip(&srow[i..w - 2 * r + i]) {
                    *o += kv * sv;
                }
            }
        }
        for x in (0..r.min(w)).chain(w.saturating_sub(r).max(r.min(w))..w) {
            let mut acc = 0.0f32;
            for (i, kv) in k.iter().enumerate() {
                let xx = (x + i).saturating_sub(r).min(w - 1);
                acc += kv * srow[xx];
            }
            row[x] = acc;
        }
    });
    let tmp = &*tmp;
    par_rows(dst, w, threads, |y, row| {
        row.iter_mut().for_each(|v| *v = 0.0);
        for (i, kv) in k.iter().enumerate() {
            let yy = (y + i).saturating_sub(r).min(h - 1);
            let srow = &tmp[yy * w..(yy + 1) * w];
            for (o, sv) in row.iter_mut().zip(srow) {
                *o += kv * sv;
            }
        }
    });
}
