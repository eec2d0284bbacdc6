//! The first pass of a frame: every node's guess, then its correlation. With a previous field
//! (guess `auto` or `predict`), a node starts where its last step takes it (velocity), or, when
//! it has no previous value, where the affine fit of its neighbours' previous values puts it,
//! with a second try from its last position when the velocity guess fails; the global
//! (U0, V0) serves the nodes still without a guess (never a wrong one: no significant peak
//! leaves them `no_guess`). Guess `predict` without a previous field grows from the centre
//! node ring by ring, each node from the mean of its converged inner neighbours. What
//! happens after this pass (final check, growth, keypoints, refinement) is `growth.rs`.

use super::{median_ok_score, Correlator, EXTRAPOLATION_RINGS};
use crate::field::NodeStatus;
use crate::global::GlobalMiss;
use crate::interpolate::Mat2;
use crate::pool::SharedSlice;
use crate::settings::GuessMode;
use crate::zoi::{spectrum_len, Image, ReferenceSpectra, ZoiResult};

impl Correlator {
    pub(super) fn run_zois(&mut self, image: Image) {
        let (n, pad) = (self.fft_px, self.fft_pad_px);
        let n2 = spectrum_len(n);
        let iterations = super::fft_iterations(&self.settings);
        let use_previous = self.settings.guess != GuessMode::Correli && self.has_previous;
        let whole_mesh = if use_previous && self.previous.iter().any(|p| p.is_none()) {
            self.affine_fit_around(None, 0)
        } else {
            None
        };
        for k in 0..self.guesses.len() {
            let base = self.ref_nodes[k].base_px;
            // A node without a previous value (it failed or was outside the image) starts from
            // what the affine fit of its neighbours' previous values extrapolates to it: the
            // global (U0, V0) can be far from it (a stretch about the centre has U0 = 0 while
            // its border moves by pixels), and so can a plain neighbour mean at a border, and
            // either would make it correlate another area.
            let previous = match (use_previous, self.previous[k]) {
                (false, _) => None,
                // A node moving steadily (a ramp) is where its last step takes it: the last
                // value plus the last change (at a reversal this overshoots by one step, which
                // the integer search takes back).
                (true, Some(p)) => Some(match self.previous2[k] {
                    Some(q) => (2.0 * p.0 - q.0, 2.0 * p.1 - q.1),
                    None => p,
                }),
                (true, None) => self
                    .affine_fit_around(Some(k), EXTRAPOLATION_RINGS)
                    .or(whole_mesh)
                    .map(|fit| self.extrapolate(k, fit)),
            };
            // NaN: no prediction, the node starts from the global (U0, V0).
            self.guesses[k] =
                previous.map_or((f64::NAN, f64::NAN), |p| (p.0 - base.0, p.1 - base.1));
        }
        // The global correlation (two FFTs of up to 512², and one more of the reference after
        // each reference update) runs only when some node has no prediction: on a followed
        // mesh the predictions usually cover every node.
        let needs_global = !use_previous || self.guesses.iter().any(|g| g.0.is_nan());
        let global = if needs_global {
            if self.global_reference_stale {
                self.global.set_reference(Image {
                    pixels: &self.reference_pixels,
                    width_px: self.width_px,
                    height_px: self.height_px,
                });
                self.global_reference_stale = false;
            }
            match self.global.displacement(image) {
                Ok(peak) => Some(peak.displacement_px),
                // Nothing to match: the ZOIs will say where the texture is missing.
                Err(GlobalMiss::Flat) => Some((0, 0)),
                Err(GlobalMiss::NotSignificant) => None,
            }
        } else {
            None
        };
        self.field.global_px = global;
        // Without a significant peak the nodes keep no guess (NaN: `no_guess`), never a
        // wrong one.
        if let Some((u0, v0)) = global {
            for guess in self.guesses.iter_mut().filter(|g| g.0.is_nan()) {
                *guess = (u0 as f64, v0 as f64);
            }
        }
        let plain = &self.plain_spectra;
        let windowed = &self.windowed_references;
        let ref_nodes = &self.ref_nodes;
        let guesses = &self.guesses;
        // IC-GN with the previous field: the FFT ZOI is sampled through the node's last
        // gradient.
        let no_warps = [None];
        let warps: &[Option<Mat2>] = if use_previous {
            &self.previous_gradient
        } else {
            &no_warps
        };
        let results = SharedSlice::new(&mut self.results);
        let correlate_node = |engine: &mut crate::zoi::ZoiEngine, k: usize, guess: (f64, f64)| {
            let r = ref_nodes[k];
            let result = if r.status != NodeStatus::Ok {
                ZoiResult {
                    status: r.status,
                    ..ZoiResult::default()
                }
            } else {
                let spectra = ReferenceSpectra {
                    plain: &plain[k * n2..(k + 1) * n2],
                    windowed: &windowed[k * n * n..(k + 1) * n * n],
                };
                engine.correlate(
                    &spectra,
                    image,
                    r.top_left.0 + pad,
                    r.top_left.1 + pad,
                    guess,
                    warps.get(k).copied().flatten(),
                    iterations,
                )
            };
            // SAFETY: each node is written by exactly one item of the job, and only when the
            // new result is better than what is there (the first pass writes every node).
            let better = |old: &ZoiResult| {
                old.status != NodeStatus::Ok
                    || (result.status == NodeStatus::Ok && result.score > old.score)
            };
            if unsafe { better(&results.read(k)) } {
                unsafe { results.write(k, result) };
            }
        };
        // SAFETY: single-threaded here; the pool is not running.
        for k in 0..self.mesh.len() {
            unsafe { results.write(k, ZoiResult::default()) };
        }
        if self.settings.guess != GuessMode::Predict || use_previous {
            self.pool.run(self.mesh.len(), &|engine, k| {
                correlate_node(engine, k, guesses[k])
            });
            if use_previous {
                // A node the velocity guess failed (at a load reversal the guess overshoots by
                // twice the last step) gets a second try from its last position.
                // SAFETY (both closures): the pool is not running.
                let min_score = self.settings.min_relative_score
                    * median_ok_score(
                        (0..self.mesh.len()).map(|k| unsafe { results.read(k) }),
                        &mut self.scores,
                    );
                let retry = &mut self.retry;
                retry.clear();
                for k in 0..self.mesh.len() {
                    // SAFETY: the pool is not running.
                    let result = unsafe { results.read(k) };
                    // Outside the image too: an overshooting guess can push a border ZOI out.
                    let failed = result.status != NodeStatus::Ok || result.score < min_score;
                    if failed && self.previous[k].is_some() && self.previous2[k].is_some() {
                        retry.push(k);
                    }
                }
                let (previous, retry) = (&self.previous, &self.retry);
                self.pool.run(retry.len(), &|engine, i| {
                    let k = retry[i];
                    let p = previous[k].expect("retried nodes have a previous value");
                    let base = ref_nodes[k].base_px;
                    correlate_node(engine, k, (p.0 - base.0, p.1 - base.1));
                });
            }
            return;
        }
        // Predict without a previous field: grow from the centre node, ring by ring; each node
        // starts from the mean of its converged neighbours of inner rings.
        let mesh = &self.mesh;
        for ring in 0..mesh.rings() {
            let members = &mesh.ring_order[mesh.ring_starts[ring]..mesh.ring_starts[ring + 1]];
            self.pool.run(members.len(), &|engine, item| {
                let k = members[item];
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
                        let result = unsafe { results.read(nb) };
                        if result.status == NodeStatus::Ok {
                            su += result.u_px;
                            sv += result.v_px;
                            count += 1.0;
                        }
                    }
                }
                let guess = if count > 0.0 {
                    (su / count, sv / count)
                } else {
                    guesses[k]
                };
                correlate_node(engine, k, guess);
            });
        }
    }
}
