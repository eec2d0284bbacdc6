//! Fits of keypoint correspondences: locally weighted quadratic and affine fits, the affine
//! map through three pairs, least squares, seeded RANSAC and the local-consistency pass.

use super::*;

/// Weighted least-squares quadratic fit of `pairs` around `p` (Gaussian radius `radius`),
/// returned as its linearisation at p (value and gradient there), which has no bias from the
/// curvature of the field. None when the support is too thin or degenerate.
pub(super) fn weighted_quadratic(
    pairs: &[([f64; 2], [f64; 2])],
    p: [f64; 2],
    radius: f64,
) -> Option<Affine2> {
    let inv2 = 1.0 / (2.0 * radius * radius);
    let mut s = [[0.0f64; 6]; 6];
    let mut b = [[0.0f64; 6]; 2];
    let (mut sw, mut sw2) = (0.0, 0.0);
    for (r, d) in pairs {
        let dx = r[0] - p[0];
        let dy = r[1] - p[1];
        let q = (dx * dx + dy * dy) * inv2;
        if q > 12.0 {
            continue;
        }
        let w = (-q).exp();
        let (x, y) = (dx / radius, dy / radius);
        let v = [1.0, x, y, x * x, x * y, y * y];
        for i in 0..6 {
            for j in 0..6 {
                s[i][j] += w * v[i] * v[j];
            }
            b[0][i] += w * v[i] * d[0];
            b[1][i] += w * v[i] * d[1];
        }
        sw += w;
        sw2 += w * w;
    }
    if sw <= 0.0 || sw * sw / sw2 < 25.0 {
        return None;
    }
    let cx = solve_n(s, b[0])?;
    let cy = solve_n(s, b[1])?;
    let a = [
        [cx[1] / radius, cx[2] / radius],
        [cy[1] / radius, cy[2] / radius],
    ];
    let t = [
        cx[0] - a[0][0] * p[0] - a[0][1] * p[1],
        cy[0] - a[1][0] * p[0] - a[1][1] * p[1],
    ];
    Some(Affine2 { a, t })
}

/// Gaussian elimination with partial pivoting; None when (nearly) singular.
pub(super) fn solve_n<const K: usize>(mut m: [[f64; K]; K], mut b: [f64; K]) -> Option<[f64; K]> {
    let scale = m.iter().flatten().fold(0.0f64, |acc, v| acc.max(v.abs()));
    if scale.is_nan() || scale <= 0.0 {
        return None;
    }
    for col in 0..K {
        let mut piv = col;
        for r in col + 1..K {
            if m[r][col].abs() > m[piv][col].abs() {
                piv = r;
            }
        }
        if m[piv][col].is_nan() || m[piv][col].abs() <= 1e-9 * scale {
            return None;
        }
        m.swap(col, piv);
        b.swap(col, piv);
        for r in col + 1..K {
            let f = m[r][col] / m[col][col];
            let pivot_row = m[col];
            for (v, p) in m[r][col..].iter_mut().zip(&pivot_row[col..]) {
                *v -= f * p;
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = [0.0; K];
    for r in (0..K).rev() {
        let mut acc = b[r];
        for c in r + 1..K {
            acc -= m[r][c] * x[c];
        }
        x[r] = acc / m[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Gaussian radius such that about 25 inliers fall within one radius on average.
pub(super) fn density_radius(pairs: &[([f64; 2], [f64; 2])]) -> f64 {
    if pairs.is_empty() {
        return 1.0;
    }
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for (r, _) in pairs {
        for k in 0..2 {
            lo[k] = lo[k].min(r[k]);
            hi[k] = hi[k].max(r[k]);
        }
    }
    let area = ((hi[0] - lo[0]) * (hi[1] - lo[1])).max(1.0);
    (25.0 * area / (std::f64::consts::PI * pairs.len() as f64))
        .sqrt()
        .max(8.0)
}

/// Weighted least-squares affine fit of `pairs` around `p` with Gaussian radius `radius`,
/// skipping index `skip`. None when the support is too thin or degenerate.
pub(super) fn weighted_affine(
    pairs: &[([f64; 2], [f64; 2])],
    p: [f64; 2],
    radius: f64,
    skip: Option<usize>,
) -> Option<Affine2> {
    let inv2 = 1.0 / (2.0 * radius * radius);
    let mut s = [[0.0f64; 3]; 3];
    let mut bx = [0.0f64; 3];
    let mut by = [0.0f64; 3];
    let (mut sw, mut sw2) = (0.0, 0.0);
    for (i, (r, d)) in pairs.iter().enumerate() {
        if Some(i) == skip {
            continue;
        }
        let dx = r[0] - p[0];
        let dy = r[1] - p[1];
        let q = (dx * dx + dy * dy) * inv2;
        if q > 4.5 {
            continue;
        }
        let w = (-q).exp();
        let v = [1.0, dx / radius, dy / radius];
        for a in 0..3 {
            for b in 0..3 {
                s[a][b] += w * v[a] * v[b];
            }
            bx[a] += w * v[a] * d[0];
            by[a] += w * v[a] * d[1];
        }
        sw += w;
        sw2 += w * w;
    }
    // Effective number of points and conditioning of the spatial spread.
    if sw <= 0.0 || sw * sw / sw2 < 10.0 {
        return None;
    }
    let cxx = s[1][1] / sw - (s[0][1] / sw).powi(2);
    let cyy = s[2][2] / sw - (s[0][2] / sw).powi(2);
    let cxy = s[1][2] / sw - s[0][1] * s[0][2] / (sw * sw);
    let det = cxx * cyy - cxy * cxy;
    if det < 0.01 {
        return None;
    }
    affine_from_normal_equations(&s, &bx, &by, radius, p)
}

/// The affine map from the normal equations `s` of a fit in coordinates (x − origin) / scale
/// with right-hand sides `bx`, `by` (for the x and y images): value and slopes per component.
pub(super) fn affine_from_normal_equations(
    s: &[[f64; 3]; 3],
    bx: &[f64; 3],
    by: &[f64; 3],
    scale: f64,
    origin: [f64; 2],
) -> Option<Affine2> {
    let cx = solve3(s, bx)?;
    let cy = solve3(s, by)?;
    let a = [
        [cx[1] / scale, cx[2] / scale],
        [cy[1] / scale, cy[2] / scale],
    ];
    let t = [
        cx[0] - a[0][0] * origin[0] - a[0][1] * origin[1],
        cy[0] - a[1][0] * origin[0] - a[1][1] * origin[1],
    ];
    Some(Affine2 { a, t })
}

/// Solves a 3x3 linear system by Cramer's rule.
pub(super) fn solve3(m: &[[f64; 3]; 3], b: &[f64; 3]) -> Option<[f64; 3]> {
    let det3 = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(m);
    let scale = m.iter().flatten().fold(0.0f64, |acc, v| acc.max(v.abs()));
    if !d.is_finite() || d.abs() <= 1e-12 * scale.powi(3) {
        return None;
    }
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut mk = *m;
        for r in 0..3 {
            mk[r][k] = b[r];
        }
        *o = det3(&mk) / d;
    }
    Some(out)
}

/// Exact affine map through three correspondences.
pub(super) fn affine_from3(p: [([f64; 2], [f64; 2]); 3]) -> Option<Affine2> {
    let (a, b, c) = (p[0], p[1], p[2]);
    let u = [b.0[0] - a.0[0], b.0[1] - a.0[1]];
    let v = [c.0[0] - a.0[0], c.0[1] - a.0[1]];
    let det = u[0] * v[1] - u[1] * v[0];
    // Reject thin triangles (area below ~50 px² or very flat).
    let lu = (u[0] * u[0] + u[1] * u[1]).sqrt();
    let lv = (v[0] * v[0] + v[1] * v[1]).sqrt();
    if det.abs() < 100.0 || det.abs() < 0.1 * lu * lv {
        return None;
    }
    let up = [b.1[0] - a.1[0], b.1[1] - a.1[1]];
    let vp = [c.1[0] - a.1[0], c.1[1] - a.1[1]];
    // A [u v] = [up vp]  =>  A = [up vp] [u v]^-1
    let inv = [[v[1] / det, -v[0] / det], [-u[1] / det, u[0] / det]];
    let m = [[up[0], vp[0]], [up[1], vp[1]]];
    let am = [
        [
            m[0][0] * inv[0][0] + m[0][1] * inv[1][0],
            m[0][0] * inv[0][1] + m[0][1] * inv[1][1],
        ],
        [
            m[1][0] * inv[0][0] + m[1][1] * inv[1][0],
            m[1][0] * inv[0][1] + m[1][1] * inv[1][1],
        ],
    ];
    let t = [
        a.1[0] - am[0][0] * a.0[0] - am[0][1] * a.0[1],
        a.1[1] - am[1][0] * a.0[0] - am[1][1] * a.0[1],
    ];
    Some(Affine2 { a: am, t })
}

/// Determinant positive and singular values within [0.2, 5].
pub(super) fn plausible(m: &Affine2) -> bool {
    let det = m.a[0][0] * m.a[1][1] - m.a[0][1] * m.a[1][0];
    if det.is_nan() || det <= 0.0 || !m.t[0].is_finite() || !m.t[1].is_finite() {
        return false;
    }
    let smax = spectral_norm(&m.a);
    let smin = det / smax;
    smin > 0.2 && smax < 5.0
}

pub(super) fn residual(m: &Affine2, p: &([f64; 2], [f64; 2])) -> f64 {
    let q = m.apply(p.0);
    ((q[0] - p.1[0]).powi(2) + (q[1] - p.1[1]).powi(2)).sqrt()
}

/// Unweighted least-squares affine fit (coordinates centred and scaled for conditioning).
pub(super) fn fit_affine(pairs: &[([f64; 2], [f64; 2])]) -> Option<Affine2> {
    if pairs.len() < 3 {
        return None;
    }
    let n = pairs.len() as f64;
    let mut c = [0.0; 2];
    for (r, _) in pairs {
        c[0] += r[0] / n;
        c[1] += r[1] / n;
    }
    let spread = (pairs
        .iter()
        .map(|(r, _)| (r[0] - c[0]).powi(2) + (r[1] - c[1]).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    if spread.is_nan() || spread < 1.0 {
        return None;
    }
    let mut s = [[0.0f64; 3]; 3];
    let mut bx = [0.0f64; 3];
    let mut by = [0.0f64; 3];
    for (r, d) in pairs {
        let v = [1.0, (r[0] - c[0]) / spread, (r[1] - c[1]) / spread];
        for a in 0..3 {
            for b in 0..3 {
                s[a][b] += v[a] * v[b];
            }
            bx[a] += v[a] * d[0];
            by[a] += v[a] * d[1];
        }
    }
    // Nearly collinear points: no affine map.
    let det = (s[1][1] * s[2][2] - s[1][2] * s[1][2]) / (n * n);
    if det < 1e-4 {
        return None;
    }
    affine_from_normal_equations(&s, &bx, &by, spread, c)
}

/// Seeded RANSAC for the affine map; returns the refined model and its inlier count.
pub(super) fn ransac(pairs: &[([f64; 2], [f64; 2])]) -> Option<(Affine2, usize)> {
    let n = pairs.len();
    if n < 3 {
        return None;
    }
    let mut rng = XorShift(0x2545_F491_4F6C_DD1D);
    let mut best: Option<(Affine2, usize)> = None;
    let mut needed = RANSAC_MAX_ITER;
    let mut it = 0;
    while it < needed.min(RANSAC_MAX_ITER) {
        it += 1;
        let i = rng.below(n);
        let j = rng.below(n);
        let k = rng.below(n);
        if i == j || j == k || i == k {
            continue;
        }
        let Some(m) = affine_from3([pairs[i], pairs[j], pairs[k]]) else {
            continue;
        };
        if !plausible(&m) {
            continue;
        }
        let count = pairs
            .iter()
            .filter(|p| residual(&m, p) < RANSAC_THRESHOLD)
            .count();
        if best.as_ref().is_none_or(|b| count > b.1) {
            best = Some((m, count));
            let w = count as f64 / n as f64;
            let p_fail = 1.0 - w * w * w;
            if p_fail <= 0.0 {
                needed = it;
            } else if p_fail < 1.0 {
                needed = ((1e-4f64).ln() / p_fail.ln()).ceil().max(50.0) as usize;
            }
        }
    }
    let (mut model, mut count) = best?;
    // Refine by least squares on the inliers (twice).
    for _ in 0..2 {
        let inl: Vec<_> = pairs
            .iter()
            .filter(|p| residual(&model, p) < RANSAC_THRESHOLD)
            .copied()
            .collect();
        let Some(m) = fit_affine(&inl) else { break };
        let c = pairs
            .iter()
            .filter(|p| residual(&m, p) < RANSAC_THRESHOLD)
            .count();
        if c >= count {
            model = m;
            count = c;
        } else {
            break;
        }
    }
    Some((model, count))
}

/// Second pass for non-affine fields: starting from the global RANSAC inliers, keeps every
/// tentative match that agrees within LOCAL_THRESHOLD with the locally weighted affine fit of the
/// current inliers, evaluated at the nearest node of a grid (spacing radius / 2). Two sweeps.
pub(super) fn local_consistency(
    pairs: &[([f64; 2], [f64; 2])],
    global: &Affine2,
    threads: usize,
) -> Vec<([f64; 2], [f64; 2])> {
    let mut inl: Vec<([f64; 2], [f64; 2])> = pairs
        .iter()
        .filter(|p| residual(global, p) < RANSAC_THRESHOLD)
        .copied()
        .collect();
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for (r, _) in pairs {
        for k in 0..2 {
            lo[k] = lo[k].min(r[k]);
            hi[k] = hi[k].max(r[k]);
        }
    }
    for _ in 0..2 {
        if inl.len() < MIN_INLIERS {
            break;
        }
        let radius = density_radius(&inl);
        let step = 0.5 * radius;
        let nx = (((hi[0] - lo[0]) / step).ceil() as usize + 1).min(64);
        let ny = (((hi[1] - lo[1]) / step).ceil() as usize + 1).min(64);
        let sx = (hi[0] - lo[0]) / (nx.max(2) - 1) as f64;
        let sy = (hi[1] - lo[1]) / (ny.max(2) - 1) as f64;
        let node = |i: usize| [lo[0] + sx * (i % nx) as f64, lo[1] + sy * (i / nx) as f64];
        let fits: Vec<Affine2> = par_map(nx * ny, threads, |a, b| {
            (a..b)
                .map(|i| weighted_affine(&inl, node(i), radius, None).unwrap_or(*global))
                .collect::<Vec<_>>()
        })
        .into_iter()
        .flatten()
        .collect();
        let nearest = |r: [f64; 2]| {
            let ix = if sx > 0.0 {
                ((r[0] - lo[0]) / sx).round() as usize
            } else {
                0
            };
            let iy = if sy > 0.0 {
                ((r[1] - lo[1]) / sy).round() as usize
            } else {
                0
            };
            iy.min(ny - 1) * nx + ix.min(nx - 1)
        };
        inl = pairs
            .iter()
            .filter(|p| residual(&fits[nearest(p.0)], p) < LOCAL_THRESHOLD)
            .copied()
            .collect();
    }
    inl
}
