//! Displacement maps x = φ(X) from reference (Lagrangian) to current coordinates, in px, with
//! their exact gradient and inverse. x = pixel column, y = pixel row, origin at the centre of
//! the top-left pixel.

/// A 2-vector, px.
pub type Vec2 = [f64; 2];
/// A 2x2 matrix, row-major `[[a11, a12], [a21, a22]]`.
pub type Mat2 = [[f64; 2]; 2];

/// The identity matrix.
pub const IDENTITY: Mat2 = [[1.0, 0.0], [0.0, 1.0]];

/// Iteration cap of every Newton inverse; reached only for non-invertible maps.
pub const NEWTON_MAX_ITERATIONS: u32 = 50;
/// Convergence tolerance of the Newton inverses, px.
pub const NEWTON_TOLERANCE_PX: f64 = 1e-12;

/// x = c + F (X - c) + t: translation, rotation, stretches, any homogeneous gradient.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Deformation gradient F, det F > 0.
    pub f: Mat2,
    /// Translation t, px.
    pub translation_px: Vec2,
    /// Centre c, px (reference coordinates); a fixed point when t = 0.
    pub centre_px: Vec2,
}

/// Chirp along x (like DIC Challenge sample 14): v = 0 and
/// u(X) = A sin θ(X), θ(X) = 2π n ((X - x0) / L)² for X ≥ x0, u = 0 before x0.
/// The local frequency, θ'(X) / 2π = 2 n (X - x0) / L², rises linearly from 0 at x0, so that
/// there are n periods over [x0, x0 + L]. u is C¹ at x0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chirp {
    /// Amplitude A, px.
    pub amplitude_px: f64,
    /// Start x0 of the chirp, px.
    pub start_px: f64,
    /// Length L over which `periods` periods fit, px.
    pub length_px: f64,
    /// Number n of periods over L.
    pub periods: f64,
}

/// Smooth non-homogeneous radial stretch (a bulge) about c:
/// x - c = (X - c) (1 + e g(r)), g(r) = exp(-r² / (2 w²)), r = |X - c|.
/// The strain is e at the centre (isotropic) and fades over the width w; invertible for e < e₀ = 2.718...
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bulge {
    /// Strain e at the centre.
    pub strain: f64,
    /// Width w, px.
    pub width_px: f64,
    /// Centre c, px.
    pub centre_px: Vec2,
}

/// A displacement map with exact truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// Homogeneous.
    Affine(Affine),
    /// Chirp sine along x, heterogeneous.
    Chirp(Chirp),
    /// Radial bulge, heterogeneous.
    Bulge(Bulge),
}

/// det of a 2x2 matrix.
pub fn det(m: &Mat2) -> f64 {
    m[0][0] * m[1][1] - m[0][1] * m[1][0]
}

/// Inverse of a 2x2 matrix; panics on a singular one (an invariant of every motion here).
pub fn inverse(m: &Mat2) -> Mat2 {
    let d = det(m);
    assert!(d.abs() > 1e-300, "singular matrix {m:?}");
    [[m[1][1] / d, -m[0][1] / d], [-m[1][0] / d, m[0][0] / d]]
}

/// m v.
pub fn mul_vec(m: &Mat2, v: Vec2) -> Vec2 {
    [
        m[0][0] * v[0] + m[0][1] * v[1],
        m[1][0] * v[0] + m[1][1] * v[1],
    ]
}

/// a b.
pub fn mul_mat(a: &Mat2, b: &Mat2) -> Mat2 {
    [
        [
            a[0][0] * b[0][0] + a[0][1] * b[1][0],
            a[0][0] * b[0][1] + a[0][1] * b[1][1],
        ],
        [
            a[1][0] * b[0][0] + a[1][1] * b[1][0],
            a[1][0] * b[0][1] + a[1][1] * b[1][1],
        ],
    ]
}

/// Rotation by `angle_rad` (counter-clockwise in x-right, y-up; clockwise on screen where y is
/// the row going down).
pub fn rotation(angle_rad: f64) -> Mat2 {
    let (s, c) = angle_rad.sin_cos();
    [[c, -s], [s, c]]
}

impl Affine {
    /// The identity map.
    pub const IDENTITY: Affine = Affine {
        f: IDENTITY,
        translation_px: [0.0, 0.0],
        centre_px: [0.0, 0.0],
    };
}

impl Chirp {
    fn phase_rad(&self, x: f64) -> (f64, f64) {
        let s = (x - self.start_px).max(0.0) / self.length_px;
        let k = 2.0 * std::f64::consts::PI * self.periods;
        (k * s * s, 2.0 * k * s / self.length_px)
    }

    /// u(X) and du/dX.
    fn u_and_slope(&self, x: f64) -> (f64, f64) {
        let (theta, dtheta) = self.phase_rad(x);
        let (s, c) = theta.sin_cos();
        (self.amplitude_px * s, self.amplitude_px * c * dtheta)
    }
}

impl Bulge {
    fn factor(&self, r2: f64) -> (f64, f64) {
        // Returns (1 + e g, d(1 + e g)/d(r²)).
        let g = (-r2 / (2.0 * self.width_px * self.width_px)).exp();
        (
            1.0 + self.strain * g,
            -self.strain * g / (2.0 * self.width_px * self.width_px),
        )
    }
}

impl Motion {
    /// The identity map.
    pub const IDENTITY: Motion = Motion::Affine(Affine::IDENTITY);

    /// x = φ(X), px.
    pub fn forward(&self, p: Vec2) -> Vec2 {
        match self {
            Motion::Affine(a) => {
                let d = mul_vec(&a.f, [p[0] - a.centre_px[0], p[1] - a.centre_px[1]]);
                [
                    a.centre_px[0] + d[0] + a.translation_px[0],
                    a.centre_px[1] + d[1] + a.translation_px[1],
                ]
            }
            Motion::Chirp(c) => [p[0] + c.u_and_slope(p[0]).0, p[1]],
            Motion::Bulge(b) => {
                let d = [p[0] - b.centre_px[0], p[1] - b.centre_px[1]];
                let (k, _) = b.factor(d[0] * d[0] + d[1] * d[1]);
                [b.centre_px[0] + k * d[0], b.centre_px[1] + k * d[1]]
            }
        }
    }

    /// Displacement u(X) = φ(X) - X, px.
    pub fn displacement(&self, p: Vec2) -> Vec2 {
        let x = self.forward(p);
        [x[0] - p[0], x[1] - p[1]]
    }

    /// F(X) = ∂φ/∂X, exact.
    pub fn gradient(&self, p: Vec2) -> Mat2 {
        match self {
            Motion::Affine(a) => a.f,
            Motion::Chirp(c) => [[1.0 + c.u_and_slope(p[0]).1, 0.0], [0.0, 1.0]],
            Motion::Bulge(b) => {
                let d = [p[0] - b.centre_px[0], p[1] - b.centre_px[1]];
                let (k, dk) = b.factor(d[0] * d[0] + d[1] * d[1]);
                // x_i = c_i + k(r²) d_i → ∂x_i/∂X_j = k δ_ij + 2 k'(r²) d_i d_j.
                [
                    [k + 2.0 * dk * d[0] * d[0], 2.0 * dk * d[0] * d[1]],
                    [2.0 * dk * d[1] * d[0], k + 2.0 * dk * d[1] * d[1]],
                ]
            }
        }
    }

    /// X = φ⁻¹(x): closed form for affine maps, bounded Newton iteration otherwise.
    pub fn inverse(&self, x: Vec2) -> Vec2 {
        match self {
            Motion::Affine(a) => {
                let inv = inverse(&a.f);
                let d = mul_vec(
                    &inv,
                    [
                        x[0] - a.centre_px[0] - a.translation_px[0],
                        x[1] - a.centre_px[1] - a.translation_px[1],
                    ],
                );
                [a.centre_px[0] + d[0], a.centre_px[1] + d[1]]
            }
            Motion::Chirp(c) => {
                // Solve X + u(X) = x; 1 + u' > 0 is checked when the chirp is built.
                let mut p = x[0] - c.u_and_slope(x[0]).0;
                for _ in 0..NEWTON_MAX_ITERATIONS {
                    let (u, du) = c.u_and_slope(p);
                    let step = (p + u - x[0]) / (1.0 + du);
                    p -= step;
                    if step.abs() < NEWTON_TOLERANCE_PX {
                        break;
                    }
                }
                [p, x[1]]
            }
            Motion::Bulge(b) => {
                // Radial: solve r (1 + e g(r)) = ρ for r, along the same direction.
                let d = [x[0] - b.centre_px[0], x[1] - b.centre_px[1]];
                let rho = (d[0] * d[0] + d[1] * d[1]).sqrt();
                if rho == 0.0 {
                    return b.centre_px;
                }
                let mut r = rho / b.factor(rho * rho).0;
                for _ in 0..NEWTON_MAX_ITERATIONS {
                    let (k, dk) = b.factor(r * r);
                    let step = (r * k - rho) / (k + 2.0 * r * r * dk);
                    r -= step;
                    if step.abs() < NEWTON_TOLERANCE_PX {
                        break;
                    }
                }
                let s = r / rho;
                [b.centre_px[0] + s * d[0], b.centre_px[1] + s * d[1]]
            }
        }
    }

    /// Whether the map is homogeneous (affine).
    pub fn is_homogeneous(&self) -> bool {
        matches!(self, Motion::Affine(_))
    }
}
