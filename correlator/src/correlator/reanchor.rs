//! Nodes whose material came back into view on a followed mesh. While a node's material was
//! out of the image (or its match failed), its position was carried by the affine
//! extrapolation of its neighbours, reference update after reference update; when the material
//! returns, the node measures whatever material its carried position landed on, so its total
//! displacement carries the extrapolation's error (up to 2 px after a large stretch and a fast
//! unloading), and the final check against the current reference cannot see it: that match is
//! right. Such a node is measured again against the frame its mesh was defined in (the origin):
//! its own ZOI there, correlated with the frame through the total displacement and the gradient
//! of its never-lost neighbours, then checked with the same final check. A node that verifies
//! gets that total displacement (and its base is corrected, so it counts as never lost again); a
//! node that does not is `low_zncc`, never a wrong `ok`. Without the origin image (a correlator
//! restored from a saved reference whose `origin.state` is missing) the returned nodes stay as
//! measured.

use super::{
    to_mat2, Correlator, Entry, FrameCoefficients, Support, CARRY_RINGS, EXTRAPOLATION_RINGS,
    LOCAL_RINGS,
};
use crate::field::NodeStatus;
use crate::interpolate::Mat2;
use crate::pool::SharedSlice;
use crate::verify;
use crate::zoi::{Image, ZoiResult, ZoiSearch};

impl Correlator {
    /// Measures the returned nodes against the origin (see the module documentation).
    pub(super) fn reanchor_returned(&mut self, image: Image) {
        if self.origin.is_none() || self.reference.is_origin {
            return;
        }
        let whole_mesh = self.affine_fit(None, 0, None, Support::NeverLost);
        self.scratch.entries.clear();
        for k in 0..self.field.nodes.len() {
            let node = self.field.nodes[k];
            if node.status != NodeStatus::Ok || self.history.never_lost[k] {
                continue;
            }
            let gradient: Mat2 = self
                .affine_fit(Some(k), CARRY_RINGS, Some(k), Support::NeverLost)
                .or(whole_mesh)
                .map_or([[0.0; 2]; 2], |fit| to_mat2(fit.gradient));
            self.scratch.entries.push(Entry {
                node: k,
                guess_px: (node.u_px, node.v_px),
                gradient,
            });
        }
        // Carried by an extrapolation, up to pixels off: the full search.
        self.measure_against_origin(image, false, FrameCoefficients::Frame);
        for (entry, &(result, score)) in self.scratch.entries.iter().zip(&self.scratch.reanchored) {
            let k = entry.node;
            let node = &mut self.field.nodes[k];
            if result.status == NodeStatus::Ok && score >= self.settings.min_zncc {
                let correction = (result.u_px - node.u_px, result.v_px - node.v_px);
                node.u_px = result.u_px;
                node.v_px = result.v_px;
                node.score = score;
                let base = &mut self.reference.nodes[k].base_px;
                base.0 += correction.0;
                base.1 += correction.1;
                self.history.never_lost[k] = true;
            } else {
                node.status = NodeStatus::LowZncc;
                node.score = score;
                node.u_px = 0.0;
                node.v_px = 0.0;
            }
        }
    }

    /// At a reference update, the new bases (`scratch_pairs`, the nodes' total displacements)
    /// of the `ok` nodes are measured against the origin directly, where that verifies: the
    /// errors of the measurements against intermediate references then do not add up from
    /// reference to reference (a border node of an incremental reference drifted by 1.7 px
    /// over 70 updates without this).
    pub(super) fn bases_from_origin(&mut self, image: Image) {
        if self.origin.is_none() || self.reference.is_origin {
            return;
        }
        let mut entries = std::mem::take(&mut self.scratch.entries);
        self.origin_entries(0, &mut entries);
        self.scratch.entries = entries;
        // Each guess is the node's total displacement just measured (within a pixel of what the
        // origin gives): the prediction's shortcut, the full search where it is not confirmed.
        self.measure_against_origin(image, true, FrameCoefficients::Frame);
        for (entry, &(result, score)) in self.scratch.entries.iter().zip(&self.scratch.reanchored) {
            if result.status == NodeStatus::Ok && score >= self.settings.min_zncc {
                self.scratch.pairs[entry.node] = (result.u_px, result.v_px);
            }
        }
    }

    /// The entries of [`Self::bases_from_origin`] (the `ok` nodes, each with its new base and
    /// the gradient of its neighbours' fit) into `entries`, from node `first` round the mesh.
    fn origin_entries(&self, first: usize, entries: &mut Vec<Entry>) {
        entries.clear();
        let nodes = self.field.nodes.len();
        for k in (first..nodes).chain(0..first.min(nodes)) {
            if self.field.nodes[k].status != NodeStatus::Ok {
                continue;
            }
            let gradient: Mat2 = self
                .affine_fit(Some(k), LOCAL_RINGS, None, Support::Valid)
                .or_else(|| self.affine_fit(Some(k), EXTRAPOLATION_RINGS, None, Support::Valid))
                .map_or([[0.0; 2]; 2], |fit| to_mat2(fit.gradient));
            entries.push(Entry {
                node: k,
                guess_px: self.scratch.pairs[k],
                gradient,
            });
        }
    }

    /// [`Self::bases_from_origin`] left to [`Correlator::measure_pending_bases`]: the entries
    /// are kept (`reference.origin_pending`), the new reference starts from the bases measured
    /// through the references before it. The pass starts where the last one stopped, so that
    /// renewals closer together than a pass still measure every node in turn.
    pub(super) fn defer_bases_from_origin(&mut self) {
        let mut pending = std::mem::take(&mut self.reference.origin_pending);
        if self.origin.is_some() && !self.reference.is_origin {
            self.origin_entries(self.reference.origin_next_node, &mut pending);
        } else {
            pending.clear();
        }
        self.reference.origin_pending = pending;
    }

    /// Measures the next `max_nodes` pending bases of the current reference against the origin
    /// (see [`Self::defer_bases_from_origin`]) and corrects those that verify, as
    /// [`Self::bases_from_origin`] would have at the renewal: the node's ZOI stays where the
    /// reference put it, its followed point moves by the correction (`offset_px`). Returns true
    /// when this completed the reference's pass.
    pub(super) fn measure_some_pending_bases(&mut self, max_nodes: usize) -> bool {
        let pending = self.reference.origin_pending.len();
        if pending == 0 || max_nodes == 0 {
            return false;
        }
        let take = max_nodes.min(pending);
        self.scratch.entries.clear();
        self.scratch
            .entries
            .extend(self.reference.origin_pending.drain(..take));
        let Some(pixels) = self.reference.pixels.take() else {
            return false;
        };
        let image = Image {
            pixels: &pixels,
            width_px: self.width_px,
            height_px: self.height_px,
        };
        self.measure_against_origin(image, true, FrameCoefficients::Reference);
        self.reference.pixels = Some(pixels);
        for (entry, &(result, score)) in self.scratch.entries.iter().zip(&self.scratch.reanchored) {
            let r = &mut self.reference.nodes[entry.node];
            if result.status == NodeStatus::Ok && score >= self.settings.min_zncc {
                let correction = (result.u_px - r.base_px.0, result.v_px - r.base_px.1);
                r.base_px = (result.u_px, result.v_px);
                r.offset_px.0 += correction.0;
                r.offset_px.1 += correction.1;
            }
            self.reference.origin_next_node = (entry.node + 1) % self.mesh.len();
        }
        self.reference.origin_pending.is_empty()
    }

    /// Each of `entries` (node, total displacement, gradient) measured against the origin:
    /// its ZOI there correlated with `image` through the gradient, and the final check; the
    /// results and their ZNCC go to `reanchored`, in the order of `entries`. `predicted`: the
    /// guesses are within a pixel (see [`ZoiSearch::predicted`]).
    fn measure_against_origin(
        &mut self,
        image: Image,
        predicted: bool,
        coefficients: FrameCoefficients,
    ) {
        let (n, pad) = (self.settings.zoi_px, self.fft_pad_px);
        let offset = (n - self.fft_px) as f64 / 2.0 - pad as f64;
        // A measurement, not a guess, when IC-GN has no origin coefficients: the paper's iterations.
        let iterations = crate::zoi::SubpixelIterations::paper(self.settings.max_iterations);
        let Some(origin) = &self.origin else {
            return;
        };
        let origin = Image {
            pixels: &origin.pixels,
            width_px: self.width_px,
            height_px: self.height_px,
        };
        // Out of `self` while the items write it (no allocation: the buffer moves back).
        let mut reanchored = std::mem::take(&mut self.scratch.reanchored);
        let mut origin_order = std::mem::take(&mut self.scratch.origin_order);
        reanchored.clear();
        reanchored.resize(self.scratch.entries.len(), (ZoiResult::default(), 0.0));
        let (entries, top_left) = (&self.scratch.entries, &self.mesh.top_left);
        let out = SharedSlice::new(&mut reanchored);
        // IC-GN methods measure with IC-GN: the origin's subset prepared on the fly.
        let icgn = self.origin_icgn(coefficients);
        let min_zncc = self.settings.min_zncc;
        let noise = origin_order.noise_slots(entries.len());
        self.pool.run(entries.len(), &|engine, i| {
            let entry = entries[i];
            let (x0, y0) = top_left[entry.node];
            if let Some(icgn) = &icgn {
                let mut scratch = std::mem::take(&mut engine.subset_scratch);
                let (result, scale) =
                    icgn.measure((x0, y0), entry.guess_px, entry.gradient, &mut scratch);
                engine.subset_scratch = scratch;
                // SAFETY: item i writes only slot i.
                unsafe { noise.write(i, scale) };
                let score = if result.status == NodeStatus::Ok {
                    let check =
                        |g| verify::zncc(origin, (x0, y0), n, image, (result.u_px, result.v_px), g);
                    let own = check(result.warp_gradient).unwrap_or(0.0);
                    if own < min_zncc {
                        own.max(check(entry.gradient).unwrap_or(0.0))
                    } else {
                        own
                    }
                } else {
                    0.0
                };
                // SAFETY: item i writes only slot i.
                unsafe { out.write(i, (result, score)) };
                return;
            }
            let search = ZoiSearch {
                top_left_px: (x0 + pad, y0 + pad),
                guess_px: entry.guess_px,
                warp: Some(entry.gradient),
                iterations,
                predicted,
            };
            let result = engine.correlate_uncached(origin, image, search);
            // The FFT ZOI's centre is `offset` px from the node's when an odd subset holds an
            // even FFT ZOI: the node's own displacement is the gradient's step from there.
            let mut result = result;
            let g = entry.gradient;
            result.u_px += (g[0][0] + g[0][1]) * offset;
            result.v_px += (g[1][0] + g[1][1]) * offset;
            let score = if result.status == NodeStatus::Ok {
                verify::zncc(
                    origin,
                    (x0, y0),
                    n,
                    image,
                    (result.u_px, result.v_px),
                    entry.gradient,
                )
                .unwrap_or(0.0)
            } else {
                0.0
            };
            // SAFETY: item i writes only slot i.
            unsafe { out.write(i, (result, score)) };
        });
        if let Some(icgn) = &icgn {
            self.origin_second_order(icgn, origin, image, &mut reanchored, &mut origin_order);
        }
        self.scratch.reanchored = reanchored;
        self.scratch.origin_order = origin_order;
    }
}
