//! The rig-driven camera: every frame is rendered from the most recent rig sample
//! (`wire::RigState`), so the images show the specimen as the machine deforms it.
//!
//! Pushed, not pulled: unlike a [`crate::MotionSource`] (asked for the motion of frame k), the
//! rig state arrives on its own clock. The shell (see [`crate::stream::stream_following_rig`])
//! feeds each received sample to [`RigCamera::push`]; before each frame it asks
//! [`RigCamera::next_motion`] and renders with [`RigCamera::render`]. No IPC here.
//!
//! Image motion of a sample, about the image centre c = ((W - 1) / 2, (H - 1) / 2):
//! x = c + F (X - c) + t with F = R(θ) diag(λx, λy) (θ = `specimen_rotation_rad`, λ the
//! specimen stretches) and t = `specimen_centre_offset_mm` / mm-per-px. Rig X is the image x
//! (column), rig Y the image y (row).
//!
//! The pattern is rendered once, at start, over the reach of an envelope of admissible states
//! ([`RigEnvelope`]): stretches in [λmax^-1/2, λmax] on both axes (λmax^-1/2 is the lateral
//! contraction of an incompressible sheet in uniaxial tension to λmax), rotations up to ±θmax,
//! centre offsets up to ±dmax on each axis. A sample outside the envelope cannot be rendered
//! honestly (the pattern does not reach that far): [`RigCamera::next_motion`] says so with the
//! reason, and the shell skips and counts the frame instead of clamping.

use crate::error::ProducerError;
use crate::field_motion::{FieldMotion, Framing};
use crate::motion::{mul_mat, rotation, Affine, Motion};
use crate::simulated::{motion_reach_px, SimulatedCamera, SimulatedConfig};
use crate::source::{FrameDims, FrameInfo, FrameSource, Truth};
use crate::specimen_states::{SpecimenStates, StateError};
use wire::RigState;

/// `FrameHeader::scenario_id` of rig-driven frames (beyond the [`crate::ScenarioKind`] ids).
pub const RIG_SCENARIO_ID: u32 = 100;
/// Default image scale, mm per px (a 1024 px camera sees 15 mm of the specimen).
pub const DEFAULT_MM_PER_PX: f64 = 0.25;
/// Image scale on a strip (a specimen held by two grips), mm per px: the 100 mm strip and
/// its clamps across a 1024 px image, 20 mm = 167 px across.
pub const DEFAULT_STRIP_MM_PER_PX: f64 = 0.12;
/// Default largest stretch of the envelope, both axes.
pub const DEFAULT_MAX_STRETCH: f64 = 3.0;
/// Default largest specimen rotation of the envelope, degrees.
pub const DEFAULT_MAX_ROTATION_DEG: f64 = 2.0;
/// Default largest specimen centre offset of the envelope, mm (each axis).
pub const DEFAULT_MAX_OFFSET_MM: f64 = 0.5;
/// Largest `max_stretch` accepted (the rig's built-in tests go to 8).
pub const MAX_STRETCH_LIMIT: f64 = 8.0;
/// Largest texture the fast renderer builds (texels), see `FastRenderer::new`.
const MAX_TEXELS: f64 = (1u64 << 30) as f64;
/// Rotation samples over [-θmax, θmax] when computing the reach.
const ROTATION_SAMPLES: u32 = 9;
/// Relative tolerance of the envelope test (round-off of the rig's own arithmetic).
const ENVELOPE_TOLERANCE: f64 = 1e-9;

/// The states the camera can render: its pattern covers φ⁻¹ of every image pixel for all of them.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigEnvelope {
    /// Largest stretch along either axis (≥ 1); the smallest admitted is `max_stretch^-1/2`.
    pub max_stretch: f64,
    /// Largest |rotation| of the specimen, rad (< 45°).
    pub max_rotation_rad: f64,
    /// Largest |centre offset| along each axis, mm.
    pub max_offset_mm: f64,
}

impl Default for RigEnvelope {
    fn default() -> Self {
        RigEnvelope {
            max_stretch: DEFAULT_MAX_STRETCH,
            max_rotation_rad: DEFAULT_MAX_ROTATION_DEG.to_radians(),
            max_offset_mm: DEFAULT_MAX_OFFSET_MM,
        }
    }
}

impl RigEnvelope {
    /// Smallest stretch admitted: the lateral contraction λmax^-1/2 of uniaxial tension.
    pub fn min_stretch(&self) -> f64 {
        1.0 / self.max_stretch.sqrt()
    }

    fn validate(&self) -> Result<(), ProducerError> {
        let invalid = |name: &str, value: f64, expected: &str| ProducerError::InvalidParameter {
            name: name.to_owned(),
            value: value.to_string(),
            expected: expected.to_owned(),
        };
        if !(self.max_stretch.is_finite() && (1.0..=MAX_STRETCH_LIMIT).contains(&self.max_stretch))
        {
            return Err(invalid(
                "max-stretch",
                self.max_stretch,
                &format!("a stretch in [1, {MAX_STRETCH_LIMIT}]"),
            ));
        }
        if !(self.max_rotation_rad.is_finite()
            && (0.0..45f64.to_radians()).contains(&self.max_rotation_rad))
        {
            return Err(invalid(
                "max-rotation-deg",
                self.max_rotation_rad.to_degrees(),
                "an angle in [0, 45) degrees",
            ));
        }
        if !(self.max_offset_mm.is_finite() && self.max_offset_mm >= 0.0) {
            return Err(invalid(
                "max-offset-mm",
                self.max_offset_mm,
                "a non-negative offset in mm",
            ));
        }
        Ok(())
    }

    /// `Ok` when `k` lies inside the envelope, else the first reason it does not.
    pub fn admit(&self, k: &RigKinematics) -> Result<(), BeyondEnvelope> {
        let (lo, hi) = (
            self.min_stretch() * (1.0 - ENVELOPE_TOLERANCE),
            self.max_stretch * (1.0 + ENVELOPE_TOLERANCE),
        );
        for (name, value) in [("stretch_x", k.stretch_x), ("stretch_y", k.stretch_y)] {
            if !(value.is_finite() && (lo..=hi).contains(&value)) {
                return Err(BeyondEnvelope::Stretch {
                    name,
                    value,
                    min: self.min_stretch(),
                    max: self.max_stretch,
                });
            }
        }
        if !(k.rotation_rad.is_finite()
            && k.rotation_rad.abs() <= self.max_rotation_rad * (1.0 + ENVELOPE_TOLERANCE))
        {
            return Err(BeyondEnvelope::Rotation {
                rotation_rad: k.rotation_rad,
                max_rotation_rad: self.max_rotation_rad,
            });
        }
        for (axis, value) in ["X", "Y"].into_iter().zip(k.centre_offset_mm) {
            if !(value.is_finite()
                && value.abs() <= self.max_offset_mm * (1.0 + ENVELOPE_TOLERANCE) + 1e-12)
            {
                return Err(BeyondEnvelope::Offset {
                    axis,
                    value_mm: value,
                    max_mm: self.max_offset_mm,
                });
            }
        }
        Ok(())
    }
}

/// Why a rig state lies outside the envelope: the quantity, its bounds and the option that
/// sets them.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum BeyondEnvelope {
    #[error("{name} {value:.4} outside [{min:.4}, {max:.4}] (--max-stretch {max}, with the lateral contraction max^-1/2)")]
    Stretch {
        /// `stretch_x` or `stretch_y`.
        name: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error("rotation {:.3}° beyond ±{:.3}° (--max-rotation-deg)", .rotation_rad.to_degrees(), .max_rotation_rad.to_degrees())]
    Rotation {
        rotation_rad: f64,
        max_rotation_rad: f64,
    },
    #[error(
        "specimen solve {solve_id} not received: the camera does not film a state it does not have"
    )]
    SolveMissing { solve_id: u64 },
    #[error("specimen solve {solve_id} followed to the grips of this sample turns an element inside out")]
    SolveUnusable { solve_id: u64 },
    #[error("centre offset {axis} {value_mm:.4} mm beyond ±{max_mm} mm (--max-offset-mm)")]
    Offset {
        /// `X` or `Y`.
        axis: &'static str,
        value_mm: f64,
        max_mm: f64,
    },
}

/// How the camera follows the rig.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigFollowConfig {
    /// Image scale, mm per px (> 0).
    pub mm_per_px: f64,
    /// Image scale when a finite-element strip is mounted (two grips), mm per px (> 0).
    pub strip_mm_per_px: f64,
    /// The admissible states.
    pub envelope: RigEnvelope,
}

impl Default for RigFollowConfig {
    fn default() -> Self {
        RigFollowConfig {
            mm_per_px: DEFAULT_MM_PER_PX,
            strip_mm_per_px: DEFAULT_STRIP_MM_PER_PX,
            envelope: RigEnvelope::default(),
        }
    }
}

/// The specimen kinematics of one rig sample, as the camera uses them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigKinematics {
    /// `RigState::sample_id`.
    pub sample_id: u64,
    /// `RigState::test_index`: frames of one test form one frame sequence.
    pub test_index: u32,
    /// In-plane stretches along rig X and Y.
    pub stretch_x: f64,
    pub stretch_y: f64,
    /// Specimen rotation, rad.
    pub rotation_rad: f64,
    /// Specimen centre offset along rig X and Y, mm.
    pub centre_offset_mm: [f64; 2],
    /// The specimen's solve and grip displacements (mm) when it is a finite-element
    /// structure (`RigState::specimen_solve`): the camera films that field, and the fields
    /// above are the filmed region's mean.
    pub specimen: Option<(u64, [f64; 4])>,
}

impl RigKinematics {
    /// The reference state (no motion).
    pub fn at_rest(sample_id: u64) -> Self {
        RigKinematics {
            sample_id,
            test_index: 0,
            stretch_x: 1.0,
            stretch_y: 1.0,
            rotation_rad: 0.0,
            centre_offset_mm: [0.0, 0.0],
            specimen: None,
        }
    }
}

impl From<&RigState> for RigKinematics {
    fn from(state: &RigState) -> Self {
        RigKinematics {
            sample_id: state.sample_id,
            test_index: state.test_index,
            stretch_x: state.specimen_stretch_x,
            stretch_y: state.specimen_stretch_y,
            rotation_rad: state.specimen_rotation_rad,
            centre_offset_mm: state.specimen_centre_offset_mm,
            specimen: state.specimen_solve(),
        }
    }
}

/// The motion of one rig sample with its truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigMotion {
    /// The rig sample it comes from.
    pub sample_id: u64,
    /// The rig's test index (the frame sequence).
    pub test_index: u32,
    /// The homogeneous map rendered.
    pub motion: Motion,
    /// The same, as the frame header's ground truth.
    pub truth: Truth,
}

/// What the camera can do with the most recent rig sample.
#[derive(Clone, Debug, PartialEq)]
pub enum NextMotion {
    /// No rig sample has arrived yet.
    NoSample,
    /// The most recent sample lies outside the envelope: the frame cannot be rendered.
    Beyond {
        /// The sample.
        sample_id: u64,
        /// Why, naming the quantity, its bounds and the option that sets them.
        reason: BeyondEnvelope,
    },
    /// Render this.
    Ready(RigMotion),
}

/// Turns rig samples into image motions (pure: fed with samples, no IPC).
#[derive(Clone, Debug)]
pub struct RigFollower {
    config: RigFollowConfig,
    width: u32,
    height: u32,
    latest: Option<RigKinematics>,
    samples_seen: u64,
}

impl RigFollower {
    /// A follower for `width` x `height` frames.
    pub fn new(config: RigFollowConfig, width: u32, height: u32) -> Result<Self, ProducerError> {
        for (name, scale) in [
            ("mm-per-px", config.mm_per_px),
            ("strip-mm-per-px", config.strip_mm_per_px),
        ] {
            if !(scale.is_finite() && scale > 0.0) {
                return Err(ProducerError::InvalidParameter {
                    name: name.to_owned(),
                    value: scale.to_string(),
                    expected: "a positive image scale in mm per px".to_owned(),
                });
            }
        }
        config.envelope.validate()?;
        Ok(RigFollower {
            config,
            width,
            height,
            latest: None,
            samples_seen: 0,
        })
    }

    /// The settings.
    pub fn config(&self) -> &RigFollowConfig {
        &self.config
    }

    /// Centre of the image motion, px.
    pub fn centre_px(&self) -> [f64; 2] {
        [
            (f64::from(self.width) - 1.0) / 2.0,
            (f64::from(self.height) - 1.0) / 2.0,
        ]
    }

    /// Takes a received sample: the most recently received one is the one rendered (arrival
    /// order, so a restarted rig whose ids start again from 0 is followed too).
    pub fn push(&mut self, state: &RigState) {
        self.push_kinematics(RigKinematics::from(state));
    }

    /// Same as [`RigFollower::push`] with the kinematics already extracted.
    pub fn push_kinematics(&mut self, kinematics: RigKinematics) {
        self.latest = Some(kinematics);
        self.samples_seen += 1;
    }

    /// The most recent sample.
    pub fn latest(&self) -> Option<&RigKinematics> {
        self.latest.as_ref()
    }

    /// Samples pushed so far.
    pub fn samples_seen(&self) -> u64 {
        self.samples_seen
    }

    /// The image motion of `k` (whether or not it lies inside the envelope).
    pub fn motion_of(&self, k: &RigKinematics) -> RigMotion {
        let f = mul_mat(
            &rotation(k.rotation_rad),
            &[[k.stretch_x, 0.0], [0.0, k.stretch_y]],
        );
        let translation_px = [
            k.centre_offset_mm[0] / self.config.mm_per_px,
            k.centre_offset_mm[1] / self.config.mm_per_px,
        ];
        let centre_px = self.centre_px();
        RigMotion {
            sample_id: k.sample_id,
            test_index: k.test_index,
            motion: Motion::Affine(Affine {
                f,
                translation_px,
                centre_px,
            }),
            truth: Truth {
                f,
                translation_px,
                centre_px,
                homogeneous: k.specimen.is_none(),
                scenario_id: RIG_SCENARIO_ID,
                specimen: k.specimen,
            },
        }
    }

    /// What to render for the most recent sample.
    pub fn next_motion(&self) -> NextMotion {
        let Some(k) = self.latest else {
            return NextMotion::NoSample;
        };
        match self.config.envelope.admit(&k) {
            Ok(()) => NextMotion::Ready(self.motion_of(&k)),
            Err(reason) => NextMotion::Beyond {
                sample_id: k.sample_id,
                reason,
            },
        }
    }

    /// How far outside the image φ⁻¹ of an image pixel lands, px, at most, over the envelope.
    ///
    /// For an affine map the components of φ⁻¹(x) = c + diag(1/λx, 1/λy) R(θ)ᵀ (x - c - t) are
    /// linear in x over the image, in 1/λx, 1/λy and in t, so their extremes lie at the image
    /// corners and at the corners of the stretch and offset ranges, all visited here. Over θ
    /// they are sampled; the gap to the true extreme is bounded by |x - c - t| / λmin times
    /// (1 - cos(Δθ / 2)) and added.
    pub fn reach_px(&self) -> f64 {
        let e = &self.config.envelope;
        let stretches = [e.min_stretch(), e.max_stretch];
        let offset_px = e.max_offset_mm / self.config.mm_per_px;
        let offsets = [-offset_px, offset_px];
        let steps = if e.max_rotation_rad > 0.0 {
            ROTATION_SAMPLES
        } else {
            1
        };
        let step_rad = if steps > 1 {
            2.0 * e.max_rotation_rad / f64::from(steps - 1)
        } else {
            0.0
        };
        let mut motions = Vec::with_capacity(4 * 4 * steps as usize);
        for &sx in &stretches {
            for &sy in &stretches {
                for i in 0..steps {
                    let theta = -e.max_rotation_rad + step_rad * f64::from(i);
                    for &ox in &offsets {
                        for &oy in &offsets {
                            let k = RigKinematics {
                                sample_id: 0,
                                test_index: 0,
                                stretch_x: sx,
                                stretch_y: sy,
                                rotation_rad: theta,
                                centre_offset_mm: [
                                    ox * self.config.mm_per_px,
                                    oy * self.config.mm_per_px,
                                ],
                                specimen: None,
                            };
                            motions.push(self.motion_of(&k).motion);
                        }
                    }
                }
            }
        }
        let sampled = motion_reach_px(motions.into_iter(), self.width, self.height);
        let half_diagonal_px = 0.5 * f64::from(self.width).hypot(f64::from(self.height));
        let radius_px = (half_diagonal_px + offset_px * std::f64::consts::SQRT_2) / e.min_stretch();
        sampled + radius_px * (1.0 - (0.5 * step_rad).cos())
    }
}

/// The simulated camera driven by the rig state.
pub struct RigCamera {
    camera: SimulatedCamera,
    follower: RigFollower,
    reach_px: f64,
    next_index: u64,
    /// The finite-element specimen's solves received, and the field of the next frame.
    specimen: SpecimenStates,
    field: Option<FieldMotion>,
}

impl RigCamera {
    /// Builds the pattern over the reach of the envelope (once; this is the slow part).
    pub fn new(config: SimulatedConfig, follow: RigFollowConfig) -> Result<Self, ProducerError> {
        let follower = RigFollower::new(follow, config.width, config.height)?;
        let reach_px = follower.reach_px();
        // The fast renderer's texture covers the image plus the reach on every side.
        let side_px = f64::from(config.width.max(config.height)) + 2.0 * (reach_px + 12.0);
        let texels = (side_px * config.oversample as f64).powi(2);
        if config.renderer == crate::RendererKind::Fast && texels >= MAX_TEXELS {
            return Err(ProducerError::InvalidParameter {
                name: "max-stretch".to_owned(),
                value: follow.envelope.max_stretch.to_string(),
                expected: format!(
                    "an envelope whose pattern fits the fast renderer: {side_px:.0} px per side at \
                     {}x oversampling needs {:.1} GiB; lower --max-stretch, --max-rotation-deg, \
                     --max-offset-mm or --oversample",
                    config.oversample,
                    texels * 4.0 / f64::from(1u32 << 30)
                ),
            });
        }
        let camera = SimulatedCamera::for_reach(config, reach_px)?;
        Ok(RigCamera {
            camera,
            follower,
            reach_px,
            next_index: 0,
            specimen: SpecimenStates::new(),
            field: None,
        })
    }

    /// Frame geometry.
    pub fn dims(&self) -> FrameDims {
        self.camera.dims()
    }

    /// How far beyond the image the pattern reaches, px.
    pub fn reach_px(&self) -> f64 {
        self.reach_px
    }

    /// The follower (envelope, latest sample).
    pub fn follower(&self) -> &RigFollower {
        &self.follower
    }

    /// Takes a received rig sample.
    pub fn push(&mut self, state: &RigState) {
        self.follower.push(state);
    }

    /// Same as [`RigCamera::push`] with the kinematics already extracted.
    pub fn push_kinematics(&mut self, kinematics: RigKinematics) {
        self.follower.push_kinematics(kinematics);
    }

    /// Takes a received `specimen` sample.
    pub fn push_specimen(
        &mut self,
        header: &wire::SpecimenHeader,
        payload: &[f64],
    ) -> Result<(), StateError> {
        self.specimen.push(header, payload)
    }

    /// The specimen's solves received.
    pub fn specimen_states(&self) -> &SpecimenStates {
        &self.specimen
    }

    /// How the camera frames the specimen mounted: its centre at the image centre, the
    /// follower's scale for its shape.
    pub fn framing(&self) -> Framing {
        let c = self.follower.config();
        Framing {
            mm_per_px: c.mm_per_px,
            strip_mm_per_px: c.strip_mm_per_px,
        }
    }

    /// What the next frame would show; for a finite-element specimen, its field is prepared
    /// here (a solve not received, or one whose field cannot be filmed, skips the frame).
    pub fn next_motion(&mut self) -> NextMotion {
        self.field = None;
        let next = self.follower.next_motion();
        let NextMotion::Ready(motion) = &next else {
            return next;
        };
        let Some((solve_id, grip_mm)) = motion.truth.specimen else {
            return next;
        };
        let dims = self.camera.dims();
        let size_px = [dims.width, dims.height];
        let framed = self
            .specimen
            .framed_field(solve_id, &grip_mm, &self.framing(), size_px);
        let reason = match framed {
            Ok(field) => {
                self.field = Some(field);
                return next;
            }
            Err(StateError::Unknown(_)) => BeyondEnvelope::SolveMissing { solve_id },
            Err(_) => BeyondEnvelope::SolveUnusable { solve_id },
        };
        NextMotion::Beyond {
            sample_id: motion.sample_id,
            reason,
        }
    }

    /// Renders `motion` (from [`RigCamera::next_motion`]) as the next frame into `out`.
    pub fn render(
        &mut self,
        motion: &RigMotion,
        out: &mut [u16],
    ) -> Result<FrameInfo, ProducerError> {
        let index = self.next_index;
        match (&self.field, motion.truth.specimen) {
            (Some(field), Some(_)) => self.camera.render_field_frame(field, index, out)?,
            (None, Some((solve_id, _))) => {
                return Err(ProducerError::InvalidParameter {
                    name: "specimen solve".to_owned(),
                    value: solve_id.to_string(),
                    expected: "a frame prepared by next_motion".to_owned(),
                })
            }
            _ => self.camera.render_frame(&motion.motion, index, out)?,
        }
        self.next_index += 1;
        Ok(FrameInfo {
            index,
            truth: Some(motion.truth),
            rig_sample_id: Some(motion.sample_id),
            sequence_id: motion.test_index,
        })
    }

    /// Noiseless pattern values of `motion` (for tests and tools).
    pub fn render_pattern(&mut self, motion: &RigMotion) -> &[f32] {
        self.camera.render_pattern(&motion.motion)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A follower at 0.015 mm/px (an offset of 0.15 mm is 10 px).
    fn follower(width: u32, height: u32) -> RigFollower {
        let config = RigFollowConfig {
            mm_per_px: 0.015,
            ..RigFollowConfig::default()
        };
        RigFollower::new(config, width, height).unwrap()
    }

    fn kin(sx: f64, sy: f64, rot_deg: f64, offset_mm: [f64; 2]) -> RigKinematics {
        RigKinematics {
            sample_id: 7,
            test_index: 0,
            stretch_x: sx,
            stretch_y: sy,
            rotation_rad: rot_deg.to_radians(),
            centre_offset_mm: offset_mm,
            specimen: None,
        }
    }

    #[test]
    fn no_sample_until_one_is_pushed_then_the_latest_wins() {
        let mut f = follower(64, 48);
        assert_eq!(f.next_motion(), NextMotion::NoSample);
        let mut state = RigState {
            sample_id: 5,
            specimen_stretch_x: 1.2,
            specimen_stretch_y: 1.0 / 1.2f64.sqrt(),
            ..RigState::default()
        };
        f.push(&state);
        state.sample_id = 3; // a restarted rig: arrival order, not id order
        state.specimen_stretch_x = 1.1;
        f.push(&state);
        assert_eq!(f.samples_seen(), 2);
        match f.next_motion() {
            NextMotion::Ready(m) => {
                assert_eq!(m.sample_id, 3);
                assert_eq!(m.truth.f[0][0], 1.1);
            }
            other => panic!("expected a motion, got {other:?}"),
        }
    }

    #[test]
    fn motion_is_rotation_times_stretch_about_the_centre_plus_offset() {
        let f = follower(101, 81);
        let k = kin(1.3, 0.9, 1.5, [0.15, -0.03]);
        let m = f.motion_of(&k);
        let (s, c) = 1.5f64.to_radians().sin_cos();
        let expected = [[c * 1.3, -s * 0.9], [s * 1.3, c * 0.9]];
        for (row, expected_row) in m.truth.f.iter().zip(expected) {
            for (value, want) in row.iter().zip(expected_row) {
                assert!((value - want).abs() < 1e-15);
            }
        }
        assert!((m.truth.translation_px[0] - 10.0).abs() < 1e-12);
        assert!((m.truth.translation_px[1] + 2.0).abs() < 1e-12);
        assert_eq!(m.truth.centre_px, [50.0, 40.0]);
        assert!(m.truth.homogeneous);
        assert_eq!(m.truth.scenario_id, RIG_SCENARIO_ID);
        // The header truth gives back the rendered displacement everywhere.
        let header_truth = wire::GroundTruth {
            deformation_gradient: [
                m.truth.f[0][0],
                m.truth.f[0][1],
                m.truth.f[1][0],
                m.truth.f[1][1],
            ],
            translation_px: m.truth.translation_px,
            centre_px: m.truth.centre_px,
            ..wire::GroundTruth::IDENTITY
        };
        for p in [[0.0, 0.0], [100.0, 80.0], [13.5, 61.25]] {
            let u = m.motion.displacement(p);
            let (hu, hv) = header_truth.displacement_px(p[0], p[1]);
            assert!((u[0] - hu).abs() < 1e-10 && (u[1] - hv).abs() < 1e-10);
        }
    }

    #[test]
    fn envelope_admits_uniaxial_up_to_max_stretch_and_refuses_beyond_with_the_reason() {
        let mut f = follower(64, 64);
        let l = DEFAULT_MAX_STRETCH;
        for (sx, sy) in [(l, 1.0 / l.sqrt()), (1.0 / l.sqrt(), l), (l, l), (1.0, 1.0)] {
            f.push_kinematics(kin(sx, sy, 0.0, [0.0, 0.0]));
            assert!(matches!(f.next_motion(), NextMotion::Ready(_)), "{sx} {sy}");
        }
        f.push_kinematics(kin(3.2, 0.55, 0.0, [0.0, 0.0]));
        match f.next_motion() {
            NextMotion::Beyond { sample_id, reason } => {
                assert_eq!(sample_id, 7);
                let reason = reason.to_string();
                assert!(reason.contains("stretch_x 3.2000"), "{reason}");
                assert!(reason.contains("--max-stretch 3"), "{reason}");
            }
            other => panic!("expected a refusal, got {other:?}"),
        }
        f.push_kinematics(kin(1.0, 1.0, 5.0, [0.0, 0.0]));
        let NextMotion::Beyond { reason, .. } = f.next_motion() else {
            panic!("5° is beyond the default 2°");
        };
        assert!(
            reason.to_string().contains("--max-rotation-deg"),
            "{reason}"
        );
        f.push_kinematics(kin(1.0, 1.0, 0.0, [0.0, -0.6]));
        let NextMotion::Beyond { reason, .. } = f.next_motion() else {
            panic!("0.6 mm is beyond the default 0.5 mm");
        };
        assert!(
            matches!(reason, BeyondEnvelope::Offset { axis: "Y", .. }),
            "{reason}"
        );
        f.push_kinematics(kin(f64::NAN, 1.0, 0.0, [0.0, 0.0]));
        assert!(matches!(f.next_motion(), NextMotion::Beyond { .. }));
    }

    /// The invariant the envelope exists for: φ⁻¹ of every image pixel stays within the reach
    /// the pattern was built for, for any admitted state (random ones, and the corners).
    #[test]
    fn reach_covers_every_admitted_state() {
        for (w, h) in [(256, 256), (320, 200)] {
            let f = follower(w, h);
            let reach = f.reach_px();
            let e = f.config().envelope;
            assert!(reach > 0.0 && reach.is_finite());
            let mut seed = 0x1234_5678_9abc_def0u64;
            let mut unit = || {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                (seed >> 11) as f64 / (1u64 << 53) as f64
            };
            let span = |u: f64, lo: f64, hi: f64| lo + u * (hi - lo);
            for k in 0..400 {
                let corner = k < 64;
                let pick = |u: f64, lo: f64, hi: f64| {
                    if corner {
                        if u < 0.5 {
                            lo
                        } else {
                            hi
                        }
                    } else {
                        span(u, lo, hi)
                    }
                };
                let state = kin(
                    pick(unit(), e.min_stretch(), e.max_stretch),
                    pick(unit(), e.min_stretch(), e.max_stretch),
                    span(
                        unit(),
                        -e.max_rotation_rad.to_degrees(),
                        e.max_rotation_rad.to_degrees(),
                    ),
                    [
                        pick(unit(), -e.max_offset_mm, e.max_offset_mm),
                        pick(unit(), -e.max_offset_mm, e.max_offset_mm),
                    ],
                );
                assert!(e.admit(&state).is_ok());
                let needed = motion_reach_px(std::iter::once(f.motion_of(&state).motion), w, h);
                assert!(needed <= reach + 1e-9, "{state:?}: {needed} > {reach}");
            }
        }
    }

    #[test]
    fn bad_settings_are_refused() {
        let bad =
            |config: RigFollowConfig| RigFollower::new(config, 64, 64).unwrap_err().to_string();
        let c = RigFollowConfig {
            mm_per_px: 0.0,
            ..RigFollowConfig::default()
        };
        assert!(bad(c).contains("mm-per-px"));
        let mut c = RigFollowConfig::default();
        c.envelope.max_stretch = 0.5;
        assert!(bad(c).contains("max-stretch"));
        let mut c = RigFollowConfig::default();
        c.envelope.max_rotation_rad = 1.0;
        assert!(bad(c).contains("max-rotation-deg"));
    }

    #[test]
    fn camera_renders_the_latest_sample_with_its_id_and_truth() {
        let mut config = SimulatedConfig::new(64, 48);
        config.threads = 1;
        let mut camera = RigCamera::new(config, RigFollowConfig::default()).unwrap();
        let mut out = vec![0u16; camera.dims().len_px()];
        assert_eq!(camera.next_motion(), NextMotion::NoSample);
        camera.push_kinematics(RigKinematics::at_rest(0));
        let NextMotion::Ready(rest) = camera.next_motion() else {
            panic!("rest is admitted");
        };
        let info = camera.render(&rest, &mut out).unwrap();
        assert_eq!((info.index, info.rig_sample_id), (0, Some(0)));
        let at_rest = out.clone();
        camera.push_kinematics(kin(1.05, 1.0 / 1.05f64.sqrt(), 0.0, [0.0, 0.0]));
        let NextMotion::Ready(stretched) = camera.next_motion() else {
            panic!("1.05 is admitted");
        };
        let info = camera.render(&stretched, &mut out).unwrap();
        assert_eq!((info.index, info.rig_sample_id), (1, Some(7)));
        assert_eq!(info.truth.unwrap().f[0][0], 1.05);
        assert_ne!(out, at_rest, "a stretched specimen looks different");
        // The pattern never runs out at the extreme admitted state: no pixel falls back to the
        // bare background over a whole border row (a speckle is everywhere within a few px).
        let l = DEFAULT_MAX_STRETCH;
        camera.push_kinematics(kin(1.0 / l.sqrt(), 1.0 / l.sqrt(), 2.0, [0.5, -0.5]));
        let NextMotion::Ready(extreme) = camera.next_motion() else {
            panic!("the envelope corner is admitted");
        };
        let pattern = camera.render_pattern(&extreme).to_vec();
        let first_row = &pattern[..64];
        let spread = first_row.iter().cloned().fold(f32::MIN, f32::max)
            - first_row.iter().cloned().fold(f32::MAX, f32::min);
        assert!(spread > 0.05, "border row is flat: {spread}");
    }
}
