//! What happens after the first pass: the final check of every result (all guess modes), and,
//! with guess `auto`, the cheaper-first rescue of the nodes that fail it:
//!
//! 1. **Reliability-guided growth** (as Ncorr does): a node that failed gets a new guess from
//!    its best-verified neighbour (highest ZNCC), extrapolated with that neighbour's local
//!    gradient, and its deformed ZOI is sampled through that gradient. Growth goes in waves
//!    (every failed node next to a verified one, in parallel), each node retried only when it
//!    has gained verified neighbours, until a wave verifies nothing new.
//! 2. **Keypoints**, when fewer than half the textured nodes in view verify after growth (a rotation or
//!    a strain too large for the global correlation): a local affine guess per node from
//!    keypoints matched over the whole image (`keypoints`), then growth again.
//! 3. **Refinement** on a fresh reference (no previous field): every verified node whose
//!    measured local gradient differs from the one its ZOI was sampled through (by more than
//!    [`crate::zoi::MIN_WARP_PX`] at the ZOI border) is correlated again through the measured
//!    gradient, so only a small residual is left to the rigid ZOI.
//!
//! Every new result passes the same check before it counts.

use super::{difference, to_mat2, Correlator, Entry};
use crate::field::NodeStatus;
use crate::interpolate::Mat2;
use crate::keypoints::KeypointMatcher;
use crate::pool::SharedSlice;
use crate::verify;
use crate::zoi::{spectrum_len, warp_worth_it, Image, ReferenceSpectra, ZoiSearch};

/// Keypoints run when fewer than this fraction of the nodes that could verify (textured, not
/// outside the image) do after growth.
const KEYPOINTS_BELOW_FRACTION: f64 = 0.5;

impl Correlator {
    fn reference_image(&self) -> Image<'_> {
        Image {
            pixels: super::reference_pixels(&self.reference.pixels),
            width_px: self.width_px,
            height_px: self.height_px,
        }
    }

    /// The local gradient of node k's neighbourhood of verified results, else the gradient
    /// its ZOI was sampled through.
    pub(super) fn local_gradient(&self, k: usize) -> Mat2 {
        self.result_gradient(k)
            .map_or(self.frame.results[k].warp_gradient, to_mat2)
    }

    /// The final check of every `ok` result: the ZNCC through its displacement and its
    /// neighbourhood's gradient, or its own warp when that fails (a false neighbour must not
    /// fail a good node); below `min_zncc` the node is `low_zncc`.
    pub(super) fn verify_results(&mut self, image: Image) {
        let n = self.settings.zoi_px;
        let min_zncc = self.settings.min_zncc;
        let reference = Image {
            pixels: super::reference_pixels(&self.reference.pixels),
            width_px: self.width_px,
            height_px: self.height_px,
        };
        let (results, ref_nodes) = (&self.frame.results, &self.reference.nodes);
        let mesh = (self.mesh.nx, self.mesh.ny);
        let zncc = SharedSlice::new(&mut self.frame.zncc);
        // Results are only read here; the verdicts go to `zncc` and become statuses below.
        self.pool.run(results.len(), &|engine, k| {
            let mut timer = crate::zoi::Timer::start(engine.profile);
            let result = results[k];
            let mut score = 0.0;
            if result.status == NodeStatus::Ok {
                let gradient = super::result_gradient(results, ref_nodes, mesh, k)
                    .map_or(result.warp_gradient, to_mat2);
                let u = (result.u_px, result.v_px);
                let top_left = ref_nodes[k].top_left;
                let check = |g: Mat2| verify::zncc(reference, top_left, n, image, u, g);
                score = check(gradient).unwrap_or(0.0);
                if score < min_zncc && gradient != result.warp_gradient {
                    score = score.max(check(result.warp_gradient).unwrap_or(0.0));
                }
            }
            timer.lap(&mut engine.split.check_ns);
            // SAFETY: item k writes only node k's slot.
            unsafe { zncc.write(k, score) };
        });
        for (result, &score) in self.frame.results.iter_mut().zip(&self.frame.zncc) {
            if result.status == NodeStatus::Ok && score < min_zncc {
                result.status = NodeStatus::LowZncc;
            }
        }
    }

    /// Guess `auto` after the first pass: growth, keypoints when too few nodes verify, and
    /// the refinement of a fresh reference (see the module documentation).
    pub(super) fn improve(&mut self, image: Image) {
        let fresh = self.history.previous.is_none();
        self.grow(image);
        // Nodes that could have verified: textured in the reference, and not sent out of the
        // image (material that left the field of view is no failure of the guess).
        let (mut candidates, mut verified) = (0usize, 0usize);
        for (r, result) in self.reference.nodes.iter().zip(&self.frame.results) {
            if r.status == NodeStatus::Ok && result.status != NodeStatus::OutsideImage {
                candidates += 1;
                verified += usize::from(result.status == NodeStatus::Ok);
            }
        }
        if (verified as f64) < KEYPOINTS_BELOW_FRACTION * candidates as f64
            && self.keypoint_pass(image)
        {
            self.grow(image);
        }
        // IC-GN refines every node through its own gradient anyway.
        if fresh && !self.settings.method.is_icgn() {
            self.refine(image);
        }
    }

    /// Reliability-guided growth from the verified nodes (module documentation, step 1).
    fn grow(&mut self, image: Image) {
        let (nx, ny) = (self.mesh.nx, self.mesh.ny);
        self.scratch.grown_from.fill(0);
        loop {
            self.scratch.entries.clear();
            for k in 0..nx * ny {
                if self.reference.nodes[k].status != NodeStatus::Ok
                    || self.frame.results[k].status == NodeStatus::Ok
                {
                    continue;
                }
                let (i, j) = (k % nx, k / nx);
                let (mut count, mut best) = (0u8, None::<usize>);
                for jj in j.saturating_sub(1)..=(j + 1).min(ny - 1) {
                    for ii in i.saturating_sub(1)..=(i + 1).min(nx - 1) {
                        let m = jj * nx + ii;
                        if m != k && self.frame.results[m].status == NodeStatus::Ok {
                            count += 1;
                            if best.is_none_or(|b| self.frame.zncc[m] > self.frame.zncc[b]) {
                                best = Some(m);
                            }
                        }
                    }
                }
                let Some(m) = best else { continue };
                if count <= self.scratch.grown_from[k] {
                    continue;
                }
                self.scratch.grown_from[k] = count;
                let g = self.local_gradient(m);
                let (a, b) = (
                    self.reference.nodes[k].top_left,
                    self.reference.nodes[m].top_left,
                );
                let (dx, dy) = (a.0 as f64 - b.0 as f64, a.1 as f64 - b.1 as f64);
                let from = self.frame.results[m];
                self.scratch.entries.push(Entry {
                    node: k,
                    guess_px: (
                        from.u_px + g[0][0] * dx + g[0][1] * dy,
                        from.v_px + g[1][0] * dx + g[1][1] * dy,
                    ),
                    gradient: g,
                });
            }
            if self.scratch.entries.is_empty() {
                return;
            }
            if self.correlate_entries(image, false) == 0 {
                return;
            }
        }
    }

    /// Keypoints matched over the whole image seed every node that has not verified with a
    /// local affine guess (module documentation, step 2). False when the keypoints gave no
    /// trustworthy map.
    fn keypoint_pass(&mut self, image: Image) -> bool {
        let (w, h) = (self.width_px, self.height_px);
        let mut matcher = self
            .keypoint_matcher
            .take()
            .unwrap_or_else(|| KeypointMatcher::new(w, h, self.settings.threads));
        if self.reference.keypoints.is_none() {
            let roi = self.roi;
            let region = (roi.x_px, roi.y_px, roi.width_px, roi.height_px);
            self.reference.keypoints = Some(matcher.detect(self.reference_image(), region));
        }
        let deformed = matcher.detect(image, (0, 0, w, h));
        let guess = self
            .reference
            .keypoints
            .as_ref()
            .and_then(|reference| matcher.estimate(reference, &deformed));
        self.keypoint_matcher = Some(matcher);
        let Some(guess) = guess else {
            return false;
        };
        self.field.keypoints_used = true;
        let half = (self.settings.zoi_px as f64 - 1.0) / 2.0;
        self.scratch.entries.clear();
        for k in 0..self.frame.results.len() {
            if self.reference.nodes[k].status != NodeStatus::Ok
                || self.frame.results[k].status == NodeStatus::Ok
            {
                continue;
            }
            let (x0, y0) = self.reference.nodes[k].top_left;
            let c = [x0 as f64 + half, y0 as f64 + half];
            let affine = guess.local_affine(c);
            let moved = affine.apply(c);
            let a = affine.a;
            self.scratch.entries.push(Entry {
                node: k,
                guess_px: (moved[0] - c[0], moved[1] - c[1]),
                gradient: [[a[0][0] - 1.0, a[0][1]], [a[1][0], a[1][1] - 1.0]],
            });
        }
        self.correlate_entries(image, false);
        true
    }

    /// Verified nodes correlated again through their measured local gradient (module
    /// documentation, step 3).
    fn refine(&mut self, image: Image) {
        let n = self.settings.zoi_px;
        self.scratch.entries.clear();
        for k in 0..self.frame.results.len() {
            let result = self.frame.results[k];
            if result.status != NodeStatus::Ok {
                continue;
            }
            let Some(g) = self.result_gradient(k).map(to_mat2) else {
                continue;
            };
            if warp_worth_it(difference(g, result.warp_gradient), n) {
                self.scratch.entries.push(Entry {
                    node: k,
                    guess_px: (result.u_px, result.v_px),
                    gradient: g,
                });
            }
        }
        self.correlate_entries(image, true);
    }

    /// Correlates `entries` (each through its gradient), checks each new result with that
    /// gradient, and keeps it when it verifies and the node had no verified result (or
    /// `replace_verified`); a node that fails keeps its old result if that one was `ok`, else
    /// the new failure. Returns how many nodes verified.
    fn correlate_entries(&mut self, image: Image, replace_verified: bool) -> usize {
        let n = self.settings.zoi_px;
        let (fft, pad) = (self.fft_px, self.fft_pad_px);
        let n2 = spectrum_len(fft);
        let iterations = super::fft_iterations(&self.settings);
        let min_zncc = self.settings.min_zncc;
        let reference = Image {
            pixels: super::reference_pixels(&self.reference.pixels),
            width_px: self.width_px,
            height_px: self.height_px,
        };
        let (entries, ref_nodes) = (&self.scratch.entries, &self.reference.nodes);
        let (plain, windowed) = (&self.reference.plain_spectra, &self.reference.windowed);
        let results = SharedSlice::new(&mut self.frame.results);
        let zncc = SharedSlice::new(&mut self.frame.zncc);
        let verified = std::sync::atomic::AtomicUsize::new(0);
        self.pool.run(entries.len(), &|engine, i| {
            let entry = entries[i];
            let k = entry.node;
            let r = ref_nodes[k];
            let spectra = ReferenceSpectra {
                plain: &plain[k * n2..(k + 1) * n2],
                windowed: &windowed[k * fft * fft..(k + 1) * fft * fft],
            };
            let search = ZoiSearch {
                top_left_px: (r.top_left.0 + pad, r.top_left.1 + pad),
                guess_px: entry.guess_px,
                warp: Some(entry.gradient),
                iterations,
                predicted: false,
            };
            let mut result = engine.correlate(&spectra, image, search);
            let mut score = 0.0;
            if result.status == NodeStatus::Ok {
                score = verify::zncc(
                    reference,
                    r.top_left,
                    n,
                    image,
                    (result.u_px, result.v_px),
                    entry.gradient,
                )
                .unwrap_or(0.0);
                if score < min_zncc {
                    result.status = NodeStatus::LowZncc;
                }
            }
            // SAFETY: item i touches only node entries[i].node's slots; nodes are distinct.
            let old = unsafe { results.read(k) };
            let keep_new = if result.status == NodeStatus::Ok {
                old.status != NodeStatus::Ok || replace_verified
            } else {
                old.status != NodeStatus::Ok
            };
            if keep_new {
                unsafe {
                    results.write(k, result);
                    zncc.write(k, score);
                }
                if result.status == NodeStatus::Ok && old.status != NodeStatus::Ok {
                    verified.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                }
            }
        });
        verified.into_inner()
    }
}
