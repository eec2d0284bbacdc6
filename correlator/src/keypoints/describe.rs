//! Blobs, their bucketing over the image, the rotated binary test pattern, and matching of
//! binary descriptors (Hamming distance, ratio test, mutual nearest neighbours).

use super::*;

#[derive(Clone, Copy, Debug)]
pub(super) struct Blob {
    pub(super) u: [f64; 2],
    pub(super) x: [f64; 2],
    pub(super) strength: f32,
    pub(super) bright: bool,
}

/// Keeps the strongest blobs per cell of a GRID_CELLS² grid (in the normalised frame) so the
/// keypoints spread over the image, then at most MAX_KEYPOINTS overall.
pub(super) fn bucket(mut all: Vec<Blob>, w: usize, h: usize) -> Vec<Blob> {
    all.sort_by(|a, b| b.strength.total_cmp(&a.strength));
    let cells = GRID_CELLS * GRID_CELLS;
    let mut per_cell = vec![0usize; cells];
    let mut occupied = 0usize;
    let cell_of = |b: &Blob| {
        let cx = ((b.u[0] / w as f64 * GRID_CELLS as f64) as usize).min(GRID_CELLS - 1);
        let cy = ((b.u[1] / h as f64 * GRID_CELLS as f64) as usize).min(GRID_CELLS - 1);
        cy * GRID_CELLS + cx
    };
    for b in &all {
        let c = cell_of(b);
        if per_cell[c] == 0 {
            occupied += 1;
        }
        per_cell[c] += 1;
    }
    if occupied == 0 {
        return Vec::new();
    }
    let cap = MAX_KEYPOINTS.div_ceil(occupied);
    per_cell.iter_mut().for_each(|c| *c = 0);
    let mut out = Vec::with_capacity(MAX_KEYPOINTS);
    for b in all {
        let c = cell_of(&b);
        if per_cell[c] < cap {
            per_cell[c] += 1;
            out.push(b);
        }
    }
    out.truncate(MAX_KEYPOINTS);
    out
}

pub(super) fn spectral_norm(m: &[[f64; 2]; 2]) -> f64 {
    let a = m[0][0] * m[0][0] + m[1][0] * m[1][0];
    let b = m[0][0] * m[0][1] + m[1][0] * m[1][1];
    let c = m[0][1] * m[0][1] + m[1][1] * m[1][1];
    let tr = a + c;
    let disc = ((a - c) * (a - c) + 4.0 * b * b).sqrt();
    (0.5 * (tr + disc)).sqrt()
}

/// Deterministic test pairs: both points Gaussian (sigma = 0.4 R) clipped to the disc.
pub(super) fn brief_pattern() -> Vec<[f32; 4]> {
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let sigma = 0.4 * DESC_RADIUS;
    let point = |rng: &mut XorShift| loop {
        let (a, b) = rng.gauss_pair();
        let (x, y) = (a * sigma, b * sigma);
        if x * x + y * y <= DESC_RADIUS * DESC_RADIUS {
            return [x as f32, y as f32];
        }
    };
    (0..DESC_BITS)
        .map(|_| {
            let p = point(&mut rng);
            let q = point(&mut rng);
            [p[0], p[1], q[0], q[1]]
        })
        .collect()
}

#[inline]
pub(super) fn hamming(a: &[u64; DESC_WORDS], b: &[u64; DESC_WORDS]) -> u32 {
    let mut s = 0;
    for k in 0..DESC_WORDS {
        s += (a[k] ^ b[k]).count_ones();
    }
    s
}

/// Mutual nearest neighbours passing the ratio test, among blobs of the same polarity.
/// Returns (reference index, deformed index).
pub(super) fn match_sets(
    reference: &KeypointSet,
    deformed: &KeypointSet,
    threads: usize,
) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let groups = [
        (0..reference.bright, 0..deformed.bright),
        (
            reference.bright..reference.len(),
            deformed.bright..deformed.len(),
        ),
    ];
    for (rr, dr) in groups {
        let (rn, dn) = (rr.len(), dr.len());
        if rn < 2 || dn < 2 {
            continue;
        }
        let rd = &reference.descriptors[rr.clone()];
        let dd = &deformed.descriptors[dr.clone()];
        // Per deformed keypoint: best reference index, best and second distances;
        // per thread: best deformed index for every reference keypoint.
        let parts = par_map(dn, threads, |a, b| {
            let mut rows = Vec::with_capacity(b - a);
            let mut col = vec![(u32::MAX, usize::MAX); rn];
            for (di, d) in dd[a..b].iter().enumerate() {
                let (mut b1, mut b2, mut bi) = (u32::MAX, u32::MAX, 0usize);
                for (ri, r) in rd.iter().enumerate() {
                    let h = hamming(d, r);
                    if h < b2 {
                        if h < b1 {
                            b2 = b1;
                            b1 = h;
                            bi = ri;
                        } else {
                            b2 = h;
                        }
                    }
                    let c = &mut col[ri];
                    if h < c.0 {
                        *c = (h, a + di);
                    }
                }
                rows.push((b1, b2, bi));
            }
            (a, rows, col)
        });
        let mut col = vec![(u32::MAX, usize::MAX); rn];
        for (_, _, c) in &parts {
            for (m, v) in col.iter_mut().zip(c) {
                if v.0 < m.0 {
                    *m = *v;
                }
            }
        }
        for (a, rows, _) in &parts {
            for (k, &(b1, b2, bi)) in rows.iter().enumerate() {
                let di = a + k;
                if b1 <= MATCH_MAX_DIST && (b1 as f64) < MATCH_RATIO * b2 as f64 && col[bi].1 == di
                {
                    out.push((rr.start + bi, dr.start + di));
                }
            }
        }
    }
    out
}
