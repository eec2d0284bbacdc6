//! The fitting's residual path: the weighted residuals r_i = (P_model − P_data) · factor_i of
//! every point, their cost Σ r² and the normal equations JᵀJ, Jᵀr accumulated point by point in
//! one pass with the analytic gradients of [`crate::gradient`] (J is never formed).
//!
//! Points are cut into blocks of [`BLOCK_POINTS`]; each block sums into its own slot of a
//! buffer allocated once, and the slots are added in block order, so the result is the same
//! bits whatever the thread count. Blocks are shared among `threads` scoped threads (a
//! problem with fewer blocks than threads uses fewer threads). No allocation per evaluation
//! on one thread; with more, only the threads' own.

use crate::gradient::Kinematics;
use crate::lsq::LeastSquares;
use crate::models::Model;
use nalgebra::{DMatrix, DVector};
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

/// Points per block of the accumulation.
pub const BLOCK_POINTS: usize = 1024;

/// The points of a fit (read-only during an evaluation).
struct Points<'a> {
    model: &'a Model,
    kinematics: Vec<Kinematics>,
    stresses_mpa: Vec<f64>,
    /// sqrt(w_c) / scale_i per point.
    factors: Vec<f64>,
}

impl Points<'_> {
    /// Weighted residual of point `i` and, when `gradient` is given, its gradient ∂r/∂p.
    fn residual(&self, p: &[f64], i: usize, gradient: Option<&mut [f64]>) -> Option<f64> {
        let factor = self.factors[i];
        let model = match gradient {
            Some(g) => {
                let value = self
                    .model
                    .nominal_stress_at(p, &self.kinematics[i], Some(&mut *g))?;
                g.iter_mut().for_each(|v| *v *= factor);
                value
            }
            None => self.model.nominal_stress_at(p, &self.kinematics[i], None)?,
        };
        let r = (model - self.stresses_mpa[i]) * factor;
        r.is_finite().then_some(r)
    }
}

/// The points of a fit and the scratch of their accumulation.
pub struct PointSet<'a> {
    points: Points<'a>,
    params: usize,
    threads: usize,
    /// Per block: cost, Jᵀr (n), upper triangle of JᵀJ (n(n+1)/2).
    partials: Vec<f64>,
    /// Per block: one gradient (n).
    gradients: Vec<f64>,
}

impl<'a> PointSet<'a> {
    /// `points`: (kinematics of the measured direction, nominal stress MPa along it, factor);
    /// `threads` ≥ 1 (0 is 1).
    pub fn new(model: &'a Model, points: &[(Kinematics, f64, f64)], threads: usize) -> Self {
        let params = model.param_names().len();
        let blocks = points.len().div_ceil(BLOCK_POINTS);
        PointSet {
            points: Points {
                model,
                kinematics: points.iter().map(|p| p.0).collect(),
                stresses_mpa: points.iter().map(|p| p.1).collect(),
                factors: points.iter().map(|p| p.2).collect(),
            },
            params,
            threads: threads.max(1),
            partials: vec![0.0; blocks * slot_width(params)],
            gradients: vec![0.0; blocks * params],
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.stresses_mpa.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The residual vector (one allocation; the statistics and the reference path use it).
    pub fn residuals(&self, p: &[f64]) -> Option<DVector<f64>> {
        let mut r = DVector::zeros(self.len());
        for i in 0..self.len() {
            r[i] = self.points.residual(p, i, None)?;
        }
        Some(r)
    }

    /// The Jacobian ∂r/∂p (m × n), analytic; formed once per fit for the standard deviations.
    pub fn jacobian(&self, p: &[f64]) -> DMatrix<f64> {
        let mut jac = DMatrix::zeros(self.len(), self.params);
        let mut g = vec![0.0; self.params];
        for i in 0..self.len() {
            if self.points.residual(p, i, Some(&mut g)).is_some() {
                for (k, v) in g.iter().enumerate() {
                    jac[(i, k)] = *v;
                }
            }
        }
        jac
    }

    /// The linear least-squares system of the parameters flagged in `linear` (the stress is
    /// linear in them) at `base`, where they are zero: design = ∂r/∂p_linear, rhs = −r.
    pub fn linear_system(
        &self,
        base: &[f64],
        linear: &[bool],
    ) -> Option<(DMatrix<f64>, DVector<f64>)> {
        let columns: Vec<usize> = (0..self.params).filter(|&k| linear[k]).collect();
        let mut design = DMatrix::zeros(self.len(), columns.len());
        let mut rhs = DVector::zeros(self.len());
        let mut g = vec![0.0; self.params];
        for i in 0..self.len() {
            rhs[i] = -self.points.residual(base, i, Some(&mut g))?;
            for (col, &k) in columns.iter().enumerate() {
                design[(i, col)] = g[k];
            }
        }
        Some((design, rhs))
    }

    /// Runs `work(points, block's point range, block's slot, a gradient buffer)` on every
    /// block, spread over the threads; false if any block returned false.
    fn for_each_block<F>(&mut self, width: usize, work: F) -> bool
    where
        F: Fn(&Points, Range<usize>, &mut [f64], &mut [f64]) -> bool + Sync,
    {
        let m = self.len();
        let n = self.params;
        let blocks = m.div_ceil(BLOCK_POINTS);
        let points = &self.points;
        let partials = &mut self.partials[..blocks * width];
        let gradients = &mut self.gradients[..blocks * n];
        let run = |first_block: usize, slots: &mut [f64], grads: &mut [f64]| -> bool {
            let mut ok = true;
            for ((b, slot), g) in slots.chunks_mut(width).enumerate().zip(grads.chunks_mut(n)) {
                let block = first_block + b;
                let range = block * BLOCK_POINTS..((block + 1) * BLOCK_POINTS).min(m);
                ok &= work(points, range, slot, g);
            }
            ok
        };
        let threads = self.threads.min(blocks).max(1);
        if threads == 1 {
            return run(0, partials, gradients);
        }
        let per_thread = blocks.div_ceil(threads);
        let all_ok = AtomicBool::new(true);
        std::thread::scope(|scope| {
            let mut slot_chunks = partials.chunks_mut(per_thread * width);
            let mut grad_chunks = gradients.chunks_mut(per_thread * n);
            let own = (slot_chunks.next(), grad_chunks.next());
            for (t, (slots, grads)) in slot_chunks.zip(grad_chunks).enumerate() {
                let (run, all_ok) = (&run, &all_ok);
                scope.spawn(move || {
                    if !run((t + 1) * per_thread, slots, grads) {
                        all_ok.store(false, Ordering::Relaxed);
                    }
                });
            }
            if let (Some(slots), Some(grads)) = own {
                if !run(0, slots, grads) {
                    all_ok.store(false, Ordering::Relaxed);
                }
            }
        });
        all_ok.into_inner()
    }
}

/// Width of a block's slot: cost, Jᵀr, upper triangle of JᵀJ.
fn slot_width(params: usize) -> usize {
    1 + params + params * (params + 1) / 2
}

impl LeastSquares for PointSet<'_> {
    fn points(&self) -> usize {
        self.len()
    }

    fn cost(&mut self, p: &[f64]) -> Option<f64> {
        let ok = self.for_each_block(1, |points, range, slot, _| {
            let mut cost = 0.0;
            for i in range {
                match points.residual(p, i, None) {
                    Some(r) => cost += r * r,
                    None => return false,
                }
            }
            slot[0] = cost;
            true
        });
        let blocks = self.len().div_ceil(BLOCK_POINTS);
        let cost: f64 = self.partials[..blocks].iter().sum();
        (ok && cost.is_finite()).then_some(cost)
    }

    fn normal_equations(&mut self, p: &[f64], jtj: &mut DMatrix<f64>, jtr: &mut DVector<f64>) {
        let n = self.params;
        let width = slot_width(n);
        self.for_each_block(width, |points, range, slot, g| {
            slot.fill(0.0);
            let (cost, rest) = slot.split_at_mut(1);
            let (jr, upper) = rest.split_at_mut(n);
            for i in range {
                let Some(r) = points.residual(p, i, Some(g)) else {
                    continue;
                };
                cost[0] += r * r;
                let mut u = 0;
                for a in 0..n {
                    jr[a] += g[a] * r;
                    for b in a..n {
                        upper[u] += g[a] * g[b];
                        u += 1;
                    }
                }
            }
            true
        });
        let blocks = self.len().div_ceil(BLOCK_POINTS);
        jtj.fill(0.0);
        jtr.fill(0.0);
        for slot in self.partials[..blocks * width].chunks(width) {
            let (jr, upper) = slot[1..].split_at(n);
            let mut u = 0;
            for a in 0..n {
                jtr[a] += jr[a];
                for b in a..n {
                    jtj[(a, b)] += upper[u];
                    u += 1;
                }
            }
        }
        for a in 0..n {
            for b in 0..a {
                jtj[(a, b)] = jtj[(b, a)];
            }
        }
    }
}
