//! The region of interest (`--roi x,y,w,h`): parsed, then checked against what the camera
//! accepts (its sensor, its smallest size and its steps) before anything is sent to it, so a
//! bad region is a clear error instead of a camera that silently rounds it.

use std::fmt;
use std::str::FromStr;

/// A region of the sensor, px: left, top, width, height.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Roi {
    pub x_px: u32,
    pub y_px: u32,
    pub width_px: u32,
    pub height_px: u32,
}

impl fmt::Display for Roi {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{},{},{},{}",
            self.x_px, self.y_px, self.width_px, self.height_px
        )
    }
}

impl FromStr for Roi {
    type Err = RoiError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let bad = || RoiError::Text {
            text: text.to_string(),
        };
        let parts: Vec<u32> = text
            .split(',')
            .map(|p| p.trim().parse::<u32>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        let [x_px, y_px, width_px, height_px] = parts[..] else {
            return Err(bad());
        };
        if width_px == 0 || height_px == 0 {
            return Err(bad());
        }
        Ok(Roi {
            x_px,
            y_px,
            width_px,
            height_px,
        })
    }
}

/// What the camera accepts for a region (from its `Width`/`Height`/`OffsetX`/`OffsetY`
/// features).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RoiLimits {
    pub sensor_width_px: u32,
    pub sensor_height_px: u32,
    pub min_width_px: u32,
    pub min_height_px: u32,
    /// Steps of the width and height (1 when any value goes).
    pub width_step_px: u32,
    pub height_step_px: u32,
    /// Steps of the offsets.
    pub x_step_px: u32,
    pub y_step_px: u32,
}

/// Why a region does not fit the camera.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum RoiError {
    #[error("--roi {text:?}: expected x,y,w,h in px (four whole numbers, w and h above 0), e.g. 0,0,1024,1024")]
    Text { text: String },
    #[error("--roi {roi}: reaches beyond the {sensor_width_px}x{sensor_height_px} px sensor")]
    Outside {
        roi: Roi,
        sensor_width_px: u32,
        sensor_height_px: u32,
    },
    #[error("--roi {roi}: the camera's smallest region is {min_width_px}x{min_height_px} px")]
    TooSmall {
        roi: Roi,
        min_width_px: u32,
        min_height_px: u32,
    },
    #[error("--roi {roi}: the camera takes {what} in steps of {step_px} px (try {nearest_px})")]
    Step {
        roi: Roi,
        what: &'static str,
        step_px: u32,
        nearest_px: u32,
    },
}

impl Roi {
    /// The whole sensor.
    pub fn full(limits: &RoiLimits) -> Roi {
        Roi {
            x_px: 0,
            y_px: 0,
            width_px: limits.sensor_width_px,
            height_px: limits.sensor_height_px,
        }
    }

    /// Checks the region against the camera's limits.
    pub fn check(&self, limits: &RoiLimits) -> Result<(), RoiError> {
        let roi = *self;
        let right = u64::from(self.x_px) + u64::from(self.width_px);
        let bottom = u64::from(self.y_px) + u64::from(self.height_px);
        if right > u64::from(limits.sensor_width_px) || bottom > u64::from(limits.sensor_height_px)
        {
            return Err(RoiError::Outside {
                roi,
                sensor_width_px: limits.sensor_width_px,
                sensor_height_px: limits.sensor_height_px,
            });
        }
        if self.width_px < limits.min_width_px || self.height_px < limits.min_height_px {
            return Err(RoiError::TooSmall {
                roi,
                min_width_px: limits.min_width_px,
                min_height_px: limits.min_height_px,
            });
        }
        for (what, value, step) in [
            ("the width", self.width_px, limits.width_step_px),
            ("the height", self.height_px, limits.height_step_px),
            ("the x offset", self.x_px, limits.x_step_px),
            ("the y offset", self.y_px, limits.y_step_px),
        ] {
            let step = step.max(1);
            if value % step != 0 {
                return Err(RoiError::Step {
                    roi,
                    what,
                    step_px: step,
                    nearest_px: value - value % step,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: RoiLimits = RoiLimits {
        sensor_width_px: 2048,
        sensor_height_px: 1536,
        min_width_px: 64,
        min_height_px: 2,
        width_step_px: 16,
        height_step_px: 2,
        x_step_px: 4,
        y_step_px: 1,
    };

    #[test]
    fn parses_four_numbers_and_refuses_anything_else_clearly() {
        assert_eq!(
            "8, 4,1024,768".parse::<Roi>(),
            Ok(Roi {
                x_px: 8,
                y_px: 4,
                width_px: 1024,
                height_px: 768
            })
        );
        for bad in [
            "",
            "1,2,3",
            "1,2,3,4,5",
            "a,0,10,10",
            "0,0,0,10",
            "-1,0,10,10",
        ] {
            let err = bad.parse::<Roi>().unwrap_err().to_string();
            assert!(err.contains("expected x,y,w,h"), "{bad}: {err}");
        }
    }

    #[test]
    fn a_region_must_fit_the_sensor_its_minimum_and_its_steps() {
        assert_eq!(Roi::full(&LIMITS).check(&LIMITS), Ok(()));
        let ok = Roi {
            x_px: 1024,
            y_px: 3,
            width_px: 1024,
            height_px: 512,
        };
        assert_eq!(ok.check(&LIMITS), Ok(()));
        let wide = Roi { x_px: 1028, ..ok };
        assert!(wide
            .check(&LIMITS)
            .unwrap_err()
            .to_string()
            .contains("beyond the 2048x1536 px sensor"));
        let small = Roi { width_px: 32, ..ok };
        assert!(matches!(
            small.check(&LIMITS),
            Err(RoiError::TooSmall { .. })
        ));
        let odd = Roi {
            width_px: 1000,
            ..ok
        };
        assert_eq!(
            odd.check(&LIMITS).unwrap_err().to_string(),
            "--roi 1024,3,1000,512: the camera takes the width in steps of 16 px (try 992)"
        );
        let x = Roi {
            x_px: 1022,
            width_px: 1024,
            ..ok
        };
        assert!(x
            .check(&LIMITS)
            .unwrap_err()
            .to_string()
            .contains("x offset"));
        // No overflow on huge values.
        let huge = Roi {
            x_px: u32::MAX,
            ..ok
        };
        assert!(matches!(huge.check(&LIMITS), Err(RoiError::Outside { .. })));
    }
}
