//! The simulated camera: a speckle pattern rendered under the motion a [`MotionSource`] gives
//! for each frame (a scenario timeline), exposed by the camera model straight into the caller's
//! buffer. All buffers are made at construction.
//!
//! A [`MotionSource`] is pulled by frame index. A motion pushed from outside (the rig state, see
//! [`crate::RigCamera`]) instead builds the camera for a known reach with
//! [`SimulatedCamera::for_reach`] and renders each motion with [`SimulatedCamera::render_frame`].

use crate::camera::{Blur, CameraModel};
use crate::error::ProducerError;
use crate::field_motion::{CellRows, FieldMotion};
use crate::motion::Motion;
use crate::parallel::for_row_bands;
use crate::render_exact::ExactRenderer;
use crate::render_fast::FastRenderer;
use crate::scenario::Scenario;
use crate::source::{check_buffer, FrameDims, FrameInfo, FrameSource, Truth};
use crate::speckle::{Speckle, SpeckleParams};

/// Where the motion of each frame comes from.
pub trait MotionSource: Send {
    /// The motion and its truth for frame `frame_index`, or `None` when the source is done.
    fn next_motion(&mut self, frame_index: u64) -> Option<(Motion, Truth)>;
    /// Number of frames, if finite.
    fn frames_total(&self) -> Option<u64>;
    /// An upper bound, px, of how far outside the image φ⁻¹ of any image pixel may land: the
    /// pattern is made that much larger.
    fn reach_px(&self, width: u32, height: u32) -> f64;
}

/// A scenario played over `frames` frames, ramping from identity to its final state.
#[derive(Clone, Copy, Debug)]
pub struct ScenarioTimeline {
    /// The scenario.
    pub scenario: Scenario,
    /// Number of frames N.
    pub frames: u64,
}

impl MotionSource for ScenarioTimeline {
    fn next_motion(&mut self, frame_index: u64) -> Option<(Motion, Truth)> {
        if frame_index >= self.frames {
            return None;
        }
        let motion = self.scenario.motion_at(frame_index, self.frames);
        Some((motion, self.scenario.truth_of(&motion)))
    }

    fn frames_total(&self) -> Option<u64> {
        Some(self.frames)
    }

    fn reach_px(&self, width: u32, height: u32) -> f64 {
        motion_reach_px(
            (0..=8).map(|k| self.scenario.motion_at_fraction(f64::from(k) / 8.0)),
            width,
            height,
        )
    }
}

/// How far outside [0, W-1] x [0, H-1] the inverse images of the border pixels of the given
/// motions land, px (sampled every 8 px along the border).
pub fn motion_reach_px(motions: impl Iterator<Item = Motion>, width: u32, height: u32) -> f64 {
    let (w, h) = (f64::from(width) - 1.0, f64::from(height) - 1.0);
    let mut reach: f64 = 0.0;
    for motion in motions {
        let mut visit = |x: f64, y: f64| {
            let p = motion.inverse([x, y]);
            let out_x = (-p[0]).max(p[0] - w).max(0.0);
            let out_y = (-p[1]).max(p[1] - h).max(0.0);
            reach = reach.max(out_x).max(out_y);
        };
        let mut x = 0.0;
        while x <= w + 8.0 {
            visit(x.min(w), 0.0);
            visit(x.min(w), h);
            x += 8.0;
        }
        let mut y = 0.0;
        while y <= h + 8.0 {
            visit(0.0, y.min(h));
            visit(w, y.min(h));
            y += 8.0;
        }
    }
    reach
}

/// Which renderer the simulated camera uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RendererKind {
    /// Oversampled texture + bicubic: live streaming.
    Fast,
    /// Analytic pattern + Gauss-Legendre pixel integration: ground truth, slow.
    Exact,
}

wire::named!(RendererKind, "renderer", { Fast => "fast", Exact => "exact" });

/// Settings of a simulated camera.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulatedConfig {
    /// Width, px.
    #[serde(rename = "width_px")]
    pub width: u32,
    /// Height, px.
    #[serde(rename = "height_px")]
    pub height: u32,
    /// The pattern.
    pub speckle: SpeckleParams,
    /// The camera.
    pub camera: CameraModel,
    /// The renderer.
    pub renderer: RendererKind,
    /// Texels per px of the fast renderer (even, 2..=8).
    pub oversample: usize,
    /// Gauss-Legendre points per axis of the exact renderer (1..=6).
    pub gauss_order: usize,
    /// Threads for rendering and exposure.
    pub threads: usize,
}

impl SimulatedConfig {
    /// Defaults: 8-bit camera, fast renderer at 4x oversampling, all cores.
    pub fn new(width: u32, height: u32) -> Self {
        SimulatedConfig {
            width,
            height,
            speckle: SpeckleParams::default(),
            camera: CameraModel::with_bit_depth(8),
            renderer: RendererKind::Fast,
            oversample: 4,
            gauss_order: 4,
            threads: crate::parallel::default_threads(),
        }
    }
}

enum Renderer {
    Fast(FastRenderer),
    Exact(ExactRenderer),
}

/// The simulated camera, a [`FrameSource`].
pub struct SimulatedCamera {
    config: SimulatedConfig,
    speckle: Speckle,
    renderer: Renderer,
    /// `None` for a camera driven from outside through [`SimulatedCamera::render_frame`].
    motions: Option<Box<dyn MotionSource>>,
    pattern: Vec<f32>,
    blur: Option<Blur>,
    next_index: u64,
}

/// Pattern margin beyond the reach of the motion, px.
const EXTRA_MARGIN_PX: f64 = 8.0;
/// Largest frame side, px, of every frame: simulated, replayed or read by `correlate`.
pub const MAX_SIDE_PX: u32 = 16_384;

/// Refuses a simulated frame side outside [8, [`MAX_SIDE_PX`]] px, naming it.
pub fn check_frame_size(width: u32, height: u32) -> Result<(), ProducerError> {
    for (name, side) in [("width", width), ("height", height)] {
        if !(8..=MAX_SIDE_PX).contains(&side) {
            return Err(ProducerError::InvalidParameter {
                name: name.to_owned(),
                value: side.to_string(),
                expected: format!("a frame side in [8, {MAX_SIDE_PX}] px"),
            });
        }
    }
    Ok(())
}

impl SimulatedCamera {
    /// Builds the pattern (and the fast texture) for the motions `motions` may produce.
    pub fn new(
        config: SimulatedConfig,
        motions: Box<dyn MotionSource>,
    ) -> Result<Self, ProducerError> {
        let reach_px = motions.reach_px(config.width, config.height);
        Self::build(config, reach_px, Some(motions))
    }

    /// A camera without a motion source, whose pattern covers `reach_px` beyond the image on
    /// every side: the caller renders each motion with [`SimulatedCamera::render_frame`] and
    /// must keep φ⁻¹ of every image pixel within that reach. As a [`FrameSource`] it gives no
    /// frame.
    pub fn for_reach(config: SimulatedConfig, reach_px: f64) -> Result<Self, ProducerError> {
        if !(reach_px.is_finite() && reach_px >= 0.0) {
            return Err(ProducerError::InvalidParameter {
                name: "reach_px".to_owned(),
                value: reach_px.to_string(),
                expected: "a finite, non-negative pattern reach in px".to_owned(),
            });
        }
        Self::build(config, reach_px, None)
    }

    fn build(
        config: SimulatedConfig,
        reach_px: f64,
        motions: Option<Box<dyn MotionSource>>,
    ) -> Result<Self, ProducerError> {
        check_frame_size(config.width, config.height)?;
        config.speckle.validate()?;
        config.camera.validate()?;
        if !(config.oversample.is_multiple_of(2) && (2..=8).contains(&config.oversample)) {
            return Err(ProducerError::InvalidParameter {
                name: "oversample".to_owned(),
                value: config.oversample.to_string(),
                expected: "2, 4, 6 or 8".to_owned(),
            });
        }
        if !(1..=crate::render_exact::MAX_GAUSS_ORDER).contains(&config.gauss_order) {
            return Err(ProducerError::InvalidParameter {
                name: "gauss_order".to_owned(),
                value: config.gauss_order.to_string(),
                expected: "1 to 6".to_owned(),
            });
        }
        let threads = config.threads.max(1);
        let margin_px = reach_px + EXTRA_MARGIN_PX;
        assert!(margin_px.is_finite(), "motion reach is not finite");
        let x_range = [-margin_px, f64::from(config.width) - 1.0 + margin_px];
        let y_range = [-margin_px, f64::from(config.height) - 1.0 + margin_px];
        let speckle = Speckle::new(config.speckle, x_range, y_range);
        let renderer = match config.renderer {
            RendererKind::Fast => Renderer::Fast(FastRenderer::new(
                &speckle,
                x_range,
                y_range,
                config.oversample,
                threads,
            )),
            RendererKind::Exact => Renderer::Exact(ExactRenderer {
                gauss_order: config.gauss_order,
                threads,
            }),
        };
        let len_px = config.width as usize * config.height as usize;
        let blur = (config.camera.blur_sigma_px > 0.0)
            .then(|| Blur::new(config.camera.blur_sigma_px, len_px));
        Ok(SimulatedCamera {
            config,
            speckle,
            renderer,
            motions,
            pattern: vec![0.0; len_px],
            blur,
            next_index: 0,
        })
    }

    /// The settings.
    pub fn config(&self) -> &SimulatedConfig {
        &self.config
    }

    /// The pattern.
    pub fn speckle(&self) -> &Speckle {
        &self.speckle
    }

    /// Renders the noiseless pattern values p in [0, 1] of `motion` into the internal buffer and
    /// returns it (for tests and tools).
    pub fn render_pattern(&mut self, motion: &Motion) -> &[f32] {
        self.render_shown_pattern(Shown::Motion(motion))
    }

    /// [`Self::render_pattern`] of a finite-element field.
    pub fn render_field_pattern(&mut self, field: &FieldMotion) -> &[f32] {
        self.render_shown_pattern(Shown::Field(field))
    }

    fn render_shown_pattern(&mut self, shown: Shown<'_>) -> &[f32] {
        let width = self.config.width as usize;
        match (&self.renderer, shown) {
            (Renderer::Fast(fast), Shown::Motion(m)) => fast.render(m, width, &mut self.pattern),
            (Renderer::Fast(fast), Shown::Field(f)) => {
                fast.render_field(f, width, &mut self.pattern)
            }
            (Renderer::Exact(exact), Shown::Motion(m)) => {
                exact.render(&self.speckle, m, width, &mut self.pattern)
            }
            (Renderer::Exact(exact), Shown::Field(f)) => {
                exact.render_field(&self.speckle, f, width, &mut self.pattern)
            }
        }
        if let Some(blur) = &mut self.blur {
            blur.apply(&mut self.pattern, width, self.config.threads.max(1));
        }
        &self.pattern
    }

    /// Renders `motion` as frame `frame_index` into `out` (no motion source involved).
    pub fn render_frame(
        &mut self,
        motion: &Motion,
        frame_index: u64,
        out: &mut [u16],
    ) -> Result<(), ProducerError> {
        self.render_shown_frame(Shown::Motion(motion), frame_index, out)
    }

    /// [`Self::render_frame`] of a finite-element field (the room behind the specimen shows
    /// [`crate::BACKDROP`]).
    pub fn render_field_frame(
        &mut self,
        field: &FieldMotion,
        frame_index: u64,
        out: &mut [u16],
    ) -> Result<(), ProducerError> {
        self.render_shown_frame(Shown::Field(field), frame_index, out)
    }

    fn render_shown_frame(
        &mut self,
        shown: Shown<'_>,
        frame_index: u64,
        out: &mut [u16],
    ) -> Result<(), ProducerError> {
        check_buffer(self.dims(), out)?;
        let (width, threads) = (self.config.width as usize, self.config.threads.max(1));
        let camera = &self.config.camera;
        match (&self.renderer, &self.blur) {
            // Without blur each row is rendered and exposed while it is in cache: the frame's
            // pattern never goes to memory (one row of scratch per thread).
            (Renderer::Fast(fast), None) => {
                for_row_bands(out, width, threads, |first_row, band| {
                    let mut pattern_row = vec![0f32; width];
                    let mut cells = CellRows::new(width);
                    for (r, row) in band.chunks_exact_mut(width).enumerate() {
                        match shown {
                            Shown::Motion(m) => fast.render_row(m, first_row + r, &mut pattern_row),
                            Shown::Field(f) => fast.render_field_row(
                                f,
                                &mut cells,
                                first_row + r,
                                &mut pattern_row,
                            ),
                        }
                        camera.expose_row(frame_index, first_row + r, &pattern_row, row);
                    }
                })
            }
            _ => {
                self.render_shown_pattern(shown);
                let camera = &self.config.camera;
                camera.expose(frame_index, &self.pattern, width, out, threads);
            }
        }
        Ok(())
    }
}

/// What a frame shows: a motion of the whole image, or a finite-element field.
#[derive(Clone, Copy)]
enum Shown<'a> {
    Motion(&'a Motion),
    Field(&'a FieldMotion),
}

impl FrameSource for SimulatedCamera {
    fn dims(&self) -> FrameDims {
        FrameDims {
            width: self.config.width,
            height: self.config.height,
            bit_depth: self.config.camera.bit_depth,
        }
    }

    fn frames_total(&self) -> Option<u64> {
        match &self.motions {
            Some(motions) => motions.frames_total(),
            None => Some(0),
        }
    }

    fn next_frame(&mut self, out: &mut [u16]) -> Result<Option<FrameInfo>, ProducerError> {
        check_buffer(self.dims(), out)?;
        let index = self.next_index;
        let Some((motion, truth)) = self
            .motions
            .as_mut()
            .and_then(|motions| motions.next_motion(index))
        else {
            return Ok(None);
        };
        self.render_frame(&motion, index, out)?;
        self.next_index += 1;
        Ok(Some(FrameInfo {
            index,
            truth: Some(truth),
            rig_sample_id: None,
            sequence_id: 0,
        }))
    }
}
