//! Tests of the keypoint guess on speckle rendered here (Gaussian spots, exact pre-images).

use super::*;

/// Test speckle renderer: Gaussian spots (random amplitude) on a bright background,
/// evaluated analytically at the pre-image of each of 3x3 sub-samples per pixel.
pub(super) struct Speckle {
    spots: Vec<[f64; 3]>,
    cells: Vec<Vec<u32>>,
    cell: f64,
    lo: [f64; 2],
    nx: usize,
    ny: usize,
    sigma: f64,
    contrast: f64,
    /// Flat background (value 0.15) where X < flat_left_of.
    flat_left_of: f64,
}

impl Speckle {
    /// Spots of `fwhm` px covering ~35 % of the box [lo, hi].
    pub(super) fn new(seed: u64, fwhm: f64, contrast: f64, lo: [f64; 2], hi: [f64; 2]) -> Self {
        let sigma = fwhm / 2.3548;
        let density = -(0.65f64).ln() / (std::f64::consts::PI * (fwhm / 2.0).powi(2));
        let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        let count = (density * area) as usize;
        let mut rng = XorShift(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        let cell = 4.0 * sigma;
        let nx = ((hi[0] - lo[0]) / cell).ceil() as usize + 1;
        let ny = ((hi[1] - lo[1]) / cell).ceil() as usize + 1;
        let mut cells = vec![Vec::new(); nx * ny];
        let mut spots = Vec::with_capacity(count);
        for k in 0..count {
            let x = lo[0] + rng.uniform() * (hi[0] - lo[0]);
            let y = lo[1] + rng.uniform() * (hi[1] - lo[1]);
            let a = 0.7 + 0.6 * rng.uniform();
            spots.push([x, y, a]);
            let cx = ((x - lo[0]) / cell) as usize;
            let cy = ((y - lo[1]) / cell) as usize;
            cells[cy * nx + cx].push(k as u32);
        }
        Speckle {
            spots,
            cells,
            cell,
            lo,
            nx,
            ny,
            sigma,
            contrast,
            flat_left_of: f64::NEG_INFINITY,
        }
    }

    /// Intensity in [0, 1] at reference point X.
    pub(super) fn value(&self, p: [f64; 2]) -> f64 {
        if p[0] < self.flat_left_of {
            return 0.15;
        }
        let cx = ((p[0] - self.lo[0]) / self.cell).floor() as isize;
        let cy = ((p[1] - self.lo[1]) / self.cell).floor() as isize;
        let inv = 1.0 / (2.0 * self.sigma * self.sigma);
        let mut v = 0.0;
        for yy in cy - 1..=cy + 1 {
            for xx in cx - 1..=cx + 1 {
                if xx < 0 || yy < 0 || xx as usize >= self.nx || yy as usize >= self.ny {
                    continue;
                }
                for &k in &self.cells[yy as usize * self.nx + xx as usize] {
                    let s = self.spots[k as usize];
                    let d2 = (p[0] - s[0]).powi(2) + (p[1] - s[1]).powi(2);
                    if d2 < 16.0 * self.sigma * self.sigma {
                        v += s[2] * (-d2 * inv).exp();
                    }
                }
            }
        }
        0.5 + 0.5 * self.contrast * (2.0 * (-2.5 * v).exp() - 1.0)
    }

    /// Renders a w x h image whose pixel x shows the pattern at `pre(x)`, with 3x3
    /// sub-samples, Gaussian noise (`noise` of full scale) and `bits` depth.
    pub(super) fn render(
        &self,
        w: usize,
        h: usize,
        pre: &dyn Fn([f64; 2]) -> [f64; 2],
        noise: f64,
        bits: u32,
        seed: u64,
    ) -> Vec<u16> {
        let full = ((1u32 << bits) - 1) as f64;
        let mut rng = XorShift(seed.wrapping_mul(0xD134_2543_DE82_EF95) | 1);
        let mut out = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for sy in [-1.0, 0.0, 1.0] {
                    for sx in [-1.0, 0.0, 1.0] {
                        let q = pre([x as f64 + sx / 3.0, y as f64 + sy / 3.0]);
                        s += self.value(q);
                    }
                }
                let v = s / 9.0 + noise * rng.gauss_pair().0;
                out.push((v * full).round().clamp(0.0, full) as u16);
            }
        }
        out
    }
}

const N: usize = 512;

/// A deformation phi(X) = c + F (X - c) + t (+ optional radial bulge), with its inverse.
#[derive(Clone, Copy)]
struct Warp {
    f: [[f64; 2]; 2],
    t: [f64; 2],
    bulge: f64,
}

impl Warp {
    fn c() -> [f64; 2] {
        [(N as f64 - 1.0) * 0.5; 2]
    }
    fn phi(&self, x: [f64; 2]) -> [f64; 2] {
        let c = Self::c();
        let d = [x[0] - c[0], x[1] - c[1]];
        let g = self.bulge * (-(d[0] * d[0] + d[1] * d[1]) / (2.0 * 100.0f64.powi(2))).exp();
        let e = [d[0] * (1.0 + g), d[1] * (1.0 + g)];
        [
            c[0] + self.f[0][0] * e[0] + self.f[0][1] * e[1] + self.t[0],
            c[1] + self.f[1][0] * e[0] + self.f[1][1] * e[1] + self.t[1],
        ]
    }
    fn inverse(&self, x: [f64; 2]) -> [f64; 2] {
        let c = Self::c();
        let det = self.f[0][0] * self.f[1][1] - self.f[0][1] * self.f[1][0];
        let y = [x[0] - c[0] - self.t[0], x[1] - c[1] - self.t[1]];
        let e = [
            (self.f[1][1] * y[0] - self.f[0][1] * y[1]) / det,
            (-self.f[1][0] * y[0] + self.f[0][0] * y[1]) / det,
        ];
        // d (1 + g(|d|)) = e, by fixed point (none without a bulge: g = 0, d = e; the
        // renderer calls this 9 times per pixel, and 50 idle iterations were 95 % of a test).
        let mut d = e;
        if self.bulge != 0.0 {
            for _ in 0..50 {
                let g =
                    self.bulge * (-(d[0] * d[0] + d[1] * d[1]) / (2.0 * 100.0f64.powi(2))).exp();
                let next = [e[0] / (1.0 + g), e[1] / (1.0 + g)];
                let converged = next == d;
                d = next;
                if converged {
                    break;
                }
            }
        }
        [c[0] + d[0], c[1] + d[1]]
    }
}

fn rot(deg: f64, s: f64) -> [[f64; 2]; 2] {
    let (sn, cs) = deg.to_radians().sin_cos();
    [[s * cs, -s * sn], [s * sn, s * cs]]
}

struct Opts {
    fwhm: f64,
    contrast: f64,
    bits: u32,
    seed_def: u64,
    /// Specimen edge: flat background left of this reference abscissa.
    edge: f64,
    /// Lighting change of the deformed image: v -> 0.1 full scale + gain v.
    gain: f64,
}

const STD: Opts = Opts {
    fwhm: 4.0,
    contrast: 0.9,
    bits: 16,
    seed_def: 1,
    edge: f64::NEG_INFINITY,
    gain: 1.0,
};

fn images(warp: &Warp, o: &Opts) -> (Vec<u16>, Vec<u16>) {
    // Pattern box: the reference image and the pre-image of the deformed one, + margin.
    let (mut lo, mut hi) = ([-10.0f64, -10.0], [N as f64 + 10.0; 2]);
    for y in (0..=N).step_by(16) {
        for x in (0..=N).step_by(16) {
            let q = warp.inverse([x as f64, y as f64]);
            for k in 0..2 {
                lo[k] = lo[k].min(q[k] - 10.0);
                hi[k] = hi[k].max(q[k] + 10.0);
            }
        }
    }
    let mut sp = Speckle::new(7, o.fwhm, o.contrast, lo, hi);
    sp.flat_left_of = o.edge;
    let r = sp.render(N, N, &|x| x, 0.01, o.bits, 11);
    let sp_def = if o.seed_def == 1 {
        sp
    } else {
        Speckle::new(o.seed_def, o.fwhm, o.contrast, lo, hi)
    };
    let d = sp_def.render(N, N, &|x| warp.inverse(x), 0.01, o.bits, 13);
    let full = ((1u32 << o.bits) - 1) as f64;
    let d = if o.gain == 1.0 {
        d
    } else {
        d.iter()
            .map(|&v| (0.1 * full + o.gain * v as f64).round().min(full) as u16)
            .collect()
    };
    (r, d)
}

/// Returns the maximal guess error over a grid of the central area, or None.
fn run(warp: Warp, o: &Opts) -> Option<f64> {
    let (r, d) = images(&warp, o);
    let mut m = KeypointMatcher::new(N, N, 2);
    fn img(p: &[u16]) -> Image<'_> {
        Image {
            pixels: p,
            width_px: N,
            height_px: N,
        }
    }
    let t0 = std::time::Instant::now();
    let ks_r = m.detect(img(&r), (0, 0, N, N));
    let ks_d = m.detect(img(&d), (0, 0, N, N));
    let guess = m.estimate(&ks_r, &ks_d);
    let el = t0.elapsed();
    let Some(g) = guess else {
        eprintln!("kp {} / {}: no guess ({el:?})", ks_r.len(), ks_d.len());
        return None;
    };
    let mut worst = 0.0f64;
    let mut worst_grad = 0.0f64;
    let mut worst_global = 0.0f64;
    for gy in 0..5 {
        for gx in 0..5 {
            let p = [176.0 + 40.0 * gx as f64, 176.0 + 40.0 * gy as f64];
            // Only points whose image lies inside the deformed image.
            let truth = warp.phi(p);
            if truth[0] < 24.0
                || truth[1] < 24.0
                || truth[0] > N as f64 - 24.0
                || truth[1] > N as f64 - 24.0
            {
                continue;
            }
            if warp.bulge == 0.0 {
                let q = g.global.apply(p);
                let e = ((q[0] - truth[0]).powi(2) + (q[1] - truth[1]).powi(2)).sqrt();
                worst_global = worst_global.max(e);
            }
            let la = g.local_affine(p);
            let q = la.apply(p);
            let e = ((q[0] - truth[0]).powi(2) + (q[1] - truth[1]).powi(2)).sqrt();
            worst = worst.max(e);
            // Gradient: central differences of phi.
            let h = 0.5;
            for k in 0..2 {
                let mut a = p;
                let mut b = p;
                a[k] -= h;
                b[k] += h;
                let (pa, pb) = (warp.phi(a), warp.phi(b));
                for r in 0..2 {
                    let j = (pb[r] - pa[r]) / (2.0 * h);
                    worst_grad = worst_grad.max((la.a[r][k] - j).abs());
                }
            }
        }
    }
    eprintln!(
        "kp {} / {}, inliers {}, worst error {worst:.3} px, gradient {worst_grad:.4}, global {worst_global:.3} px ({el:?})",
        ks_r.len(),
        ks_d.len(),
        g.inliers.len()
    );
    assert!(worst_grad < 0.03, "gradient error {worst_grad}");
    assert!(worst_global < 1.0, "global map error {worst_global}");
    Some(worst)
}

fn check(name: &str, f: [[f64; 2]; 2], t: [f64; 2], o: &Opts) {
    eprint!("{name}: ");
    let e = run(Warp { f, t, bulge: 0.0 }, o);
    assert!(matches!(e, Some(e) if e < 1.0), "{name}: {e:?}");
}

#[test]
fn rotation_5() {
    check("rot 5", rot(5.0, 1.0), [12.0, -7.0], &STD);
}
#[test]
fn rotation_30() {
    check("rot 30", rot(30.0, 1.0), [-20.0, 15.0], &STD);
}
#[test]
fn rotation_90() {
    check("rot 90", rot(90.0, 1.0), [25.0, 30.0], &STD);
}
#[test]
fn rotation_170() {
    check("rot 170", rot(170.0, 1.0), [-33.0, 21.0], &STD);
}
#[test]
fn rotation_minus_120() {
    check("rot -120", rot(-120.0, 1.0), [40.0, -18.0], &STD);
}
#[test]
fn scale_0_7() {
    check("scale 0.7", rot(0.0, 0.7), [15.0, 10.0], &STD);
}
#[test]
fn scale_1_5() {
    check("scale 1.5", rot(0.0, 1.5), [-12.0, 20.0], &STD);
}
#[test]
fn scale_1_5_rot_40() {
    check("scale 1.5 rot 40", rot(40.0, 1.5), [10.0, 5.0], &STD);
}
fn poisson(e: f64) -> [[f64; 2]; 2] {
    [[1.0 + e, 0.0], [0.0, 1.0 - 0.3 * e]]
}
fn incompressible(l: f64) -> [[f64; 2]; 2] {
    [[l, 0.0], [0.0, 1.0 / l.sqrt()]]
}
#[test]
fn stretch_10() {
    check("stretch 10%", poisson(0.1), [20.0, -10.0], &STD);
}
#[test]
fn stretch_30() {
    check("stretch 30%", poisson(0.3), [-15.0, 12.0], &STD);
}
#[test]
fn stretch_50() {
    check("stretch 50%", poisson(0.5), [10.0, 30.0], &STD);
}
#[test]
fn incompressible_10() {
    check(
        "incompressible 1.1",
        incompressible(1.1),
        [20.0, -10.0],
        &STD,
    );
}
#[test]
fn incompressible_30() {
    check(
        "incompressible 1.3",
        incompressible(1.3),
        [-15.0, 12.0],
        &STD,
    );
}
#[test]
fn incompressible_50() {
    check(
        "incompressible 1.5",
        incompressible(1.5),
        [10.0, 30.0],
        &STD,
    );
}
#[test]
fn stretch_30_rotated_60() {
    let r = rot(60.0, 1.0);
    let s = poisson(0.3);
    let f = [
        [
            r[0][0] * s[0][0] + r[0][1] * s[1][0],
            r[0][0] * s[0][1] + r[0][1] * s[1][1],
        ],
        [
            r[1][0] * s[0][0] + r[1][1] * s[1][0],
            r[1][0] * s[0][1] + r[1][1] * s[1][1],
        ],
    ];
    check("stretch 30% rot 60", f, [18.0, -25.0], &STD);
}
#[test]
fn eight_bit() {
    let o = Opts { bits: 8, ..STD };
    check("8-bit rot 30", rot(30.0, 1.0), [-20.0, 15.0], &o);
}
#[test]
fn speckle_7px() {
    let o = Opts { fwhm: 7.0, ..STD };
    check("7 px rot 90 scale 1.2", rot(90.0, 1.2), [20.0, 15.0], &o);
}
#[test]
fn speckle_3px_shrunk() {
    let o = Opts { fwhm: 3.0, ..STD };
    check(
        "3 px scale 0.75 rot -30",
        rot(-30.0, 0.75),
        [10.0, -12.0],
        &o,
    );
}
#[test]
fn speckle_8px_enlarged() {
    let o = Opts { fwhm: 8.0, ..STD };
    check("8 px scale 1.5 rot 120", rot(120.0, 1.5), [-14.0, 9.0], &o);
}
#[test]
fn background_left() {
    // A third of the reference is flat background; the specimen is enlarged, so its share
    // differs in the deformed image.
    let o = Opts { edge: 170.0, ..STD };
    check(
        "background scale 1.3 rot 20",
        rot(20.0, 1.3),
        [30.0, 0.0],
        &o,
    );
}
#[test]
fn lighting_change() {
    let o = Opts { gain: 0.55, ..STD };
    check(
        "lighting gain 0.55 rot 45",
        rot(45.0, 1.0),
        [-9.0, 14.0],
        &o,
    );
}
#[test]
fn low_contrast() {
    let o = Opts {
        contrast: 0.3,
        ..STD
    };
    check("contrast 0.3 rot 170", rot(170.0, 1.0), [-33.0, 21.0], &o);
}
#[test]
fn bulge() {
    eprint!("bulge: ");
    let w = Warp {
        f: rot(20.0, 1.0),
        t: [10.0, -5.0],
        bulge: 0.08,
    };
    let e = run(w, &STD);
    assert!(matches!(e, Some(e) if e < 1.0), "bulge: {e:?}");
}
#[test]
fn region_subset() {
    // Keypoints from sub-rectangles, reported in whole-image px.
    let warp = Warp {
        f: rot(-60.0, 1.2),
        t: [8.0, -6.0],
        bulge: 0.0,
    };
    let (r, d) = images(&warp, &STD);
    let mut m = KeypointMatcher::new(N, N, 2);
    let img = |p| Image {
        pixels: p,
        width_px: N,
        height_px: N,
    };
    let ks_r = m.detect(img(&r), (100, 80, 320, 360));
    let ks_d = m.detect(img(&d), (60, 60, 400, 400));
    let g = m.estimate(&ks_r, &ks_d).expect("guess");
    let p = [250.0, 260.0];
    let (q, t) = (g.local_affine(p).apply(p), warp.phi(p));
    let e = ((q[0] - t[0]).powi(2) + (q[1] - t[1]).powi(2)).sqrt();
    eprintln!(
        "region subset: inliers {}, error {e:.3} px",
        g.inliers.len()
    );
    assert!(e < 1.0);
    for (a, _) in &g.inliers {
        assert!(a[0] >= 100.0 && a[0] < 420.0 && a[1] >= 80.0 && a[1] < 440.0);
    }
}

#[test]
fn small_reference_roi() {
    // The correlator's use: reference keypoints from its ROI only, deformed from the whole
    // image (most deformed keypoints then have no partner).
    let warp = Warp {
        f: rot(35.0, 1.1),
        t: [15.0, -10.0],
        bulge: 0.0,
    };
    let (r, d) = images(&warp, &STD);
    let mut m = KeypointMatcher::new(N, N, 2);
    let img = |p| Image {
        pixels: p,
        width_px: N,
        height_px: N,
    };
    let ks_r = m.detect(img(&r), (156, 156, 200, 200));
    let ks_d = m.detect(img(&d), (0, 0, N, N));
    let g = m.estimate(&ks_r, &ks_d).expect("guess");
    let mut worst = 0.0f64;
    for p in [
        [180.0, 180.0],
        [256.0, 256.0],
        [330.0, 200.0],
        [200.0, 330.0],
    ] {
        let (q, t) = (g.local_affine(p).apply(p), warp.phi(p));
        worst = worst.max(((q[0] - t[0]).powi(2) + (q[1] - t[1]).powi(2)).sqrt());
    }
    eprintln!(
        "small reference ROI: kp {} / {}, inliers {}, worst error {worst:.3} px",
        ks_r.len(),
        ks_d.len(),
        g.inliers.len()
    );
    assert!(worst < 1.0);
}

#[test]
fn unrelated_gives_none() {
    for seed in [2, 3, 4] {
        eprint!("unrelated seed {seed}: ");
        let o = Opts {
            seed_def: seed,
            ..STD
        };
        assert!(run(
            Warp {
                f: rot(0.0, 1.0),
                t: [0.0, 0.0],
                bulge: 0.0
            },
            &o
        )
        .is_none());
    }
}
#[test]
fn flat_and_tiny_give_empty() {
    let flat = vec![1000u16; N * N];
    let mut m = KeypointMatcher::new(N, N, 2);
    let img = Image {
        pixels: &flat,
        width_px: N,
        height_px: N,
    };
    let k = m.detect(img, (0, 0, N, N));
    assert!(k.is_empty());
    assert!(m.estimate(&k, &k).is_none());
    let tiny = [5u16; 9];
    let img = Image {
        pixels: &tiny,
        width_px: 3,
        height_px: 3,
    };
    assert!(m.detect(img, (0, 0, 3, 3)).is_empty());
    let img = Image {
        pixels: &tiny,
        width_px: 100,
        height_px: 100,
    };
    assert!(m.detect(img, (0, 0, 100, 100)).is_empty());
    // Pure noise (no pattern) in both images: whatever is detected must not match.
    let mut rng = XorShift(99);
    let mut noise = || -> Vec<u16> {
        (0..N * N)
            .map(|_| (30000.0 + 650.0 * rng.gauss_pair().0) as u16)
            .collect()
    };
    let (n1, n2) = (noise(), noise());
    let im = |p| Image {
        pixels: p,
        width_px: N,
        height_px: N,
    };
    let k1 = m.detect(im(&n1), (0, 0, N, N));
    let k2 = m.detect(im(&n2), (0, 0, N, N));
    eprintln!("noise: {} / {} keypoints", k1.len(), k2.len());
    assert!(m.estimate(&k1, &k2).is_none());
    // Regions outside the image or too small.
    assert!(m.detect(im(&n1), (600, 0, 50, 50)).is_empty());
    assert!(m.detect(im(&n1), (0, 0, 20, 500)).is_empty());
    let zero = Image {
        pixels: &[],
        width_px: 0,
        height_px: 0,
    };
    assert!(m.detect(zero, (0, 0, 10, 10)).is_empty());
}
