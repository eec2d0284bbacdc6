//! Test-only speckle images with exact ground truth: a sum of Gaussian spots evaluated
//! analytically at the inverse-mapped coordinates of each pixel (affine maps).
//! TODO: replace with the producer crate's renderer once it lands ("one place per concept").
#![allow(dead_code)]

pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// Reference-configuration speckle: spots (X, Y, sigma, amplitude).
pub struct Speckle {
    spots: Vec<[f64; 4]>,
}

/// Affine map of the motion: x = centre + M (X - centre) + t.
#[derive(Clone, Copy)]
pub struct Affine {
    pub m: [[f64; 2]; 2],
    pub t: [f64; 2],
    pub centre: [f64; 2],
}

impl Affine {
    pub fn translation(u: f64, v: f64) -> Self {
        Affine {
            m: [[1.0, 0.0], [0.0, 1.0]],
            t: [u, v],
            centre: [0.0, 0.0],
        }
    }
    pub fn rotation_deg(deg: f64, centre: [f64; 2]) -> Self {
        let (s, c) = deg.to_radians().sin_cos();
        Affine {
            m: [[c, -s], [s, c]],
            t: [0.0, 0.0],
            centre,
        }
    }
    pub fn stretch(ex: f64, ey: f64, centre: [f64; 2]) -> Self {
        Affine {
            m: [[1.0 + ex, 0.0], [0.0, 1.0 + ey]],
            t: [0.0, 0.0],
            centre,
        }
    }
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let d = [p[0] - self.centre[0], p[1] - self.centre[1]];
        [
            self.centre[0] + self.m[0][0] * d[0] + self.m[0][1] * d[1] + self.t[0],
            self.centre[1] + self.m[1][0] * d[0] + self.m[1][1] * d[1] + self.t[1],
        ]
    }
    /// Displacement of reference point p.
    pub fn displacement(&self, p: [f64; 2]) -> [f64; 2] {
        let q = self.apply(p);
        [q[0] - p[0], q[1] - p[1]]
    }
    fn inverse_matrix(&self) -> [[f64; 2]; 2] {
        let [[a, b], [c, d]] = self.m;
        let det = a * d - b * c;
        [[d / det, -b / det], [-c / det, a / det]]
    }
}

impl Speckle {
    /// Spots covering [-margin, w + margin] x [-margin, h + margin].
    pub fn new(width: usize, height: usize, margin: f64, seed: u64) -> Self {
        let mut rng = Rng::new(seed);
        let area = (width as f64 + 2.0 * margin) * (height as f64 + 2.0 * margin);
        let count = (area * 0.06) as usize;
        let spots = (0..count)
            .map(|_| {
                [
                    -margin + rng.uniform() * (width as f64 + 2.0 * margin),
                    -margin + rng.uniform() * (height as f64 + 2.0 * margin),
                    1.2 + rng.uniform() * 1.0,
                    0.5 + 0.5 * rng.uniform(),
                ]
            })
            .collect();
        Speckle { spots }
    }

    /// Renders the speckle moved by `motion`, with Gaussian noise of std `noise` (fraction of the
    /// 20000-count nominal range).
    pub fn render(
        &self,
        width: usize,
        height: usize,
        motion: Affine,
        noise: f64,
        seed: u64,
    ) -> Vec<u16> {
        let mut acc = vec![0.0f64; width * height];
        let inv = motion.inverse_matrix();
        let norm_inv = (inv[0][0].abs() + inv[0][1].abs()).max(inv[1][0].abs() + inv[1][1].abs());
        let norm_m = (motion.m[0][0].abs() + motion.m[0][1].abs())
            .max(motion.m[1][0].abs() + motion.m[1][1].abs());
        let _ = norm_inv;
        for &[sx, sy, sigma, amp] in &self.spots {
            let [cx, cy] = motion.apply([sx, sy]);
            let radius = 4.0 * sigma * norm_m;
            let x0 = (cx - radius).floor().max(0.0) as i64;
            let x1 = (cx + radius).ceil().min(width as f64 - 1.0) as i64;
            let y0 = (cy - radius).floor().max(0.0) as i64;
            let y1 = (cy + radius).ceil().min(height as f64 - 1.0) as i64;
            let k = 1.0 / (2.0 * sigma * sigma);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    // Reference coordinates of this pixel minus the spot centre.
                    let dx = x as f64 - cx;
                    let dy = y as f64 - cy;
                    let rx = inv[0][0] * dx + inv[0][1] * dy;
                    let ry = inv[1][0] * dx + inv[1][1] * dy;
                    acc[y as usize * width + x as usize] += amp * (-(rx * rx + ry * ry) * k).exp();
                }
            }
        }
        let mut rng = Rng::new(seed);
        acc.iter()
            .map(|&a| {
                let value = 6000.0 + 12000.0 * a + noise * 20000.0 * rng.normal();
                value.round().clamp(0.0, 65535.0) as u16
            })
            .collect()
    }
}

/// Folder of the shared data, or None (with a visible message) when absent.
pub fn shared_data() -> Option<std::path::PathBuf> {
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data"));
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("SKIPPED: shared data folder {} is absent", dir.display());
        None
    }
}

pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}
