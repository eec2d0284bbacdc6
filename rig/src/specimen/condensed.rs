//! The structure between two solves: a first-order prediction from the last converged
//! equilibrium, through the tangent condensed on the grips (`membrane::condense`).
//!
//! With q the grips' axial displacements (mm, outward), q_s, F_s the solved ones and K_c the
//! condensed stiffness (N/mm), F = F_s + K_c (q − q_s). The grips give c = compliance (mm/N)
//! under load, q = x − c F for actuator positions x, so F solves (I + K_c c) F = F_s + K_c
//! (x − q_s) (a 4 × 4 system at most, by Gaussian elimination). The filmed region's mean
//! displacement gradient H and mean displacement follow the same way, from the grips'
//! displacement modes. No allocation: fixed arrays of [`MAX_GRIPS`].

// Small matrices indexed by grip and component read as the formulas do.
#![allow(clippy::needless_range_loop)]

/// The cruciform's four grips at most.
pub const MAX_GRIPS: usize = 4;

/// The first-order model of a converged equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub struct Linearisation {
    pub grips: usize,
    /// Solved grip displacements q_s, mm.
    pub grip_mm: [f64; MAX_GRIPS],
    /// Solved axial grip forces F_s, N.
    pub force_n: [f64; MAX_GRIPS],
    /// K_c[a][b], N/mm.
    pub stiffness_n_per_mm: [[f64; MAX_GRIPS]; MAX_GRIPS],
    /// Mean displacement gradient of the filmed region at the solve, and per mm of each grip.
    pub gradient: [[f64; 2]; 2],
    pub gradient_per_mm: [[[f64; 2]; 2]; MAX_GRIPS],
    /// Mean displacement of the filmed region at the solve (mm), and per mm of each grip.
    pub centre_mm: [f64; 2],
    pub centre_per_mm: [[f64; 2]; MAX_GRIPS],
}

/// What the prediction gives at some actuator positions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Predicted {
    /// Grip displacements after the grips' give, mm.
    pub grip_mm: [f64; MAX_GRIPS],
    pub force_n: [f64; MAX_GRIPS],
    pub gradient: [[f64; 2]; 2],
    pub centre_mm: [f64; 2],
}

impl Linearisation {
    /// Zero everything: a placeholder until the first solve.
    pub fn at_rest(grips: usize) -> Linearisation {
        Linearisation {
            grips,
            grip_mm: [0.0; MAX_GRIPS],
            force_n: [0.0; MAX_GRIPS],
            stiffness_n_per_mm: [[0.0; MAX_GRIPS]; MAX_GRIPS],
            gradient: [[0.0; 2]; 2],
            gradient_per_mm: [[[0.0; 2]; 2]; MAX_GRIPS],
            centre_mm: [0.0; 2],
            centre_per_mm: [[0.0; 2]; MAX_GRIPS],
        }
    }

    /// The prediction at actuator positions `position_mm` (along each grip's axis), grips
    /// giving `compliance_mm_per_n` under load.
    pub fn predict(&self, position_mm: &[f64; MAX_GRIPS], compliance_mm_per_n: f64) -> Predicted {
        let n = self.grips;
        let k = &self.stiffness_n_per_mm;
        // (I + K c) F = F_s + K (x − q_s)
        let mut a = [[0.0; MAX_GRIPS + 1]; MAX_GRIPS];
        for r in 0..n {
            let mut rhs = self.force_n[r];
            for c in 0..n {
                a[r][c] = k[r][c] * compliance_mm_per_n + if r == c { 1.0 } else { 0.0 };
                rhs += k[r][c] * (position_mm[c] - self.grip_mm[c]);
            }
            a[r][MAX_GRIPS] = rhs;
        }
        let force_n = solve_small(a, n);
        let mut grip_mm = [0.0; MAX_GRIPS];
        for g in 0..n {
            grip_mm[g] = position_mm[g] - compliance_mm_per_n * force_n[g];
        }
        let mut gradient = self.gradient;
        let mut centre_mm = self.centre_mm;
        for g in 0..n {
            let dq = grip_mm[g] - self.grip_mm[g];
            for i in 0..2 {
                centre_mm[i] += self.centre_per_mm[g][i] * dq;
                for j in 0..2 {
                    gradient[i][j] += self.gradient_per_mm[g][i][j] * dq;
                }
            }
        }
        Predicted {
            grip_mm,
            force_n,
            gradient,
            centre_mm,
        }
    }
}

/// Gaussian elimination with partial pivoting of the n × n system in `a` (augmented column
/// at index MAX_GRIPS). I + K c is diagonally dominant for the compliances the rig takes, so
/// a pivot is never zero in practice; a singular system gives non-finite forces, which the
/// plant's NaN limit catches.
fn solve_small(mut a: [[f64; MAX_GRIPS + 1]; MAX_GRIPS], n: usize) -> [f64; MAX_GRIPS] {
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        for row in col + 1..n {
            let factor = a[row][col] / a[col][col];
            for c in col..=MAX_GRIPS {
                a[row][c] -= factor * a[col][c];
            }
        }
    }
    let mut x = [0.0; MAX_GRIPS];
    for row in (0..n).rev() {
        let mut v = a[row][MAX_GRIPS];
        for c in row + 1..n {
            v -= a[row][c] * x[c];
        }
        x[row] = v / a[row][row];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn linearisation() -> Linearisation {
        let mut l = Linearisation {
            grips: 4,
            grip_mm: [10.0, 11.0, 9.0, 12.0],
            force_n: [200.0, 210.0, 190.0, 220.0],
            stiffness_n_per_mm: [[0.0; MAX_GRIPS]; MAX_GRIPS],
            gradient: [[0.3, 0.0], [0.0, 0.31]],
            gradient_per_mm: [[[0.01, 0.0], [0.0, 0.002]]; MAX_GRIPS],
            centre_mm: [0.5, -0.5],
            centre_per_mm: [[0.5, 0.0], [0.0, 0.5], [-0.5, 0.0], [0.0, -0.5]],
        };
        for a in 0..4 {
            for b in 0..4 {
                l.stiffness_n_per_mm[a][b] = if a == b { 2.0 } else { 0.3 };
            }
        }
        l
    }

    #[test]
    fn without_give_the_prediction_is_the_solve_plus_the_tangent_times_the_motion() {
        let l = linearisation();
        let at_solve = l.predict(&l.grip_mm, 0.0);
        assert_eq!(at_solve.force_n, l.force_n);
        assert_eq!(at_solve.gradient, l.gradient);
        let mut x = l.grip_mm;
        x[0] += 1.0;
        let p = l.predict(&x, 0.0);
        assert!((p.force_n[0] - 202.0).abs() < 1e-12);
        assert!((p.force_n[1] - 210.3).abs() < 1e-12);
        assert!((p.centre_mm[0] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn with_give_the_forces_and_the_grips_agree() {
        let l = linearisation();
        let c = 1e-3; // 1 mm/kN
        let mut x = l.grip_mm;
        x[1] += 3.0;
        x[3] -= 1.0;
        let p = l.predict(&x, c);
        for a in 0..4 {
            let mut f = l.force_n[a];
            for b in 0..4 {
                f += l.stiffness_n_per_mm[a][b] * (p.grip_mm[b] - l.grip_mm[b]);
            }
            assert!((f - p.force_n[a]).abs() < 1e-9, "{f} vs {}", p.force_n[a]);
            assert!((p.grip_mm[a] - (x[a] - c * p.force_n[a])).abs() < 1e-12);
        }
    }
}
