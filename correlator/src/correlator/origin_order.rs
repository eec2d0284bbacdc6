//! Method `icgn` against the origin: the order chosen per node there too. At a reference
//! renewal each node's new base (its total displacement since the origin) is measured against
//! the origin (`reanchor.rs`), at first order. The field's curvature biases that measurement
//! as it biases the frame's (`icgn/order_choice.rs`), and the bias of the total displacement
//! is that of all the increments at once: on the finite-element cruciform with the automatic
//! reference, bases measured at first order left `icgn` with `icgn1`'s error at the fillets
//! (p99 0.103 against 0.109 px; `icgn2` 0.032: `tests/suite/structure.rs`). So the base
//! measurements whose first-order bias exceeds `BIAS_TO_NOISE` times their noise are measured
//! again at second order, from the first-order warp, by the criterion of the frame's: the
//! curvature from the 3 x 3 neighbours' first-order gradients (here the origin measurements'),
//! the noise from their median residual and each node's origin subset. The second order
//! replaces the first when it converged and its ZNCC is at least the first's and `min_zncc`.

use super::icgn_stage::OriginIcgn;
use super::order_stage::second_order_needed;
use super::{median, Correlator};
use crate::field::NodeStatus;
use crate::icgn::order_choice::NoiseScale;
use crate::icgn::shape::Order;
use crate::pool::SharedSlice;
use crate::settings::Method;
use crate::verify;
use crate::zoi::{Image, ZoiResult};

/// The buffers of [`Correlator::origin_second_order`] (kept: the live path allocates nothing).
#[derive(Debug, Default)]
pub(super) struct OriginOrderScratch {
    /// The first-order origin measurements by node (not `ok` where there is none).
    results: Vec<ZoiResult>,
    /// Entries re-measured at second order.
    second: Vec<usize>,
    /// Residuals, for their median.
    residuals: Vec<f64>,
    /// Each entry's noise scale, from its first-order origin subset.
    noise: Vec<NoiseScale>,
}

impl OriginOrderScratch {
    pub fn new(nodes: usize) -> Self {
        Self {
            results: Vec::with_capacity(nodes),
            second: Vec::with_capacity(nodes),
            residuals: Vec::with_capacity(nodes),
            noise: Vec::with_capacity(nodes),
        }
    }

    /// `entries` slots for the first-order measurements' noise scales, written on the pool.
    pub fn noise_slots(&mut self, entries: usize) -> SharedSlice<'_, NoiseScale> {
        self.noise.clear();
        self.noise.resize(entries, NoiseScale::default());
        SharedSlice::new(&mut self.noise)
    }
}

impl Correlator {
    /// Re-measures at second order the entries of `measure_against_origin` (`scratch.entries`,
    /// their first-order results and scores in `reanchored`) that need it: method `icgn`
    /// only. `first` measured them, `origin` is the origin's image and `image` the one they
    /// were measured in.
    pub(super) fn origin_second_order(
        &self,
        first: &OriginIcgn<'_>,
        origin: Image,
        image: Image,
        reanchored: &mut [(ZoiResult, f64)],
        buffers: &mut OriginOrderScratch,
    ) {
        if self.settings.method != Method::Icgn {
            return;
        }
        let (n, min_zncc) = (self.settings.zoi_px, self.settings.min_zncc);
        let entries = &self.scratch.entries;
        let verified =
            |i: usize| reanchored[i].0.status == NodeStatus::Ok && reanchored[i].1 >= min_zncc;
        let missing = ZoiResult {
            status: NodeStatus::LowZncc,
            ..ZoiResult::default()
        };
        buffers.results.clear();
        buffers.results.resize(self.field.nodes.len(), missing);
        for (i, entry) in entries.iter().enumerate().filter(|&(i, _)| verified(i)) {
            buffers.results[entry.node] = reanchored[i].0;
        }
        let noise = &buffers.noise;
        let Some(residual_counts2) = median(
            (0..entries.len())
                .filter(|&i| verified(i))
                .map(|i| noise[i].residual_counts2),
            &mut buffers.residuals,
        ) else {
            return;
        };
        let mesh = (self.mesh.nx, self.mesh.ny);
        buffers.second.clear();
        for i in (0..entries.len()).filter(|&i| verified(i)) {
            let k = entries[i].node;
            let noise = noise[i].noise_px(residual_counts2);
            if second_order_needed(&buffers.results, &self.reference.nodes, mesh, k, n, noise) {
                buffers.second.push(i);
            }
        }
        let second = first.at_order(Order::Second);
        let (list, top_left) = (&buffers.second, &self.mesh.top_left);
        let out = SharedSlice::new(reanchored);
        self.pool.run(list.len(), &|engine, j| {
            let i = list[j];
            let top_left = top_left[entries[i].node];
            // SAFETY: item j reads and writes only slot list[j]; the list holds an entry once.
            let (first, _) = unsafe { out.read(i) };
            let mut scratch = std::mem::take(&mut engine.subset_scratch);
            let (result, _) = second.measure(
                top_left,
                (first.u_px, first.v_px),
                first.warp_gradient,
                &mut scratch,
            );
            engine.subset_scratch = scratch;
            if result.status != NodeStatus::Ok || result.score < first.score {
                return;
            }
            let displacement = (result.u_px, result.v_px);
            let score = verify::zncc(
                origin,
                top_left,
                n,
                image,
                displacement,
                result.warp_gradient,
            )
            .unwrap_or(0.0);
            if score >= min_zncc {
                // SAFETY: as above.
                unsafe { out.write(i, (result, score)) };
            }
        });
    }
}
