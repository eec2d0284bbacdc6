//! `dicstream bench correlate`: the correlator's speed on rendered speckle (or two image
//! files). `CorrelateBench` holds the images and the options; its methods measure the thread
//! counts, the one-thread time split, the CORRELI-GD baseline of an IC-GN run and the keypoint
//! guess; `correlate_report.rs` prints what they measured.

use super::correlate_report::{print_run, Measured};
use super::CorrelateBenchArgs;
use anyhow::{bail, Context, Result};
use correlator::settings::Method;
use correlator::{Correlator, CorrelatorSettings, TimeSplit};
use producer::motion::Affine;
use producer::{CameraModel, FastRenderer, Motion, Speckle, SpeckleParams};
use std::time::Instant;

/// The imposed sub-pixel translation (px): every ZOI does its sub-pixel iterations.
pub(super) const SHIFT_PX: [f64; 2] = [0.37, -0.21];
/// The baseline an IC-GN run is compared with: CORRELI-GD at this ZOI, same images, same run.
pub(super) const BASELINE_ZOI_PX: usize = 32;
/// Profiled frames of the time split.
const PROFILED_FRAMES: usize = 3;

/// One thread count's timings and the last field's figures.
pub(super) struct ThreadRun {
    pub threads: usize,
    pub median_s: f64,
    pub min_s: f64,
    pub max_s: f64,
    pub nodes: usize,
    pub valid: usize,
    pub mean_iterations: f64,
    /// Method `icgn`: the last field's nodes re-run at second order, and those it kept.
    pub second_order_runs: usize,
    pub second_order_nodes: usize,
    pub error_px: [f64; 2],
    /// `set_reference` on a fresh correlator (its buffers touched for the first time), and again
    /// after the timed frames (a reference update of a running correlator).
    pub set_reference_ms: f64,
    pub set_reference_again_ms: f64,
    /// The first frame after that update (no previous field against the new reference).
    pub first_frame_ms: f64,
}

/// What the keypoint guess costs on the benchmark pair.
pub(super) struct KeypointTiming {
    pub reference_ms: f64,
    pub per_frame_ms: f64,
    pub inliers: Option<usize>,
}

/// The benchmark images: a reference and the deformed images of one size, correlated in turn.
/// Rendered speckle has two deformed images, the same motion under two noise draws, so that
/// no frame repeats the last one: the previous field then predicts the next one as it does on
/// a live camera (to within the noise), not exactly.
struct Images {
    reference: Vec<u16>,
    deformed: Vec<Vec<u16>>,
    width_px: usize,
    height_px: usize,
    /// What they are, for the header line.
    source: String,
}

/// The benchmark: its options and its images.
pub(super) struct CorrelateBench {
    pub args: CorrelateBenchArgs,
    images: Images,
    /// Rendered speckle (with its known shift) rather than image files.
    pub rendered: bool,
    /// Time to render or read the images (s).
    render_s: f64,
}

impl CorrelateBench {
    /// Checks the options and renders (or reads) the images.
    pub fn new(args: CorrelateBenchArgs) -> Result<Self> {
        if args.frames == 0 {
            bail!("--frames must be at least 1");
        }
        if args.threads.is_empty() || args.threads.contains(&0) {
            bail!("--threads: expected positive thread counts, e.g. 1,2");
        }
        let t = Instant::now();
        let images = match &args.images {
            Some(files) => read_images(files)?,
            None => render_images(args.width, args.height),
        };
        Ok(Self {
            rendered: args.images.is_none(),
            args,
            images,
            render_s: t.elapsed().as_secs_f64(),
        })
    }

    /// Runs every measurement and prints the figures.
    pub fn run(&self) -> Result<()> {
        let probe = Correlator::new(self.settings(1), self.width_px(), self.height_px())
            .context("benchmark settings")?;
        let zois = field_len(&probe);
        drop(probe);
        if !self.args.json {
            self.print_header(zois);
        }
        let (runs, split) = self.thread_runs()?;
        let baseline = self.baseline(&runs)?;
        let measured = Measured {
            keypoints: self.keypoint_timing(),
            fft: correlator::timing::time_ffts(self.settings(1).fft_zoi_px(), 2000, 7),
            runs,
            split,
            baseline,
        };
        if self.args.json {
            self.print_json(&measured)
        } else {
            self.print_text(&measured);
            Ok(())
        }
    }

    /// The deformed image of frame `frame` (the images in turn).
    fn deformed(&self, frame: usize) -> &[u16] {
        &self.images.deformed[frame % self.images.deformed.len()]
    }

    pub fn width_px(&self) -> usize {
        self.images.width_px
    }

    pub fn height_px(&self) -> usize {
        self.images.height_px
    }

    /// The settings of the benchmarked method on `threads` threads.
    fn settings(&self, threads: usize) -> CorrelatorSettings {
        self.settings_with(self.args.method, self.args.zoi, threads)
    }

    /// The options' settings with another method and ZOI. Image files are correlated over
    /// the whole image, rendered speckle over the paper's centred 2^p square (the whole image
    /// when it is a power of two: the figures of the README).
    fn settings_with(&self, method: Method, zoi_px: usize, threads: usize) -> CorrelatorSettings {
        let region = if self.rendered {
            correlator::Region::centred_pow2()
        } else {
            correlator::Region::rect(correlator::Roi {
                x_px: 0,
                y_px: 0,
                width_px: self.width_px(),
                height_px: self.height_px(),
            })
        };
        CorrelatorSettings {
            method,
            zoi_px,
            step_px: self.args.step,
            region,
            threads,
            guess: self.args.guess,
            ..CorrelatorSettings::default()
        }
    }

    fn print_header(&self, zois: usize) {
        let args = &self.args;
        println!(
            "correlate: {w}x{h} px {source}, {} ZOI {} px, step {} px: {zois} ZOIs, {} guess, median of {} frames (images ready in {render_s:.1} s)",
            args.method.name(),
            args.zoi,
            args.step,
            format!("{:?}", args.guess).to_lowercase(),
            args.frames,
            w = self.width_px(),
            h = self.height_px(),
            source = self.images.source,
            render_s = self.render_s,
        );
    }

    /// Every thread count's run (printed as it ends, in text), and the one-thread time split
    /// with the ZOIs it profiled.
    fn thread_runs(&self) -> Result<(Vec<ThreadRun>, (TimeSplit, usize))> {
        let mut runs = Vec::new();
        let mut split = None;
        for &threads in &self.args.threads {
            let (run, mut correlator) = self.measure(self.settings(threads))?;
            if !self.args.json {
                print_run(&run);
            }
            runs.push(run);
            // The time split on one thread: profiling reads the clock in the hot loop, so
            // these frames are not part of the timings above.
            if split.is_none() && threads == 1 {
                split = Some(self.profile(&mut correlator)?);
                correlator.set_profiling(false);
            }
        }
        let split = match split {
            Some(split) => split,
            None => {
                let mut correlator = self.warmed_up(self.settings(1))?.0;
                self.profile(&mut correlator)?
            }
        };
        Ok((runs, split))
    }

    /// A correlator with the reference set and one frame correlated, and the time
    /// `set_reference` took (ms).
    fn warmed_up(&self, settings: CorrelatorSettings) -> Result<(Correlator, f64)> {
        let mut correlator = Correlator::new(settings, self.width_px(), self.height_px())?;
        let t = Instant::now();
        correlator.set_reference(&self.images.reference)?;
        let set_reference_ms = t.elapsed().as_secs_f64() * 1e3;
        correlator.correlate(self.deformed(0))?; // warm-up (the predictor then uses this field)
        Ok((correlator, set_reference_ms))
    }

    /// The time split of a few profiled frames and the ZOIs they correlated.
    fn profile(&self, correlator: &mut Correlator) -> Result<(TimeSplit, usize)> {
        correlator.set_profiling(true);
        for frame in 0..PROFILED_FRAMES {
            correlator.correlate(self.deformed(frame + 1))?;
        }
        Ok((
            correlator.time_split(),
            PROFILED_FRAMES * field_len(correlator),
        ))
    }

    /// One run: the median time of the options' frames after a warm-up frame.
    fn measure(&self, settings: CorrelatorSettings) -> Result<(ThreadRun, Correlator)> {
        let threads = settings.threads;
        let (mut correlator, set_reference_ms) = self.warmed_up(settings)?;
        let mut seconds: Vec<f64> = (0..self.args.frames)
            .map(|frame| {
                let t = Instant::now();
                correlator
                    .correlate(self.deformed(frame + 1))
                    .map(|_| t.elapsed().as_secs_f64())
            })
            .collect::<Result<_, _>>()?;
        let mut run = ThreadRun {
            threads,
            median_s: median(&mut seconds),
            min_s: seconds[0],
            max_s: seconds[seconds.len() - 1],
            set_reference_ms,
            ..self.field_figures(correlator.field())
        };
        let t = Instant::now();
        correlator.set_reference(&self.images.reference)?;
        run.set_reference_again_ms = t.elapsed().as_secs_f64() * 1e3;
        // Two frames: a previous field, and its step, for what follows. The first one also
        // prepares what the reference left to first need (IC-GN's subsets).
        let t = Instant::now();
        correlator.correlate(self.deformed(0))?;
        run.first_frame_ms = t.elapsed().as_secs_f64() * 1e3;
        correlator.correlate(self.deformed(1))?;
        Ok((run, correlator))
    }

    /// The last field's counts, mean iterations and (rendered speckle) mean error; the
    /// timings zero.
    fn field_figures(&self, field: &correlator::Field) -> ThreadRun {
        let ok: Vec<_> = field
            .nodes
            .iter()
            .filter(|n| n.status == correlator::NodeStatus::Ok)
            .collect();
        let count = ok.len().max(1) as f64;
        ThreadRun {
            threads: 0,
            median_s: 0.0,
            min_s: 0.0,
            max_s: 0.0,
            nodes: field.nodes.len(),
            valid: field.valid,
            mean_iterations: field.nodes.iter().map(|n| n.iterations as f64).sum::<f64>()
                / field.nodes.len() as f64,
            second_order_runs: field.second_order_runs,
            second_order_nodes: field.second_order_nodes(),
            error_px: if self.rendered {
                [
                    ok.iter().map(|n| n.u_px).sum::<f64>() / count - SHIFT_PX[0],
                    ok.iter().map(|n| n.v_px).sum::<f64>() / count - SHIFT_PX[1],
                ]
            } else {
                [f64::NAN; 2]
            },
            set_reference_ms: 0.0,
            set_reference_again_ms: 0.0,
            first_frame_ms: 0.0,
        }
    }

    /// IC-GN against CORRELI-GD at 32 px on the same images in this run: each thread count's
    /// run and time per ZOI ratio (none for `correli`).
    fn baseline(&self, runs: &[ThreadRun]) -> Result<Vec<(ThreadRun, f64)>> {
        let mut baseline = Vec::new();
        if !self.args.method.is_icgn() {
            return Ok(baseline);
        }
        for &threads in &self.args.threads {
            let settings = self.settings_with(Method::Correli, BASELINE_ZOI_PX, threads);
            let (run, _) = self.measure(settings)?;
            let ours = runs
                .iter()
                .find(|r| r.threads == threads)
                .expect("same threads");
            let ratio = (ours.median_s / ours.nodes as f64) / (run.median_s / run.nodes as f64);
            if !self.args.json {
                self.print_baseline(&run, threads, ratio);
            }
            baseline.push((run, ratio));
        }
        Ok(baseline)
    }

    fn print_baseline(&self, run: &ThreadRun, threads: usize, ratio: f64) {
        print!("  baseline correli ZOI {BASELINE_ZOI_PX}: ");
        print_run(run);
        println!(
            "  {} ZOI {} / correli ZOI {BASELINE_ZOI_PX}, {threads} thread(s): {ratio:.2}x the time per ZOI (icgn1's target: <= 1.5x)",
            self.args.method.name(),
            self.args.zoi
        );
    }

    /// Medians over the options' frames of the keypoint guess on 2 threads: the reference's
    /// keypoints (once per reference) and a frame's (detect, match, RANSAC).
    fn keypoint_timing(&self) -> KeypointTiming {
        use correlator::keypoints::KeypointMatcher;
        let (w, h) = (self.width_px(), self.height_px());
        let image = |pixels| correlator::Image {
            pixels,
            width_px: w,
            height_px: h,
        };
        let mut matcher = KeypointMatcher::new(w, h, 2);
        let mut reference_s = Vec::new();
        let mut frame_s = Vec::new();
        let mut inliers = None;
        for _ in 0..self.args.frames {
            let t = Instant::now();
            let reference_set = matcher.detect(image(&self.images.reference), (0, 0, w, h));
            reference_s.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let deformed_set = matcher.detect(image(self.deformed(0)), (0, 0, w, h));
            let guess = matcher.estimate(&reference_set, &deformed_set);
            frame_s.push(t.elapsed().as_secs_f64());
            inliers = guess.map(|g| g.inliers.len());
        }
        KeypointTiming {
            reference_ms: median(&mut reference_s) * 1e3,
            per_frame_ms: median(&mut frame_s) * 1e3,
            inliers,
        }
    }
}

/// The two image files `--images REF,DEF`.
fn read_images(files: &[std::path::PathBuf]) -> Result<Images> {
    if files.len() != 2 {
        bail!(
            "--images: expected two files, REF,DEF (got {})",
            files.len()
        );
    }
    let reference = crate::cmd::correlate::load(&files[0])?;
    let deformed = crate::cmd::correlate::load(&files[1])?;
    if (reference.width, reference.height) != (deformed.width, deformed.height) {
        bail!("--images: the two images differ in size");
    }
    Ok(Images {
        width_px: reference.width as usize,
        height_px: reference.height as usize,
        source: format!("{} against {}", files[1].display(), files[0].display()),
        reference: reference.pixels,
        deformed: vec![deformed.pixels],
    })
}

/// Rendered speckle, and the same shifted by [`SHIFT_PX`].
fn render_images(width_px: usize, height_px: usize) -> Images {
    let (w, h) = (width_px, height_px);
    let (ex, ey) = ([-16.0, w as f64 + 16.0], [-16.0, h as f64 + 16.0]);
    let speckle = Speckle::new(SpeckleParams::default(), ex, ey);
    let renderer = FastRenderer::new(&speckle, ex, ey, 4, 2);
    let moved = Motion::Affine(Affine {
        translation_px: SHIFT_PX,
        ..Affine::IDENTITY
    });
    Images {
        reference: render(&renderer, Motion::IDENTITY, w, h, 1),
        deformed: vec![
            render(&renderer, moved, w, h, 2),
            render(&renderer, moved, w, h, 3),
        ],
        width_px,
        height_px,
        source: format!(
            "speckle (producer, 1 % noise, shift {:+.2} {:+.2} px, two noise draws in turn)",
            SHIFT_PX[0], SHIFT_PX[1]
        ),
    }
}

fn render(
    renderer: &FastRenderer,
    motion: Motion,
    width: usize,
    height: usize,
    seed: u64,
) -> Vec<u16> {
    let mut pattern = vec![0f32; width * height];
    renderer.render(&motion, width, &mut pattern);
    CameraModel::read_noise_only_16bit(0.01, seed).exposed(seed, &pattern, width, 2)
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn field_len(correlator: &Correlator) -> usize {
    let (nx, ny) = correlator.mesh_size();
    nx * ny
}
