//! Built-in tests of the `--test` option: uniaxial or equibiaxial tension to a stretch at a
//! stretch rate, in centroid displacement control (paper sections 4.b and 4.c).

use crate::control::{AxisControl, ControlMode};
use crate::ids::{Axis, Channel};
use crate::program::{Program, ProgramError, Step, StopTransition};
use crate::specimen::{Loading, SpecimenConfig, SpecimenSettings};

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

    /// The loading of the test: uniaxial along X, or equibiaxial.
    pub fn loading(self) -> Loading {
        match self {
            BuiltinTest::Uniaxial => Loading::Uniaxial(Axis::X),
            BuiltinTest::Equibiaxial => Loading::Equibiaxial,
        }
    }

    /// The specimen of the test, as `settings` make it: the uniaxial strip in uniaxial tension
    /// along X, the cruciform in equibiaxial tension (by default a 100 × 20 × 2 mm strip and a
    /// cruciform whose centre is 100 × 100 × 2 mm).
    pub fn specimen(self, settings: &SpecimenSettings) -> SpecimenConfig {
        SpecimenConfig::of(self.loading(), settings)
    }

    /// Hold 1 s, then ramp the elongation(s) to `stretch` at `rate_per_s` (stretch per second),
    /// then hold 1 s. Stop transition: ramp to zero at 10× the loading rate. The stretch is
    /// nominal: the elongation over the specimen's gauge length ([`SpecimenConfig::gauge_mm`]:
    /// the homogeneous sheet's stretch; the structure's gauge zone reaches less, its arms take
    /// the rest).
    pub fn program(
        self,
        specimen: &SpecimenConfig,
        rate_per_s: f64,
        stretch: f64,
    ) -> Result<Program, TestError> {
        if !(rate_per_s.is_finite() && rate_per_s > 0.0) {
            return Err(TestError::Rate { rate_per_s });
        }
        if !(stretch.is_finite() && stretch > 1.0 && stretch <= 8.0) {
            return Err(TestError::Stretch { stretch });
        }
        let gauge_mm = specimen.gauge_mm();
        let axes: &[(Axis, f64)] = match self {
            BuiltinTest::Uniaxial => &[(Axis::X, gauge_mm[0])],
            BuiltinTest::Equibiaxial => &[(Axis::X, gauge_mm[0]), (Axis::Y, gauge_mm[1])],
        };
        let centroid = AxisControl::Centroid(ControlMode::Displacement);
        let program = Program {
            name: format!("{} to λ {stretch} at {rate_per_s} /s", self.name()),
            stop: StopTransition::RampToZero,
            stop_rate_per_s: 10.0 * rate_per_s * gauge_mm[0],
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
