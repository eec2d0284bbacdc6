//! The assembly of a frame's field: results (against the current reference, at the ZOI
//! centres) to total displacements at the followed nodes, the relative score and consistency
//! checks, the nodes returned to view measured against the origin, strains and gauges, and what
//! the next frame's guesses need.

use super::parts::PreviousFrames;
use super::{
    compose_gradients, difference, median, median_ok_score, to_mat2, Correlator, OUTLIER_MAX_PX,
    OUTLIER_MIN_PX, OUTLIER_SCATTER,
};
use crate::field::NodeStatus;
use crate::gauges::{read, read_control};
use crate::strain::{node_strains_and_gradients, strains_from_gradients};
use crate::zoi::Image;

impl Correlator {
    /// Results to total displacements at the followed nodes, then strains and gauge.
    pub(super) fn assemble(&mut self, image: Image) {
        self.corrected_results();
        self.total_displacements();
        self.refuse_low_scores();
        self.refuse_inconsistent();
        self.reanchor_returned(image);
        self.mean_displacement();
        self.strains();
        self.remember_frame();
    }

    /// First-order corrections with the local gradient ∇u of the results into
    /// `scratch.pairs`: the rigid ZOI's estimate is u(centre) + K vec(∇u) (see
    /// `GradientSensitivity`), and the followed point is off the ZOI centre by r:
    /// u(x + r) ≈ u(x) + ∇u r. IC-GN measures the subset centre through its own gradient: no
    /// rigid-ZOI bias, and its own gradient carries the followed point.
    fn corrected_results(&mut self) {
        let icgn = self.settings.method.is_icgn();
        let correct_gradient = self.settings.gradient_correction && !icgn;
        for k in 0..self.mesh.len() {
            let r = self.reference.nodes[k];
            let result = self.frame.results[k];
            let mut u = (result.u_px, result.v_px);
            if result.status == NodeStatus::Ok {
                let gradient = if icgn {
                    let g = result.warp_gradient;
                    Some(nalgebra::Matrix2::new(g[0][0], g[0][1], g[1][0], g[1][1]))
                } else {
                    self.result_gradient(k)
                };
                if let Some(g) = gradient {
                    if correct_gradient {
                        // A warped ZOI is biased only by the gradient beyond its warp.
                        let bias = self.reference.sensitivities[k]
                            .bias_px(difference(to_mat2(g), result.warp_gradient));
                        u.0 -= bias.0;
                        u.1 -= bias.1;
                    }
                    u.0 += g[(0, 0)] * r.offset_px.0 + g[(0, 1)] * r.offset_px.1;
                    u.1 += g[(1, 0)] * r.offset_px.0 + g[(1, 1)] * r.offset_px.1;
                }
            }
            self.scratch.pairs[k] = u;
        }
    }

    /// The field's nodes: base plus corrected result where ok, the check's ZNCC as score.
    fn total_displacements(&mut self) {
        for k in 0..self.mesh.len() {
            let r = self.reference.nodes[k];
            let result = self.frame.results[k];
            let node = &mut self.field.nodes[k];
            let ok = result.status == NodeStatus::Ok;
            node.u_px = if ok {
                r.base_px.0 + self.scratch.pairs[k].0
            } else {
                0.0
            };
            node.v_px = if ok {
                r.base_px.1 + self.scratch.pairs[k].1
            } else {
                0.0
            };
            node.score = self.frame.zncc[k];
            node.iterations = result.iterations;
            node.status = result.status;
        }
    }

    /// A node whose score is below `min_relative_score` times the median is not converged.
    fn refuse_low_scores(&mut self) {
        let min_score = self.settings.min_relative_score
            * median_ok_score(self.frame.results.iter().copied(), &mut self.scratch.scores);
        for (node, result) in self.field.nodes.iter_mut().zip(&self.frame.results) {
            if node.status == NodeStatus::Ok && result.score < min_score {
                node.status = NodeStatus::NotConverged;
                node.u_px = 0.0;
                node.v_px = 0.0;
            }
        }
    }

    /// A node far from what its neighbours say (a false match on other material, or a
    /// noise-driven one) is not trusted: it is marked inconsistent, so that it neither biases
    /// the strains nor moves the followed mesh onto the wrong material.
    fn refuse_inconsistent(&mut self) {
        for k in 0..self.mesh.len() {
            self.scratch.residuals[k] = if self.field.nodes[k].status == NodeStatus::Ok {
                self.increment_and_prediction(k)
                    .map_or(f64::NAN, |((u, v), (pu, pv))| (u - pu).hypot(v - pv))
            } else {
                f64::NAN
            };
        }
        let limit_px = median(
            self.scratch.residuals.iter().copied(),
            &mut self.scratch.scores,
        )
        .map_or(OUTLIER_MAX_PX, |m| {
            (OUTLIER_SCATTER * m).clamp(OUTLIER_MIN_PX, OUTLIER_MAX_PX)
        });
        for (outlier, &residual) in self
            .scratch
            .outliers
            .iter_mut()
            .zip(&self.scratch.residuals)
        {
            *outlier = residual > limit_px;
        }
        for (node, _) in self
            .field
            .nodes
            .iter_mut()
            .zip(&self.scratch.outliers)
            .filter(|(_, &outlier)| outlier)
        {
            node.status = NodeStatus::Inconsistent;
            node.u_px = 0.0;
            node.v_px = 0.0;
        }
    }

    /// The count and mean displacement of the valid nodes.
    fn mean_displacement(&mut self) {
        let (mut valid, mut su, mut sv) = (0usize, 0.0, 0.0);
        for node in self
            .field
            .nodes
            .iter()
            .filter(|n| n.status == NodeStatus::Ok)
        {
            valid += 1;
            su += node.u_px;
            sv += node.v_px;
        }
        self.field.valid = valid;
        self.field.u_mean_px = if valid > 0 { su / valid as f64 } else { 0.0 };
        self.field.v_mean_px = if valid > 0 { sv / valid as f64 } else { 0.0 };
    }

    /// Node gradients (IC-GN's own composed with the base's, or the neighbours' fit), node
    /// strains, the control gauge and the user's gauges.
    fn strains(&mut self) {
        if self.settings.method.is_icgn() {
            for k in 0..self.mesh.len() {
                self.field.gradients[k] = if self.field.nodes[k].status == NodeStatus::Ok {
                    compose_gradients(
                        self.frame.results[k].warp_gradient,
                        self.reference.nodes[k].base_gradient,
                    )
                } else {
                    [[0.0; 2]; 2]
                };
            }
            strains_from_gradients(
                &mut self.field.nodes,
                &self.field.gradients,
                self.settings.strain,
            );
        } else {
            node_strains_and_gradients(
                &mut self.field.nodes,
                (self.mesh.nx, self.mesh.ny),
                self.settings.strain_window_nodes,
                self.settings.strain,
                &mut self.field.gradients,
            );
        }
        let step_px = self.settings.step_px as f64;
        let nodes = &self.field.nodes;
        let control = read_control(&self.settings.control_gauge, &self.settings.gauges, nodes);
        self.field.gauge = control.strains_or_nan();
        self.field.gauge_nodes = control.nodes;
        self.field.gauges.clear();
        let readings = (self.settings.gauges.iter()).map(|g| read(&g.shape, nodes, step_px));
        self.field.gauges.extend(readings);
    }

    /// What the next frame's guesses need: the never-lost nodes, the last two fields, IC-GN's
    /// gradients.
    fn remember_frame(&mut self) {
        for (never_lost, node) in self.history.never_lost.iter_mut().zip(&self.field.nodes) {
            *never_lost &= node.status == NodeStatus::Ok;
        }
        let nodes = self.mesh.len();
        let previous = self
            .history
            .previous
            .get_or_insert_with(|| PreviousFrames::new(nodes));
        std::mem::swap(&mut previous.last, &mut previous.before_last);
        previous.last_step = self.frame_step;
        for (p, node) in previous.last.iter_mut().zip(&self.field.nodes) {
            *p = (node.status == NodeStatus::Ok).then_some((node.u_px, node.v_px));
        }
        if self.settings.method.is_icgn() {
            for ((g, node), result) in self
                .history
                .gradients
                .iter_mut()
                .zip(&self.field.nodes)
                .zip(&self.frame.results)
            {
                *g = (node.status == NodeStatus::Ok).then_some(result.warp_gradient);
            }
        }
    }
}
