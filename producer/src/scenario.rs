//! Named scenarios with parameters, each giving the exact motion of frame k of N: the motion
//! ramps linearly from the identity (frame 0) to its final value (frame N - 1).
//!
//! Spec syntax: `name` or `name:key=value,key=value`, e.g. `rotation:angle_deg=5`.
//! Default centre: the image centre ((W - 1) / 2, (H - 1) / 2).

use crate::error::ProducerError;
use crate::motion::{det, mul_mat, rotation, Affine, Bulge, Chirp, Mat2, Motion, Vec2, IDENTITY};
use crate::source::Truth;

/// The scenario kinds, with their final-state parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScenarioKind {
    /// No motion (noise studies). Name `static`.
    Static,
    /// Rigid translation. Name `translation`: `tx_px` (0.35), `ty_px` (-0.2).
    Translation {
        /// px.
        translation_px: Vec2,
    },
    /// Rigid rotation about a centre. Name `rotation`: `angle_deg` (5), `cx_px`, `cy_px`.
    Rotation {
        /// Final angle, rad.
        angle_rad: f64,
    },
    /// Any homogeneous gradient. Name `gradient`: `f11` (1.01), `f12` (0.005), `f21` (-0.003),
    /// `f22` (0.99), `tx_px` (0), `ty_px` (0), `cx_px`, `cy_px`.
    Gradient {
        /// Final F.
        f: Mat2,
        /// Final translation, px.
        translation_px: Vec2,
    },
    /// Uniaxial stretch of an incompressible sheet along x: F = diag(λ, λ^-1/2).
    /// Name `uniaxial`: `lambda` (1.1).
    Uniaxial {
        /// Final stretch λ.
        lambda: f64,
    },
    /// Equibiaxial stretch F = diag(λ, λ). Name `equibiaxial`: `lambda` (1.07).
    Equibiaxial {
        /// Final stretch λ.
        lambda: f64,
    },
    /// Chirp sine along x like DIC Challenge sample 14 (see [`Chirp`]). Name `chirp`:
    /// `amplitude_px` (0.1), `start_px` (100), `periods` (6) over the rest of the width.
    Chirp {
        /// Final amplitude, px.
        amplitude_px: f64,
        /// Start, px.
        start_px: f64,
        /// Periods over [start, W - 1].
        periods: f64,
    },
    /// Smooth non-homogeneous radial stretch (see [`Bulge`]). Name `bulge`: `strain` (0.05),
    /// `width_px` (min(W, H) / 4).
    Bulge {
        /// Final strain at the centre.
        strain: f64,
        /// Width, px.
        width_px: f64,
    },
    /// Uniaxial incompressible stretch, plus a small rotation and an off-centre translation:
    /// F = R(θ) diag(λ, λ^-1/2), about a centre off the image centre. Name `bad-positioning`:
    /// `lambda` (1.1), `angle_deg` (1), `tx_px` (3.3), `ty_px` (-2.7), `centre_dx_px` (40),
    /// `centre_dy_px` (-25).
    BadPositioning {
        /// Final stretch λ.
        lambda: f64,
        /// Final angle, rad.
        angle_rad: f64,
        /// Final translation, px.
        translation_px: Vec2,
    },
}

/// Known scenario names, in [`ScenarioKind::id`] order.
pub const SCENARIO_NAMES: [&str; 9] = [
    "static",
    "translation",
    "rotation",
    "gradient",
    "uniaxial",
    "equibiaxial",
    "chirp",
    "bulge",
    "bad-positioning",
];

impl ScenarioKind {
    /// Stable numeric id (index in [`SCENARIO_NAMES`]), carried in frame headers.
    pub fn id(&self) -> u32 {
        match self {
            ScenarioKind::Static => 0,
            ScenarioKind::Translation { .. } => 1,
            ScenarioKind::Rotation { .. } => 2,
            ScenarioKind::Gradient { .. } => 3,
            ScenarioKind::Uniaxial { .. } => 4,
            ScenarioKind::Equibiaxial { .. } => 5,
            ScenarioKind::Chirp { .. } => 6,
            ScenarioKind::Bulge { .. } => 7,
            ScenarioKind::BadPositioning { .. } => 8,
        }
    }

    /// Name, as parsed.
    pub fn name(&self) -> &'static str {
        SCENARIO_NAMES[self.id() as usize]
    }
}

/// A scenario: a kind with its parameters, and the centre of its homogeneous part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scenario {
    /// Kind and final parameters.
    pub kind: ScenarioKind,
    /// Centre, px (reference coordinates).
    pub centre_px: Vec2,
    /// Image width, px (the chirp spans it).
    pub width_px: f64,
}

struct Params<'a> {
    spec: &'a str,
    pairs: Vec<(&'a str, &'a str, bool)>,
}

impl<'a> Params<'a> {
    /// The `key=value` pairs of `rest`, what follows the scenario `name` in `spec`.
    fn parse(spec: &str, name: &'a str, rest: &'a str) -> Result<Params<'a>, ProducerError> {
        let mut pairs = Vec::new();
        for item in rest.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let Some((k, v)) = item.split_once('=') else {
                return Err(ProducerError::InvalidParameter {
                    name: item.to_owned(),
                    value: String::new(),
                    expected: format!("key=value in scenario spec '{spec}'"),
                });
            };
            pairs.push((k.trim(), v.trim(), false));
        }
        Ok(Params { spec: name, pairs })
    }

    /// (`cx_px`, `cy_px`), `default` where not given.
    fn centre(&mut self, default: Vec2) -> Result<Vec2, ProducerError> {
        Ok([
            self.get("cx_px", default[0])?,
            self.get("cy_px", default[1])?,
        ])
    }

    fn get(&mut self, key: &str, default: f64) -> Result<f64, ProducerError> {
        let Some(pair) = self.pairs.iter_mut().find(|(k, _, _)| *k == key) else {
            return Ok(default);
        };
        pair.2 = true;
        let value: f64 = pair
            .1
            .parse()
            .map_err(|_| ProducerError::InvalidParameter {
                name: key.to_owned(),
                value: pair.1.to_owned(),
                expected: "a number".to_owned(),
            })?;
        if !value.is_finite() {
            return Err(ProducerError::InvalidParameter {
                name: key.to_owned(),
                value: pair.1.to_owned(),
                expected: "a finite number".to_owned(),
            });
        }
        Ok(value)
    }

    fn finish(self, known: &str) -> Result<(), ProducerError> {
        if let Some((k, v, _)) = self.pairs.iter().find(|(_, _, used)| !used) {
            return Err(ProducerError::InvalidParameter {
                name: (*k).to_owned(),
                value: (*v).to_owned(),
                expected: format!("one of the parameters of {}: {known}", self.spec),
            });
        }
        Ok(())
    }
}

fn invalid(name: &str, value: f64, expected: &str) -> ProducerError {
    ProducerError::InvalidParameter {
        name: name.to_owned(),
        value: value.to_string(),
        expected: expected.to_owned(),
    }
}

fn positive(name: &str, value: f64) -> Result<f64, ProducerError> {
    if value > 0.0 {
        Ok(value)
    } else {
        Err(invalid(name, value, "a positive number"))
    }
}

/// A scenario kind parsed from its parameters, with the list of its keys.
type Parsed = Result<(ScenarioKind, &'static str), ProducerError>;

/// `rotation`: `angle_deg` about (`cx_px`, `cy_px`), which replace `centre`.
fn parse_rotation(p: &mut Params, centre: &mut Vec2) -> Parsed {
    *centre = p.centre(*centre)?;
    let angle_deg = p.get("angle_deg", 5.0)?;
    if angle_deg.abs() >= 90.0 {
        return Err(invalid("angle_deg", angle_deg, "|angle| < 90"));
    }
    Ok((
        ScenarioKind::Rotation {
            angle_rad: angle_deg.to_radians(),
        },
        "angle_deg, cx_px, cy_px",
    ))
}

/// `gradient`: F = [[f11, f12], [f21, f22]] about (`cx_px`, `cy_px`), which replace `centre`,
/// and a translation; F's linear ramp from I must stay invertible.
fn parse_gradient(p: &mut Params, centre: &mut Vec2) -> Parsed {
    *centre = p.centre(*centre)?;
    let f = [
        [p.get("f11", 1.01)?, p.get("f12", 0.005)?],
        [p.get("f21", -0.003)?, p.get("f22", 0.99)?],
    ];
    // Every ramped F = I + s (F - I), s in [0, 1], must stay invertible.
    for step in 0..=100 {
        let s = f64::from(step) / 100.0;
        let fs = lerp_mat(s, &f);
        if det(&fs) <= 0.05 {
            return Err(invalid(
                "f11,f12,f21,f22",
                det(&f),
                "a gradient whose linear ramp from I keeps det F > 0.05",
            ));
        }
    }
    Ok((
        ScenarioKind::Gradient {
            f,
            translation_px: [p.get("tx_px", 0.0)?, p.get("ty_px", 0.0)?],
        },
        "f11, f12, f21, f22, tx_px, ty_px, cx_px, cy_px",
    ))
}

/// `chirp` over an image `width_px` wide: it must start inside and stay invertible.
fn parse_chirp(p: &mut Params, width_px: f64) -> Parsed {
    let amplitude_px = p.get("amplitude_px", 0.1)?;
    let start_px = p.get("start_px", 100.0_f64.min(width_px / 4.0))?;
    let periods = positive("periods", p.get("periods", 6.0)?)?;
    if start_px >= width_px - 1.0 {
        return Err(invalid("start_px", start_px, "a start inside the image"));
    }
    let chirp = Chirp {
        amplitude_px,
        start_px,
        length_px: width_px - 1.0 - start_px,
        periods,
    };
    // Max slope |u'| = A 4π n / L at the end: keep 1 + u' > 0 with a margin.
    let max_slope = amplitude_px.abs() * 4.0 * std::f64::consts::PI * periods / chirp.length_px;
    if max_slope >= 0.5 {
        return Err(invalid(
            "amplitude_px",
            amplitude_px,
            "amplitude * 4π * periods / length < 0.5 (an invertible chirp)",
        ));
    }
    Ok((
        ScenarioKind::Chirp {
            amplitude_px,
            start_px,
            periods,
        },
        "amplitude_px, start_px, periods",
    ))
}

/// `bulge` about (`cx_px`, `cy_px`), which replace `centre`; its default width is a quarter
/// of the image's smaller side `side_px`.
fn parse_bulge(p: &mut Params, centre: &mut Vec2, side_px: f64) -> Parsed {
    *centre = p.centre(*centre)?;
    let strain = p.get("strain", 0.05)?;
    if !(-0.5..=1.0).contains(&strain) {
        return Err(invalid("strain", strain, "a strain in [-0.5, 1]"));
    }
    Ok((
        ScenarioKind::Bulge {
            strain,
            width_px: positive("width_px", p.get("width_px", side_px / 4.0)?)?,
        },
        "strain, width_px, cx_px, cy_px",
    ))
}

/// `bad-positioning`: a stretch, a rotation and a translation about a centre moved from
/// `centre` by (`centre_dx_px`, `centre_dy_px`).
fn parse_bad_positioning(p: &mut Params, centre: &mut Vec2) -> Parsed {
    *centre = [
        centre[0] + p.get("centre_dx_px", 40.0)?,
        centre[1] + p.get("centre_dy_px", -25.0)?,
    ];
    let angle_deg = p.get("angle_deg", 1.0)?;
    if angle_deg.abs() >= 90.0 {
        return Err(invalid("angle_deg", angle_deg, "|angle| < 90"));
    }
    Ok((
        ScenarioKind::BadPositioning {
            lambda: positive("lambda", p.get("lambda", 1.1)?)?,
            angle_rad: angle_deg.to_radians(),
            translation_px: [p.get("tx_px", 3.3)?, p.get("ty_px", -2.7)?],
        },
        "lambda, angle_deg, tx_px, ty_px, centre_dx_px, centre_dy_px",
    ))
}

impl Scenario {
    /// Parses `name` or `name:key=value,...` for an image of `width` x `height` px.
    /// An unknown name is an error listing the known ones; an unknown key lists the valid keys.
    pub fn parse(spec: &str, width: u32, height: u32) -> Result<Scenario, ProducerError> {
        assert!(width > 0 && height > 0, "empty image");
        let (name, rest) = spec.split_once(':').unwrap_or((spec, ""));
        let name = name.trim();
        let mut p = Params::parse(spec, name, rest)?;
        let (w, h) = (f64::from(width), f64::from(height));
        let mut centre = [(w - 1.0) / 2.0, (h - 1.0) / 2.0];
        let (kind, known) = match name {
            "static" => (ScenarioKind::Static, ""),
            "translation" => (
                ScenarioKind::Translation {
                    translation_px: [p.get("tx_px", 0.35)?, p.get("ty_px", -0.2)?],
                },
                "tx_px, ty_px",
            ),
            "rotation" => parse_rotation(&mut p, &mut centre)?,
            "gradient" => parse_gradient(&mut p, &mut centre)?,
            "uniaxial" => (
                ScenarioKind::Uniaxial {
                    lambda: positive("lambda", p.get("lambda", 1.1)?)?,
                },
                "lambda",
            ),
            "equibiaxial" => (
                ScenarioKind::Equibiaxial {
                    lambda: positive("lambda", p.get("lambda", 1.07)?)?,
                },
                "lambda",
            ),
            "chirp" => parse_chirp(&mut p, w)?,
            "bulge" => parse_bulge(&mut p, &mut centre, w.min(h))?,
            "bad-positioning" => parse_bad_positioning(&mut p, &mut centre)?,
            _ => {
                return Err(ProducerError::UnknownScenario {
                    name: name.to_owned(),
                    known: SCENARIO_NAMES.join(", "),
                })
            }
        };
        p.finish(if known.is_empty() { "(none)" } else { known })?;
        Ok(Scenario {
            kind,
            centre_px: centre,
            width_px: w,
        })
    }

    /// The motion at ramp fraction `s` in [0, 1] (0: identity, 1: final state).
    pub fn motion_at_fraction(&self, s: f64) -> Motion {
        assert!((0.0..=1.0).contains(&s), "ramp fraction {s} outside [0, 1]");
        let affine = |f: Mat2, t: Vec2| {
            Motion::Affine(Affine {
                f,
                translation_px: t,
                centre_px: self.centre_px,
            })
        };
        let ramp = |final_value: f64, start: f64| start + s * (final_value - start);
        match self.kind {
            ScenarioKind::Static => affine(IDENTITY, [0.0, 0.0]),
            ScenarioKind::Translation { translation_px: t } => {
                affine(IDENTITY, [s * t[0], s * t[1]])
            }
            ScenarioKind::Rotation { angle_rad } => affine(rotation(s * angle_rad), [0.0, 0.0]),
            ScenarioKind::Gradient {
                f,
                translation_px: t,
            } => affine(lerp_mat(s, &f), [s * t[0], s * t[1]]),
            ScenarioKind::Uniaxial { lambda } => {
                let l = ramp(lambda, 1.0);
                affine([[l, 0.0], [0.0, 1.0 / l.sqrt()]], [0.0, 0.0])
            }
            ScenarioKind::Equibiaxial { lambda } => {
                let l = ramp(lambda, 1.0);
                affine([[l, 0.0], [0.0, l]], [0.0, 0.0])
            }
            ScenarioKind::Chirp {
                amplitude_px,
                start_px,
                periods,
            } => Motion::Chirp(Chirp {
                amplitude_px: s * amplitude_px,
                start_px,
                length_px: self.width_px - 1.0 - start_px,
                periods,
            }),
            ScenarioKind::Bulge { strain, width_px } => Motion::Bulge(Bulge {
                strain: s * strain,
                width_px,
                centre_px: self.centre_px,
            }),
            ScenarioKind::BadPositioning {
                lambda,
                angle_rad,
                translation_px: t,
            } => {
                let l = ramp(lambda, 1.0);
                let f = mul_mat(&rotation(s * angle_rad), &[[l, 0.0], [0.0, 1.0 / l.sqrt()]]);
                affine(f, [s * t[0], s * t[1]])
            }
        }
    }

    /// Ramp fraction of frame `k` of `n`: 0 at the first frame, 1 at the last.
    pub fn fraction(frame: u64, frames_total: u64) -> f64 {
        assert!(frame < frames_total, "frame {frame} of {frames_total}");
        if frames_total == 1 {
            1.0
        } else {
            frame as f64 / (frames_total - 1) as f64
        }
    }

    /// The motion of frame `k` of `n` (identity at frame 0, final state at frame n - 1; a
    /// single frame gets the final state).
    pub fn motion_at(&self, frame: u64, frames_total: u64) -> Motion {
        self.motion_at_fraction(Self::fraction(frame, frames_total))
    }

    /// The truth record of a motion of this scenario (affine part at the centre).
    pub fn truth_of(&self, motion: &Motion) -> Truth {
        let c = self.centre_px;
        let (f, translation_px) = match motion {
            Motion::Affine(a) => {
                assert_eq!(a.centre_px, c, "affine motion about another centre");
                (a.f, a.translation_px)
            }
            other => (other.gradient(c), other.displacement(c)),
        };
        Truth {
            f,
            translation_px,
            centre_px: c,
            homogeneous: motion.is_homogeneous(),
            scenario_id: self.kind.id(),
            specimen: None,
        }
    }
}

fn lerp_mat(s: f64, f: &Mat2) -> Mat2 {
    let mut out = IDENTITY;
    for i in 0..2 {
        for j in 0..2 {
            out[i][j] += s * (f[i][j] - IDENTITY[i][j]);
        }
    }
    out
}
