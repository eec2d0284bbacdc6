//! The membrane's constitutive update at a Gauss point (plane stress, incompressible).
//!
//! In-plane right Cauchy-Green C (2×2, Voigt c = [C11, C22, C12]); plane stress and
//! incompressibility give C33 = λ3² = 1 / det C, so with t = tr C and J = det C:
//! I1 = t + 1/J, I2 = t/J + J. The reduced energy w(c) = W(I1(c), I2(c)) per unit reference
//! volume gives the second Piola-Kirchhoff stress and the material tangent in Voigt form on the
//! Green-Lagrange strain e = [E11, E22, 2 E12]: S_i = ∂w/∂e_i, D_ij = ∂²w/∂e_i∂e_j, with
//! ∂c/∂e = diag(2, 2, 1). No pressure field: σ33 = 0 is built into w. Everything is analytic
//! from W1, W2 and W11, W12, W22 (the chain rule below), checked against finite differences in
//! the tests.

use crate::law::{MembraneLaw, SheetLaw};
use crate::wrinkling;

/// A symmetric 2×2 tensor in Voigt order [11, 22, 12].
pub type Voigt = [f64; 3];
/// A 3×3 matrix on Voigt components.
pub type Matrix3 = [[f64; 3]; 3];

/// ∂c/∂e: c = [C11, C22, C12] from e = [E11, E22, 2 E12].
const VOIGT_SCALE: Voigt = [2.0, 2.0, 1.0];

/// Which branch of the tension-field law the point is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MembraneState {
    /// Both principal stresses non-negative: the full law.
    Taut,
    /// One principal stress would be compressive: uniaxial tension along the major stretch.
    Wrinkled,
    /// No stretch above 1: no stress.
    Slack,
}

impl MembraneState {
    /// The state's name in files (`taut`, `wrinkled`, `slack`).
    pub fn name(self) -> &'static str {
        match self {
            MembraneState::Taut => "taut",
            MembraneState::Wrinkled => "wrinkled",
            MembraneState::Slack => "slack",
        }
    }
}

/// Count of Gauss points per state, to report how much of the sheet wrinkled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StateCount {
    pub taut: usize,
    pub wrinkled: usize,
    pub slack: usize,
}

impl StateCount {
    pub fn add(&mut self, state: MembraneState) {
        match state {
            MembraneState::Taut => self.taut += 1,
            MembraneState::Wrinkled => self.wrinkled += 1,
            MembraneState::Slack => self.slack += 1,
        }
    }
}

/// Stress and tangent at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointResponse {
    /// Second Piola-Kirchhoff stress, MPa, Voigt [S11, S22, S12].
    pub stress_pk2_mpa: Voigt,
    /// ∂S/∂e, MPa.
    pub tangent_mpa: Matrix3,
    pub state: MembraneState,
    /// (I1, I2) of the actual (unrelaxed) state.
    pub invariants: (f64, f64),
}

/// Why a point has no response.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointFailure {
    /// det C ≤ 0 (or not finite): the element is inverted.
    Inverted { det_c: f64 },
    /// The law has no value at these invariants.
    OutsideDomain { i1: f64, i2: f64 },
}

/// Scalar function of c with its gradient and Hessian.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Jet {
    pub value: f64,
    pub gradient: Voigt,
    pub hessian: Matrix3,
}

pub(crate) fn outer(a: &Voigt, b: &Voigt) -> Matrix3 {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = a[i] * b[j];
        }
    }
    m
}

/// Σ w_k m_k.
pub(crate) fn combine(terms: &[(f64, Matrix3)]) -> Matrix3 {
    let mut m = [[0.0; 3]; 3];
    for (w, t) in terms {
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += w * t[i][j];
            }
        }
    }
    m
}

/// (I1, I2) of the plane-stress incompressible state as jets in c; `None` if det C ≤ 0.
pub(crate) fn invariant_jets(c: &Voigt) -> Option<(Jet, Jet)> {
    let [c1, c2, c3] = *c;
    let t = c1 + c2;
    let j = c1 * c2 - c3 * c3;
    if !(j > 0.0 && j.is_finite() && t.is_finite()) {
        return None;
    }
    let gt = [1.0, 1.0, 0.0];
    let gj = [c2, c1, -2.0 * c3];
    let hj = [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -2.0]];
    let (j2, j3) = (j * j, j * j * j);
    let i1 = Jet {
        value: t + 1.0 / j,
        gradient: std::array::from_fn(|k| gt[k] - gj[k] / j2),
        hessian: combine(&[(2.0 / j3, outer(&gj, &gj)), (-1.0 / j2, hj)]),
    };
    let i2 = Jet {
        value: t / j + j,
        gradient: std::array::from_fn(|k| gt[k] / j - t / j2 * gj[k] + gj[k]),
        hessian: combine(&[
            (-1.0 / j2, outer(&gt, &gj)),
            (-1.0 / j2, outer(&gj, &gt)),
            (2.0 * t / j3, outer(&gj, &gj)),
            (1.0 - t / j2, hj),
        ]),
    };
    Some((i1, i2))
}

/// w(c) = W(I1, I2) of an invariant law to second order: gradient and Hessian in c.
pub(crate) fn invariant_energy_jet<L: MembraneLaw + ?Sized>(
    law: &L,
    c: &Voigt,
) -> Result<Jet, PointFailure> {
    let (i1, i2) = invariant_jets(c).ok_or(PointFailure::Inverted {
        det_c: c[0] * c[1] - c[2] * c[2],
    })?;
    let outside = PointFailure::OutsideDomain {
        i1: i1.value,
        i2: i2.value,
    };
    let (w1, w2) = law
        .first_derivatives_mpa(i1.value, i2.value)
        .ok_or(outside)?;
    let [w11, w12, w22] = law
        .second_derivatives_mpa(i1.value, i2.value)
        .ok_or(outside)?;
    let (g1, g2) = (i1.gradient, i2.gradient);
    Ok(Jet {
        value: f64::NAN, // W itself is not needed (only its derivatives are known).
        gradient: std::array::from_fn(|k| w1 * g1[k] + w2 * g2[k]),
        hessian: combine(&[
            (w11, outer(&g1, &g1)),
            (w12, outer(&g1, &g2)),
            (w12, outer(&g2, &g1)),
            (w22, outer(&g2, &g2)),
            (w1, i1.hessian),
            (w2, i2.hessian),
        ]),
    })
}

/// S and D in Voigt form on e from a jet of w in c.
fn stress_and_tangent(jet: &Jet) -> (Voigt, Matrix3) {
    let s = VOIGT_SCALE;
    let stress = std::array::from_fn(|i| s[i] * jet.gradient[i]);
    let tangent = std::array::from_fn(|i| std::array::from_fn(|j| s[i] * s[j] * jet.hessian[i][j]));
    (stress, tangent)
}

/// The full (taut) law at c, without tension-field relaxation.
pub fn taut_response<L: SheetLaw + ?Sized>(
    law: &L,
    c: &Voigt,
) -> Result<PointResponse, PointFailure> {
    let (gradient, hessian) = law.energy_derivatives(c)?;
    let jet = Jet {
        value: f64::NAN,
        gradient,
        hessian,
    };
    let (stress_pk2_mpa, tangent_mpa) = stress_and_tangent(&jet);
    let (i1, i2) = invariant_jets(c)
        .map(|(a, b)| (a.value, b.value))
        .unwrap_or_default();
    Ok(PointResponse {
        stress_pk2_mpa,
        tangent_mpa,
        state: MembraneState::Taut,
        invariants: (i1, i2),
    })
}

/// Tension-field options of the point law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wrinkling {
    /// Relax the energy where a principal stress would be compressive.
    pub enabled: bool,
    /// Fraction ε of the full law blended into wrinkled and slack points, so that a wrinkled
    /// region is not a mechanism: (1 − ε) relaxed + ε full (equal to the full law on the taut
    /// boundary, so the stress stays continuous). 1e-3 by default: a wrinkled point carries
    /// 1e-3 of the full law's compression; 1e-4 and below leave the soft modes so ill-conditioned
    /// that Newton crawls on a sheet wrinkled all over (a sheared sheet: 60 iterations at 1e-4,
    /// 10 at 1e-3, quadratic at the end).
    pub residual_stiffness: f64,
    /// A minor principal stress down to −tolerance × the major one still counts as taut (the
    /// uniaxial state sits on the boundary: keeping it taut keeps the full tangent there).
    pub taut_tolerance: f64,
}

impl Default for Wrinkling {
    fn default() -> Self {
        Wrinkling {
            enabled: true,
            residual_stiffness: 1e-3,
            taut_tolerance: 1e-6,
        }
    }
}

impl Wrinkling {
    /// The full law everywhere (a sheet that could carry compression).
    pub fn off() -> Self {
        Wrinkling {
            enabled: false,
            ..Wrinkling::default()
        }
    }
}

/// Principal values (major, minor) of a symmetric 2×2 tensor in Voigt order.
pub fn principal_values(t: &Voigt) -> (f64, f64) {
    let mean = 0.5 * (t[0] + t[1]);
    let radius = (0.25 * (t[0] - t[1]).powi(2) + t[2] * t[2]).sqrt();
    (mean + radius, mean - radius)
}

/// The membrane law at c with tension-field relaxation: taut, wrinkled or slack.
pub fn response<L: SheetLaw + ?Sized>(
    law: &L,
    c: &Voigt,
    wrinkling: &Wrinkling,
) -> Result<PointResponse, PointFailure> {
    let taut = taut_response(law, c)?;
    if !wrinkling.enabled {
        return Ok(taut);
    }
    let (s_major, s_minor) = principal_values(&taut.stress_pk2_mpa);
    if s_minor >= -wrinkling.taut_tolerance * s_major.abs() {
        return Ok(taut);
    }
    let (c_major, _) = principal_values(c);
    let (relaxed, state) = if c_major <= 1.0 {
        (None, MembraneState::Slack)
    } else {
        let jet = wrinkling::relaxed_energy_jet(law, c).ok_or(PointFailure::OutsideDomain {
            i1: taut.invariants.0,
            i2: taut.invariants.1,
        })?;
        (Some(stress_and_tangent(&jet)), MembraneState::Wrinkled)
    };
    let eps = wrinkling.residual_stiffness;
    let (rs, rd) = relaxed.unwrap_or(([0.0; 3], [[0.0; 3]; 3]));
    Ok(PointResponse {
        stress_pk2_mpa: std::array::from_fn(|i| (1.0 - eps) * rs[i] + eps * taut.stress_pk2_mpa[i]),
        tangent_mpa: combine(&[(1.0 - eps, rd), (eps, taut.tangent_mpa)]),
        state,
        invariants: taut.invariants,
    })
}
