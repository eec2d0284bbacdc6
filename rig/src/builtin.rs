//! Built-in tests of the `--test` option: uniaxial or equibiaxial tension to a stretch at a
//! stretch rate, in centroid displacement control (paper sections 4.b and 4.c).

use crate::control::{AxisControl, ControlMode};
use crate::ids::{Axis, Channel};
use crate::program::{Program, ProgramError, Step, StopTransition};
use crate::specimen::{Loading, SpecimenConfig, SpecimenGeometry};

/// Why a built-in test's program was refused: its rate or stretch as the command line gives
/// them, or the program they make.
#[derive(Debug, thiserror::Error)]
pub enum TestError {
    #[error("--rate {}: expected a positive stretch rate (/s)", crate::refusal::number(*.rate_per_s))]
    Rate { rate_per_s: f64 },
    #[error("--stretch {}: expected a stretch in (1, 8]", crate::refusal::number(*.stretch))]
    Stretch { stretch: f64 },
    #[error(transparent)]
    Program(#[from] ProgramError),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BuiltinTest {
    Uniaxial,
    Equibiaxial,
}

impl BuiltinTest {
    pub fn parse(text: &str) -> Option<BuiltinTest> {
        match text {
            "uniaxial" => Some(BuiltinTest::Uniaxial),
            "equibiaxial" => Some(BuiltinTest::Equibiaxial),
            _ => None,
        }
    }

    /// As the command line names it.
    pub fn name(self) -> &'static str {
        match self {
            BuiltinTest::Uniaxial => "uniaxial",
            BuiltinTest::Equibiaxial => "equibiaxial",
        }
    }

    /// The specimen of the test: a 100 × 20 × 2 mm strip in uniaxial tension along X, the
    /// default 100 × 100 × 2 mm cruciform centre in equibiaxial tension.
    pub fn specimen(self) -> SpecimenConfig {
        match self {
            BuiltinTest::Uniaxial => SpecimenConfig {
                geometry: SpecimenGeometry {
                    gauge_length_mm: 100.0,
                    width_mm: 20.0,
                    thickness_mm: 2.0,
                },
                loading: Loading::Uniaxial(Axis::X),
                ..SpecimenConfig::default()
            },
            BuiltinTest::Equibiaxial => SpecimenConfig::default(),
        }
    }

    /// Hold 1 s, then ramp the elongation(s) to `stretch` at `rate_per_s` (stretch per second),
    /// then hold 1 s. Stop transition: ramp to zero at 10× the loading rate.
    pub fn program(self, rate_per_s: f64, stretch: f64) -> Result<Program, TestError> {
        if !(rate_per_s.is_finite() && rate_per_s > 0.0) {
            return Err(TestError::Rate { rate_per_s });
        }
        if !(stretch.is_finite() && stretch > 1.0 && stretch <= 8.0) {
            return Err(TestError::Stretch { stretch });
        }
        let geometry = self.specimen().geometry;
        let axes: &[(Axis, f64)] = match self {
            BuiltinTest::Uniaxial => &[(Axis::X, geometry.gauge_length_mm)],
            BuiltinTest::Equibiaxial => &[
                (Axis::X, geometry.gauge_length_mm),
                (Axis::Y, geometry.width_mm),
            ],
        };
        let centroid = AxisControl::Centroid(ControlMode::Displacement);
        let program = Program {
            name: format!("{} to λ {stretch} at {rate_per_s} /s", self.name()),
            stop: StopTransition::RampToZero,
            stop_rate_per_s: 10.0 * rate_per_s * geometry.gauge_length_mm,
            setup: axes.iter().map(|&(axis, _)| (axis, centroid)).collect(),
            channels: axes
                .iter()
                .map(|&(axis, gauge_mm)| {
                    let steps = vec![
                        Step::Hold { duration_s: 1.0 },
                        Step::Ramp {
                            to: (stretch - 1.0) * gauge_mm,
                            rate_per_s: rate_per_s * gauge_mm,
                            relative: false,
                        },
                        Step::Hold { duration_s: 1.0 },
                    ];
                    (Channel::Elongation(axis), steps)
                })
                .collect(),
        };
        program.validate()?;
        Ok(program)
    }
}
