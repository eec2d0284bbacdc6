//! A solved state followed to nearby grip positions: u(q) = u_s + Σ_g m_g (q_g − q_s,g), with
//! m_g the grips' displacement modes at the solve ([`crate::condense`]). The same first order
//! the rig's forces follow between two solves, for the whole field: what the camera films and
//! what its truth is between two solves.

/// A solve's displacements, its grips' displacements and its grip modes.
#[derive(Clone, Debug, PartialEq)]
pub struct GripLinearField {
    /// u_s: two per node, mm.
    pub displacement_mm: Vec<f64>,
    /// q_s: one per grip, mm.
    pub grip_mm: Vec<f64>,
    /// m_g: per grip, two per node, mm per mm.
    pub modes: Vec<Vec<f64>>,
}

impl GripLinearField {
    /// The nodal displacements (mm, two per node) at grip displacements `grip_mm` (one per
    /// grip, in the solve's order; extra values are ignored, missing ones taken as q_s).
    pub fn at(&self, grip_mm: &[f64]) -> Vec<f64> {
        let mut u = self.displacement_mm.clone();
        for ((mode, &q_s), &q) in self.modes.iter().zip(&self.grip_mm).zip(grip_mm) {
            let dq = q - q_s;
            if dq != 0.0 {
                for (u, m) in u.iter_mut().zip(mode) {
                    *u += m * dq;
                }
            }
        }
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_the_solve_the_field_is_the_solve_and_it_moves_with_each_mode() {
        let field = GripLinearField {
            displacement_mm: vec![1.0, 2.0, 3.0, 4.0],
            grip_mm: vec![10.0, 20.0],
            modes: vec![vec![0.5, 0.0, 0.0, 0.0], vec![0.0, 0.0, 0.0, -1.0]],
        };
        assert_eq!(field.at(&[10.0, 20.0]), field.displacement_mm);
        assert_eq!(field.at(&[12.0, 20.0]), vec![2.0, 2.0, 3.0, 4.0]);
        assert_eq!(field.at(&[12.0, 19.0]), vec![2.0, 2.0, 3.0, 5.0]);
        assert_eq!(
            field.at(&[10.0]),
            field.displacement_mm,
            "a missing grip stays put"
        );
    }
}
