//! The first pass of a frame: every node's guess, then its correlation. With a previous field
//! (guess `auto` or `predict`), a node starts where its last step takes it (velocity), or, when
//! it has no previous value, where the affine fit of its neighbours' previous values puts it,
//! with a second try from its last position when the velocity guess fails; the global
//! (U0, V0) serves the nodes still without a guess (never a wrong one: no significant peak
//! leaves them `no_guess`). Guess `predict` without a previous field grows from the centre
//! node ring by ring, each node from the mean of its converged inner neighbours. What
//! happens after this pass (final check, growth, keypoints, refinement) is `growth.rs`.

use super::parts::{PreviousFrames, Reference, Scratch};
use super::{median_ok_score, AffineFit, Correlator, EXTRAPOLATION_RINGS};
use crate::field::NodeStatus;
use crate::global::GlobalMiss;
use crate::interpolate::Mat2;
use crate::mesh::Mesh;
use crate::pool::{Pool, SharedSlice};
use crate::settings::GuessMode;
use crate::zoi::{
    spectrum_len, Image, ReferenceSpectra, SubpixelIterations, ZoiEngine, ZoiResult, ZoiSearch,
};

impl Correlator {
    pub(super) fn run_zois(&mut self, image: Image) {
        let use_previous =
            self.settings.guess != GuessMode::Correli && self.history.previous.is_some();
        self.predict_guesses(use_previous);
        // The global correlation (two FFTs of up to 512², and one more of the reference after
        // each reference update) runs only when some node has no prediction: on a followed
        // mesh the predictions usually cover every node.
        let needs_global = !use_previous || self.frame.guesses.iter().any(|g| g.0.is_nan());
        let global = if needs_global {
            self.global_displacement(image)
        } else {
            None
        };
        self.field.global_px = global;
        // Without a significant peak the nodes keep no guess (NaN: `no_guess`), never a
        // wrong one.
        if let Some((u0, v0)) = global {
            for guess in self.frame.guesses.iter_mut().filter(|g| g.0.is_nan()) {
                *guess = (u0 as f64, v0 as f64);
            }
        }
        self.frame.results.fill(ZoiResult::default());
        self.correlate_first_pass(image, use_previous);
    }

    /// Every node's guess against the current reference from the previous frames (NaN: no
    /// prediction, the node starts from the global (U0, V0)).
    fn predict_guesses(&mut self, use_previous: bool) {
        let previous = self.history.previous.as_ref().filter(|_| use_previous);
        let whole_mesh = match previous {
            Some(p) if p.last.iter().any(|p| p.is_none()) => self.affine_fit_around(None, 0),
            _ => None,
        };
        for k in 0..self.frame.guesses.len() {
            let base = self.reference.nodes[k].base_px;
            let predicted = previous.and_then(|p| self.predict(k, p, whole_mesh));
            self.frame.guesses[k] =
                predicted.map_or((f64::NAN, f64::NAN), |p| (p.0 - base.0, p.1 - base.1));
        }
    }

    /// Node k's total displacement in this frame from the previous frames.
    fn predict(
        &self,
        k: usize,
        previous: &PreviousFrames,
        whole_mesh: Option<AffineFit>,
    ) -> Option<(f64, f64)> {
        match previous.last[k] {
            // A node moving steadily (a ramp) is where its last velocity takes it: the last
            // value plus the last change, scaled by the camera frames since the last one over
            // those between the last two (frames dropped by a busy correlator would otherwise
            // leave every prediction short by the steps missed; at a reversal this overshoots
            // by a step, which the integer search takes back).
            Some(p) => Some(match previous.before_last[k] {
                Some(q) => {
                    let r = self.frame_step as f64 / previous.last_step.max(1) as f64;
                    (p.0 + r * (p.0 - q.0), p.1 + r * (p.1 - q.1))
                }
                None => p,
            }),
            // A node without a previous value (it failed or was outside the image) starts from
            // what the affine fit of its neighbours' previous values extrapolates to it: the
            // global (U0, V0) can be far from it (a stretch about the centre has U0 = 0 while
            // its border moves by pixels), and so can a plain neighbour mean at a border, and
            // either would make it correlate another area.
            None => self
                .affine_fit_around(Some(k), EXTRAPOLATION_RINGS)
                .or(whole_mesh)
                .map(|fit| self.extrapolate(k, fit)),
        }
    }

    /// The global (U0, V0) of the frame against the reference (renewed first when stale);
    /// None without a significant peak.
    fn global_displacement(&mut self, image: Image) -> Option<(i64, i64)> {
        if self.reference.global_stale {
            self.global.set_reference(Image {
                pixels: super::reference_pixels(&self.reference.pixels),
                width_px: self.width_px,
                height_px: self.height_px,
            });
            self.reference.global_stale = false;
        }
        match self.global.displacement(image) {
            Ok(peak) => Some(peak.displacement_px),
            // Nothing to match: the ZOIs will say where the texture is missing.
            Err(GlobalMiss::Flat) => Some((0, 0)),
            Err(GlobalMiss::NotSignificant) => None,
        }
    }

    /// Every node correlated from its guess; with the previous frames a second try for the
    /// nodes the velocity guess failed; guess `predict` without them grows from the centre.
    fn correlate_first_pass(&mut self, image: Image, use_previous: bool) {
        self.frame.unsearched.fill(false);
        let job = NodeJob {
            reference: &self.reference,
            // IC-GN with the previous field: the FFT ZOI is sampled through the node's last
            // gradient.
            warps: if use_previous {
                &self.history.gradients
            } else {
                &[]
            },
            results: SharedSlice::new(&mut self.frame.results),
            image,
            fft_px: self.fft_px,
            pad_px: self.fft_pad_px,
            iterations: super::fft_iterations(&self.settings),
            skip_predicted: self.settings.method.is_icgn(),
            unsearched: SharedSlice::new(&mut self.frame.unsearched),
        };
        let guesses = &self.frame.guesses;
        if self.settings.guess == GuessMode::Predict && !use_previous {
            job.grow_from_centre(&self.pool, &self.mesh, guesses);
            return;
        }
        // A node with a previous value of its own is predicted from it (within a pixel on a
        // steady field): its ZOI skips the integer search when the prediction is confirmed.
        let previous = self.history.previous.as_ref().filter(|_| use_previous);
        self.pool.run(self.mesh.len(), &|engine, k| {
            let predicted = previous.is_some_and(|p| p.last[k].is_some());
            job.correlate(engine, k, guesses[k], predicted)
        });
        if let Some(previous) = self.history.previous.as_ref().filter(|_| use_previous) {
            let min_relative_score = self.settings.min_relative_score;
            job.retry_from_last_position(
                &self.pool,
                previous,
                &mut self.scratch,
                min_relative_score,
            );
        }
    }
}

impl Correlator {
    /// IC-GN: the predicted nodes whose prediction, taken without the FFT stage, failed the
    /// final check are correlated from it with the full search (as without a prediction), and
    /// every result is checked again. Nothing to do on a field the predictions follow.
    pub(super) fn search_unconfirmed(&mut self, image: Image) {
        self.scratch.retry.clear();
        for (k, (result, &unsearched)) in self
            .frame
            .results
            .iter()
            .zip(&self.frame.unsearched)
            .enumerate()
        {
            if unsearched && result.status != NodeStatus::Ok {
                self.scratch.retry.push(k);
            }
        }
        if self.scratch.retry.is_empty() {
            return;
        }
        let use_previous = self.history.previous.is_some();
        let job = NodeJob {
            reference: &self.reference,
            warps: if use_previous {
                &self.history.gradients
            } else {
                &[]
            },
            results: SharedSlice::new(&mut self.frame.results),
            image,
            fft_px: self.fft_px,
            pad_px: self.fft_pad_px,
            iterations: super::fft_iterations(&self.settings),
            skip_predicted: false,
            unsearched: SharedSlice::new(&mut self.frame.unsearched),
        };
        let (retry, guesses) = (&self.scratch.retry, &self.frame.guesses);
        self.pool.run(retry.len(), &|engine, i| {
            let k = retry[i];
            job.correlate(engine, k, guesses[k], false)
        });
        self.verify_results(image);
    }
}

/// The first pass's correlation of one node from a guess, keeping the better of its result
/// and what the node has.
struct NodeJob<'a> {
    reference: &'a Reference,
    /// Each node's gradient to sample its FFT ZOI through (none past the end).
    warps: &'a [Option<Mat2>],
    results: SharedSlice<'a, ZoiResult>,
    image: Image<'a>,
    fft_px: usize,
    pad_px: usize,
    iterations: SubpixelIterations,
    /// IC-GN: a predicted node takes its prediction as its guess without the FFT stage
    /// (IC-GN refines it, the final check and [`Correlator::search_unconfirmed`] catch a wrong
    /// one), marked in `unsearched`.
    skip_predicted: bool,
    unsearched: SharedSlice<'a, bool>,
}

impl NodeJob<'_> {
    /// `predicted`: the guess is the node's own prediction (see [`ZoiSearch::predicted`]).
    fn correlate(&self, engine: &mut ZoiEngine, k: usize, guess: (f64, f64), predicted: bool) {
        let r = self.reference.nodes[k];
        let unsearched = predicted && self.skip_predicted && r.status == NodeStatus::Ok;
        let result = if unsearched {
            // No score of its own: 0 until IC-GN's.
            ZoiResult {
                u_px: guess.0,
                v_px: guess.1,
                status: NodeStatus::Ok,
                warp_gradient: self.warps.get(k).copied().flatten().unwrap_or_default(),
                ..ZoiResult::default()
            }
        } else if r.status != NodeStatus::Ok {
            ZoiResult {
                status: r.status,
                ..ZoiResult::default()
            }
        } else {
            let (n, n2) = (self.fft_px, spectrum_len(self.fft_px));
            let spectra = ReferenceSpectra {
                plain: &self.reference.plain_spectra[k * n2..(k + 1) * n2],
                windowed: &self.reference.windowed[k * n * n..(k + 1) * n * n],
            };
            let search = ZoiSearch {
                top_left_px: (r.top_left.0 + self.pad_px, r.top_left.1 + self.pad_px),
                guess_px: guess,
                warp: self.warps.get(k).copied().flatten(),
                iterations: self.iterations,
                predicted,
            };
            engine.correlate(&spectra, self.image, search)
        };
        // SAFETY: each node is written by exactly one item of the job, and only when the
        // new result is better than what is there (the first pass writes every node).
        let better = |old: &ZoiResult| {
            old.status != NodeStatus::Ok
                || (result.status == NodeStatus::Ok && result.score > old.score)
        };
        if unsafe { better(&self.results.read(k)) } {
            unsafe {
                self.results.write(k, result);
                self.unsearched.write(k, unsearched);
            }
        }
    }

    /// A node the velocity guess failed (at a load reversal the guess overshoots by twice the
    /// last step) gets a second try from its last position.
    fn retry_from_last_position(
        &self,
        pool: &Pool,
        previous: &PreviousFrames,
        scratch: &mut Scratch,
        min_relative_score: f64,
    ) {
        let nodes = previous.last.len();
        // SAFETY (reads below): the pool is not running.
        // Predictions taken without the FFT stage have no score and are not retried here
        // (the final check decides; see `search_unconfirmed`).
        let searched = |k: &usize| !unsafe { self.unsearched.read(*k) };
        let min_score = min_relative_score
            * median_ok_score(
                (0..nodes)
                    .filter(searched)
                    .map(|k| unsafe { self.results.read(k) }),
                &mut scratch.scores,
            );
        scratch.retry.clear();
        for k in (0..nodes).filter(searched) {
            let result = unsafe { self.results.read(k) };
            // Outside the image too: an overshooting guess can push a border ZOI out.
            let failed = result.status != NodeStatus::Ok || result.score < min_score;
            if failed && previous.last[k].is_some() && previous.before_last[k].is_some() {
                scratch.retry.push(k);
            }
        }
        let retry = &scratch.retry;
        pool.run(retry.len(), &|engine, i| {
            let k = retry[i];
            let p = previous.last[k].expect("retried nodes have a previous value");
            let base = self.reference.nodes[k].base_px;
            self.correlate(engine, k, (p.0 - base.0, p.1 - base.1), false);
        });
    }

    /// Predict without a previous field: grow from the centre node, ring by ring; each node
    /// starts from the mean of its converged neighbours of inner rings.
    fn grow_from_centre(&self, pool: &Pool, mesh: &Mesh, guesses: &[(f64, f64)]) {
        for ring in 0..mesh.rings() {
            let members = &mesh.ring_order[mesh.ring_starts[ring]..mesh.ring_starts[ring + 1]];
            pool.run(members.len(), &|engine, item| {
                let k = members[item];
                let guess = self.inner_mean(mesh, k, ring).unwrap_or(guesses[k]);
                self.correlate(engine, k, guess, false);
            });
        }
    }

    /// The mean displacement of node k's converged neighbours of rings inside `ring`.
    fn inner_mean(&self, mesh: &Mesh, k: usize, ring: usize) -> Option<(f64, f64)> {
        let (i, j) = ((k % mesh.nx) as i64, (k / mesh.nx) as i64);
        let (mut su, mut sv, mut count) = (0.0, 0.0, 0.0);
        for dj in -1..=1i64 {
            for di in -1..=1i64 {
                let (ii, jj) = (i + di, j + dj);
                if ii < 0 || jj < 0 || ii >= mesh.nx as i64 || jj >= mesh.ny as i64 {
                    continue;
                }
                let nb = jj as usize * mesh.nx + ii as usize;
                if mesh.ring_of[nb] >= ring {
                    continue;
                }
                // SAFETY: inner rings were finished by earlier jobs; this job writes only this ring.
                let result = unsafe { self.results.read(nb) };
                if result.status == NodeStatus::Ok {
                    su += result.u_px;
                    sv += result.v_px;
                    count += 1.0;
                }
            }
        }
        (count > 0.0).then(|| (su / count, sv / count))
    }
}
