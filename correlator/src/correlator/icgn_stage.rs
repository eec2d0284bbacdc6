//! The IC-GN stage of the correlator (methods `icgn1`, `icgn2`): the frame's B-spline
//! coefficients (once per frame, on the pool), the reference subsets (each on its node's first
//! IC-GN against a reference, on the pool: a new reference costs no subset until then), and
//! the refinement of every node whose guess verified: IC-GN from the guess's displacement and
//! gradient (the node's gradient in the previous frame on a followed mesh, else the
//! least-squares gradient of its neighbours' guesses), then the final check against
//! `min_zncc`, on IC-GN's own ZNCC of the subset (see `refine_icgn`). What IC-GN finds
//! replaces the guess: its displacement, its gradient (the node's `warp_gradient`), its
//! iterations, and its status (`outside_image` when a sample leaves the image,
//! `not_converged` at the iteration cap, `low_zncc` when the final check fails).

use super::parts::SubsetState;
use super::{Correlator, Entry, FrameCoefficients};
use crate::field::NodeStatus;
use crate::icgn::bspline::Coefficients;
use crate::icgn::order_choice::NoiseScale;
use crate::icgn::shape::{Order, Warp};
use crate::icgn::subset::{self, PLANES};
use crate::icgn::{self, Subset};
use crate::interpolate::Mat2;
use crate::pool::SharedSlice;
use crate::settings::{GuessMode, Method};
use crate::verify;
use crate::zoi::{Image, Timer, ZoiResult};

impl Correlator {
    fn order(&self) -> Order {
        match self.settings.method {
            Method::Icgn2 => Order::Second,
            // `icgn` starts at first order; `order_stage.rs` re-runs some nodes at second.
            Method::Icgn1 | Method::Icgn | Method::Correli => Order::First,
        }
    }

    /// The B-spline coefficients of `pixels` (the frame, or a new reference) into the frame's
    /// buffer.
    pub(super) fn prefilter(&mut self, pixels: &[u16]) {
        let start = self.profiling.then(std::time::Instant::now);
        let mut coefficients = self
            .coefficients
            .take()
            .expect("IC-GN correlators have a coefficient buffer");
        self.prefilter_into(&mut coefficients, pixels);
        self.coefficients = Some(coefficients);
        if let Some(start) = start {
            self.coefficients_ns += start.elapsed().as_nanos() as u64;
        }
    }

    /// The origin's coefficients are the reference's (right after `set_reference`).
    pub(super) fn origin_coefficients_from_reference(&mut self) {
        let origin = self.origin.as_mut().and_then(|o| o.coefficients.as_mut());
        if let (Some(origin), Some(reference)) = (origin, self.coefficients.as_ref()) {
            origin.data.copy_from_slice(&reference.data);
        }
    }

    /// The B-spline coefficients of `pixels` into `coefficients`, rows then columns spread
    /// over the pool.
    pub(super) fn prefilter_into(&self, coefficients: &mut Coefficients, pixels: &[u16]) {
        let (w, h) = (coefficients.width_px, coefficients.height_px);
        let (row_items, column_items) = (coefficients.row_items(), coefficients.column_items());
        let data = SharedSlice::new(&mut coefficients.data);
        self.pool.run(row_items, &|_, item| {
            let first = item * crate::icgn::bspline::ROWS_PER_ITEM;
            let last = (first + crate::icgn::bspline::ROWS_PER_ITEM).min(h);
            // SAFETY: item `item` writes only its rows.
            let rows = unsafe { data.slice_mut(first * w, (last - first) * w) };
            Coefficients::prefilter_rows(pixels, w, first, rows);
        });
        self.pool.run(column_items, &|_, item| {
            // SAFETY: item `item` touches only its columns; the buffer holds w x h values.
            unsafe { Coefficients::prefilter_columns(data.as_mut_ptr(), w, h, item) };
        });
    }

    /// The coefficients (which hold the reference's) kept as the reference's, and every
    /// subset left to prepare on first need (in `refine_icgn`).
    pub(super) fn keep_reference_coefficients(&mut self) {
        let frame = self.coefficients.as_ref().expect("IC-GN coefficients");
        let kept = self.reference.coefficients.as_mut();
        kept.expect("IC-GN reference coefficients")
            .data
            .copy_from_slice(&frame.data);
        self.reference.subset_states.fill(SubsetState::Unprepared);
        (self.reference.second_order_states).fill(SubsetState::Unprepared);
    }

    /// IC-GN of node k's subset in the origin frame against the frame whose coefficients the
    /// correlator holds (`coefficients`: the frame's, or the current reference's), from
    /// `guess_px` and `gradient` (`reanchor`): the subset is prepared in the engine's scratch.
    /// None without IC-GN or without the origin's coefficients.
    pub(super) fn origin_icgn(&self, coefficients: FrameCoefficients) -> Option<OriginIcgn<'_>> {
        if !self.settings.method.is_icgn() {
            return None;
        }
        let origin = self.origin.as_ref()?;
        Some(OriginIcgn {
            origin: Image {
                pixels: &origin.pixels,
                width_px: self.width_px,
                height_px: self.height_px,
            },
            origin_coefficients: origin.coefficients.as_ref()?,
            frame_coefficients: match coefficients {
                FrameCoefficients::Frame => self.coefficients.as_ref()?,
                FrameCoefficients::Reference => self.reference.coefficients.as_ref()?,
            },
            n: self.settings.zoi_px,
            order: self.order(),
            max_iterations: self.settings.max_iterations,
        })
    }

    /// IC-GN for every node whose guess verified (see the module documentation).
    pub(super) fn refine_icgn(&mut self, image: Image) {
        let use_previous = self.settings.guess != GuessMode::Correli;
        self.scratch.entries.clear();
        for k in 0..self.frame.results.len() {
            let result = self.frame.results[k];
            if result.status != NodeStatus::Ok {
                continue;
            }
            // The paper's guess ignores previous frames, and so does its gradient.
            let previous = self.history.gradients[k].filter(|_| use_previous);
            let gradient = previous.unwrap_or_else(|| self.local_gradient(k));
            self.scratch.entries.push(Entry {
                node: k,
                guess_px: (result.u_px, result.v_px),
                gradient,
            });
        }
        let n = self.settings.zoi_px;
        let half = (n as f64 - 1.0) / 2.0;
        let values = PLANES * n * n;
        let (order, max_iterations, min_zncc) = (
            self.order(),
            self.settings.max_iterations,
            self.settings.min_zncc,
        );
        let reference = Image {
            pixels: super::reference_pixels(&self.reference.pixels),
            width_px: self.width_px,
            height_px: self.height_px,
        };
        let coefficients = self.coefficients.as_ref().expect("IC-GN coefficients");
        let reference_coefficients = self.reference.coefficients.as_ref();
        let reference_coefficients = reference_coefficients.expect("IC-GN reference coefficients");
        let (entries, ref_nodes) = (&self.scratch.entries, &self.reference.nodes);
        // Nodes still `unsearched` here passed the first-pass check at their own prediction.
        let predicted = &self.frame.unsearched;
        let planes = SharedSlice::new(&mut self.reference.subset_planes);
        let stats = SharedSlice::new(&mut self.reference.subset_stats);
        let states = SharedSlice::new(&mut self.reference.subset_states);
        let results = SharedSlice::new(&mut self.frame.results);
        let zncc = SharedSlice::new(&mut self.frame.zncc);
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
            // SAFETY: item i touches only node entries[i].node's slots; nodes are distinct.
            let (planes, stats) =
                unsafe { (planes.slice_mut(k * values, values), stats.slice_mut(k, 1)) };
            let mut state = unsafe { states.read(k) };
            if state == SubsetState::Unprepared {
                let spec = subset::SubsetSpec {
                    top_left_px: top_left,
                    side_px: n,
                    order,
                };
                let ready = subset::prepare(
                    reference,
                    reference_coefficients,
                    spec,
                    planes,
                    &mut stats[0],
                );
                state = if ready {
                    SubsetState::Ready
                } else {
                    SubsetState::Flat
                };
                unsafe { states.write(k, state) };
                timer.lap(&mut engine.split.other_ns);
            }
            if state == SubsetState::Flat {
                let result = ZoiResult {
                    status: NodeStatus::LowContrast,
                    ..ZoiResult::default()
                };
                unsafe {
                    results.write(k, result);
                    zncc.write(k, 0.0);
                }
                return;
            }
            let subset = Subset {
                planes,
                stats: &stats[0],
                n,
                centre_px: (top_left.0 as f64 + half, top_left.1 as f64 + half),
            };
            let guess = Warp::affine(entry.guess_px, entry.gradient);
            // A prediction taken without the FFT stage is off by its frames' noise.
            let stop = if predicted[k] {
                icgn::Stop::WithinNoise
            } else {
                icgn::Stop::Converged
            };
            let outcome = icgn::solve(&subset, order, coefficients, guess, max_iterations, stop);
            timer.lap(&mut engine.split.iterations_ns);
            let (result, score) = check.apply(top_left, &outcome, entry.gradient);
            timer.lap(&mut engine.split.check_ns);
            // SAFETY: item i touches only node entries[i].node's slots; nodes are distinct.
            unsafe {
                results.write(k, result);
                zncc.write(k, score);
            }
        });
    }
}

/// The final check of an IC-GN result (see `refine_icgn`).
#[derive(Clone, Copy)]
pub(super) struct FinalCheck<'a> {
    pub reference: Image<'a>,
    pub n: usize,
    pub image: Image<'a>,
    pub min_zncc: f64,
}

impl FinalCheck<'_> {
    /// The result of the node whose reference subset is at `top_left` from `outcome`, and its
    /// score: an `ok` outcome is `low_zncc` when both its own ZNCC and the check through
    /// `guess_gradient` are below `min_zncc`.
    pub fn apply(
        &self,
        top_left: (usize, usize),
        outcome: &icgn::Outcome,
        guess_gradient: Mat2,
    ) -> (ZoiResult, f64) {
        let mut result = zoi_result(outcome);
        let (u, v) = (result.u_px, result.v_px);
        let mut score = 0.0;
        if result.status == NodeStatus::Ok {
            // IC-GN's own ZNCC of the whole subset (B-spline samples) predicted at the final
            // warp: that of its last evaluation plus half the last update's predicted
            // decrease of the ZNSSD; an `ok` subset stopped where that update moves no
            // subset point by more than `icgn::CONVERGED_PX` or lies within a few noise
            // deviations (`icgn::PREDICTED_STEP_NOISE`). Below `min_zncc`, the check through the
            // guess's gradient (smoother than a noisy subset's own, as the check of the
            // other results falls back to).
            score = outcome.zncc;
            if score < self.min_zncc {
                let check =
                    |g| verify::zncc(self.reference, top_left, self.n, self.image, (u, v), g);
                score = score.max(check(guess_gradient).unwrap_or(0.0));
            }
            if score < self.min_zncc {
                result.status = NodeStatus::LowZncc;
            }
        }
        (result, score)
    }
}

/// What [`Correlator::origin_icgn`] hands to the pool items of a measurement against the origin.
#[derive(Clone, Copy)]
pub(super) struct OriginIcgn<'a> {
    origin: Image<'a>,
    origin_coefficients: &'a Coefficients,
    frame_coefficients: &'a Coefficients,
    n: usize,
    order: Order,
    max_iterations: u32,
}

impl OriginIcgn<'_> {
    /// The same measurement with shape function `order`.
    pub(super) fn at_order(&self, order: Order) -> Self {
        OriginIcgn { order, ..*self }
    }

    /// Node's subset with top-left `top_left` in the origin, measured in the frame from the
    /// total displacement `guess_px` and gradient `gradient`, in `scratch` (3 n² values); with
    /// what its noise needs (method `icgn`'s order choice, `origin_order.rs`).
    pub(super) fn measure(
        &self,
        top_left: (usize, usize),
        guess_px: (f64, f64),
        gradient: crate::interpolate::Mat2,
        scratch: &mut [f32],
    ) -> (ZoiResult, NoiseScale) {
        let n = self.n;
        let mut stats = subset::SubsetStats::default();
        let spec = subset::SubsetSpec {
            top_left_px: top_left,
            side_px: n,
            order: self.order,
        };
        if !subset::prepare(
            self.origin,
            self.origin_coefficients,
            spec,
            scratch,
            &mut stats,
        ) {
            let result = ZoiResult {
                status: NodeStatus::LowContrast,
                ..ZoiResult::default()
            };
            return (result, NoiseScale::default());
        }
        let half = (n as f64 - 1.0) / 2.0;
        let subset = Subset {
            planes: scratch,
            stats: &stats,
            n,
            centre_px: (top_left.0 as f64 + half, top_left.1 as f64 + half),
        };
        let outcome = icgn::solve(
            &subset,
            self.order,
            self.frame_coefficients,
            Warp::affine(guess_px, gradient),
            self.max_iterations,
            icgn::Stop::Converged,
        );
        let noise = match self.order {
            Order::First => NoiseScale::of(outcome.zncc, &stats, n),
            Order::Second => NoiseScale::default(),
        };
        (zoi_result(&outcome), noise)
    }
}

/// IC-GN's outcome as a node result: the displacement of the subset centre, the ZNCC of the
/// last samples as the score, and the shape function's gradient as the node's gradient.
fn zoi_result(outcome: &icgn::Outcome) -> ZoiResult {
    let (u, v) = outcome.warp.displacement();
    ZoiResult {
        u_px: u,
        v_px: v,
        score: outcome.zncc,
        iterations: outcome.iterations,
        status: outcome.status,
        warp_gradient: outcome.warp.gradient(),
    }
}
