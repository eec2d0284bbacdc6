//! Method `icgn`'s second pass: after the first-order IC-GN of every node (`icgn_stage.rs`),
//! the nodes whose first-order displacement the field's curvature biases by more than
//! `icgn::order_choice::BIAS_TO_NOISE` times its noise are re-run at second order from their
//! first-order warp (see `icgn/order_choice.rs` for the criterion and its derivation). The
//! second-order result replaces the first when it converged, its ZNCC is at least the first's
//! and it passes the final check; `Field::second_order` records the nodes it replaced and
//! `Field::second_order_runs` how many were re-run. A subset's second-order constants are
//! derived from its first-order planes on its first re-run against a reference, on the pool,
//! and kept (`Reference::second_order_stats`): a smooth field costs none.

use super::icgn_stage::FinalCheck;
use super::parts::SubsetState;
use super::{median, neighbourhood_gradient, Correlator, Entry, RefNode};
use crate::field::NodeStatus;
use crate::icgn::order_choice::{self, Curvature};
use crate::icgn::shape::{Order, Warp};
use crate::icgn::subset::{self, PLANES};
use crate::icgn::{self, Subset};
use crate::pool::SharedSlice;
use crate::settings::Method;
use crate::zoi::{Image, Timer, ZoiResult};

impl Correlator {
    /// The second pass (method `icgn` only; the flags are cleared whatever the method).
    pub(super) fn refine_second_order(&mut self, image: Image) {
        self.field.second_order.fill(false);
        self.field.second_order_runs = 0;
        if self.settings.method != Method::Icgn {
            return;
        }
        let n = self.settings.zoi_px;
        let (results, states, stats) = (
            &self.frame.results,
            &self.reference.subset_states,
            &self.reference.subset_stats,
        );
        let first_order_ok =
            |k: usize| results[k].status == NodeStatus::Ok && states[k] == SubsetState::Ready;
        // The field's noise: the median residual per pixel of its first-order results.
        let Some(residual_counts2) = median(
            (0..results.len())
                .filter(|&k| first_order_ok(k))
                .map(|k| order_choice::residual_counts2(results[k].score, &stats[k], n)),
            &mut self.scratch.scores,
        ) else {
            return;
        };
        let mesh = (self.mesh.nx, self.mesh.ny);
        self.scratch.entries.clear();
        for k in (0..results.len()).filter(|&k| first_order_ok(k)) {
            let noise = order_choice::displacement_noise_px(&stats[k], residual_counts2);
            if second_order_needed(results, &self.reference.nodes, mesh, k, n, noise) {
                self.scratch.entries.push(Entry {
                    node: k,
                    guess_px: (results[k].u_px, results[k].v_px),
                    gradient: results[k].warp_gradient,
                });
            }
        }
        self.field.second_order_runs = self.scratch.entries.len();
        let half = (n as f64 - 1.0) / 2.0;
        let values = PLANES * n * n;
        let (max_iterations, min_zncc) = (self.settings.max_iterations, self.settings.min_zncc);
        let reference = Image {
            pixels: super::reference_pixels(&self.reference.pixels),
            width_px: self.width_px,
            height_px: self.height_px,
        };
        let coefficients = self.coefficients.as_ref().expect("IC-GN coefficients");
        let (entries, ref_nodes) = (&self.scratch.entries, &self.reference.nodes);
        let (planes, stats) = (&self.reference.subset_planes, &self.reference.subset_stats);
        let second_stats = SharedSlice::new(&mut self.reference.second_order_stats);
        let second_states = SharedSlice::new(&mut self.reference.second_order_states);
        let results = SharedSlice::new(&mut self.frame.results);
        let zncc = SharedSlice::new(&mut self.frame.zncc);
        let flags = SharedSlice::new(&mut self.field.second_order);
        let check = FinalCheck {
            reference,
            n,
            image,
            min_zncc,
        };
        self.pool.run(entries.len(), &|engine, i| {
            let entry = entries[i];
            let k = entry.node;
            let top_left = ref_nodes[k].top_left;
            let mut timer = Timer::start(engine.profile);
            let planes = &planes[k * values..(k + 1) * values];
            // SAFETY: item i touches only node entries[i].node's slots; nodes are distinct.
            let second = unsafe { second_stats.slice_mut(k, 1) };
            let mut state = unsafe { second_states.read(k) };
            if state == SubsetState::Unprepared {
                let spec = subset::SubsetSpec {
                    top_left_px: top_left,
                    side_px: n,
                    order: Order::Second,
                };
                state = if subset::restate(spec, planes, &stats[k], &mut second[0]) {
                    SubsetState::Ready
                } else {
                    SubsetState::Flat
                };
                unsafe { second_states.write(k, state) };
                timer.lap(&mut engine.split.other_ns);
            }
            if state == SubsetState::Flat {
                return;
            }
            let subset = Subset {
                planes,
                stats: &second[0],
                n,
                centre_px: (top_left.0 as f64 + half, top_left.1 as f64 + half),
            };
            let guess = Warp::affine(entry.guess_px, entry.gradient);
            let first: ZoiResult = unsafe { results.read(k) };
            let outcome = icgn::solve(
                &subset,
                Order::Second,
                coefficients,
                guess,
                max_iterations,
                icgn::Stop::Converged,
            );
            timer.lap(&mut engine.split.iterations_ns);
            if outcome.status != NodeStatus::Ok || outcome.zncc < first.score {
                return;
            }
            let (result, score) = check.apply(top_left, &outcome, entry.gradient);
            timer.lap(&mut engine.split.check_ns);
            if result.status == NodeStatus::Ok {
                // SAFETY: as above.
                unsafe {
                    results.write(k, result);
                    zncc.write(k, score);
                    flags.write(k, true);
                }
            }
        });
    }
}

/// Whether node k's first-order result (`results` by node, on an nx x ny mesh of side-n
/// subsets) is biased by the curvature of its neighbours' gradients by more than
/// `order_choice::BIAS_TO_NOISE` times its noise `noise_px` (u, v): the choice of this frame's
/// second pass and of the measurements against the origin (`origin_order.rs`). False without a
/// curvature.
pub(super) fn second_order_needed(
    results: &[ZoiResult],
    ref_nodes: &[RefNode],
    mesh: (usize, usize),
    k: usize,
    n: usize,
    noise_px: (f64, f64),
) -> bool {
    curvature(results, ref_nodes, mesh, k).is_some_and(|c| {
        order_choice::needs_second_order(order_choice::first_order_bias_px(c, n), noise_px)
    })
}

/// The curvature at node k of an nx x ny mesh from the first-order gradients
/// (`warp_gradient`) of the `ok` nodes among the 3 x 3 around it: the slopes of the planes
/// fitted to ∂u/∂x and ∂v/∂x give u_xx and v_xx along x, those fitted to ∂u/∂y and ∂v/∂y give
/// u_yy and v_yy along y (the fit over three rows has a third of the variance of one row's
/// central difference); None with fewer than 3 such nodes or collinear ones.
fn curvature(
    results: &[ZoiResult],
    ref_nodes: &[RefNode],
    mesh: (usize, usize),
    k: usize,
) -> Option<Curvature> {
    let fit = |value: fn(&ZoiResult) -> (f64, f64)| {
        neighbourhood_gradient(results, ref_nodes, mesh, k, value)
    };
    let of_x = fit(|r| (r.warp_gradient[0][0], r.warp_gradient[1][0]))?;
    let of_y = fit(|r| (r.warp_gradient[0][1], r.warp_gradient[1][1]))?;
    Some(Curvature {
        u_xx: of_x[(0, 0)],
        v_xx: of_x[(1, 0)],
        u_yy: of_y[(0, 1)],
        v_yy: of_y[(1, 1)],
    })
}
