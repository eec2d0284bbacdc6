//! The image's scale, mm per px: the one calibration of a field's displacements in mm. Given
//! directly (`--mm-per-px 0.05`, `[camera] scale_mm_per_px`) or from a known length: two image
//! points (px) and the distance between them on the specimen, mm (`--known-length "X1,Y1 X2,Y2
//! MM"`, `[camera] scale_known_length`). Every value is checked here, once, for the command
//! line and the configuration alike.

use std::fmt;
use std::str::FromStr;
use thiserror::Error;

/// A checked scale: finite and positive, mm per px.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MmPerPx(f64);

/// Why a scale or a known length is refused.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum ScaleError {
    #[error("scale {0} mm/px: expected a finite number above 0")]
    NotPositive(f64),
    #[error("scale {0:?} mm/px: expected a finite number above 0")]
    NotANumber(String),
    #[error("known length {0:?}: expected \"X1,Y1 X2,Y2 MM\" (two image points in px and the distance between them on the specimen in mm), five numbers")]
    Syntax(String),
    #[error("known length: {what} is {value}, expected a finite number")]
    NotFinite { what: &'static str, value: f64 },
    #[error("known length: {0} mm, expected a distance above 0 mm")]
    LengthNotPositive(f64),
    #[error("known length: the two points are the same ({x},{y} px): no distance to calibrate on")]
    SamePoints { x: f64, y: f64 },
}

impl MmPerPx {
    pub fn new(mm_per_px: f64) -> Result<MmPerPx, ScaleError> {
        if mm_per_px.is_finite() && mm_per_px > 0.0 {
            Ok(MmPerPx(mm_per_px))
        } else {
            Err(ScaleError::NotPositive(mm_per_px))
        }
    }

    pub fn get(self) -> f64 {
        self.0
    }

    /// `px` px in mm.
    pub fn mm(self, px: f64) -> f64 {
        px * self.0
    }
}

impl fmt::Display for MmPerPx {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl FromStr for MmPerPx {
    type Err = ScaleError;

    fn from_str(text: &str) -> Result<MmPerPx, ScaleError> {
        let value: f64 = text
            .trim()
            .parse()
            .map_err(|_| ScaleError::NotANumber(text.to_string()))?;
        MmPerPx::new(value)
    }
}

/// Two points of the reference image (px) and the distance between them on the specimen (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnownLength {
    pub a_px: [f64; 2],
    pub b_px: [f64; 2],
    pub length_mm: f64,
}

impl KnownLength {
    /// Checks the points and the length: finite, a length above 0, two distinct points.
    pub fn new(a_px: [f64; 2], b_px: [f64; 2], length_mm: f64) -> Result<KnownLength, ScaleError> {
        let named = [
            ("x1", a_px[0]),
            ("y1", a_px[1]),
            ("x2", b_px[0]),
            ("y2", b_px[1]),
            ("the length", length_mm),
        ];
        if let Some(&(what, value)) = named.iter().find(|(_, v)| !v.is_finite()) {
            return Err(ScaleError::NotFinite { what, value });
        }
        if length_mm <= 0.0 {
            return Err(ScaleError::LengthNotPositive(length_mm));
        }
        if a_px == b_px {
            return Err(ScaleError::SamePoints {
                x: a_px[0],
                y: a_px[1],
            });
        }
        Ok(KnownLength {
            a_px,
            b_px,
            length_mm,
        })
    }

    /// The distance between the two points, px.
    pub fn distance_px(&self) -> f64 {
        (self.b_px[0] - self.a_px[0]).hypot(self.b_px[1] - self.a_px[1])
    }

    /// The scale it gives: the length over the points' distance.
    pub fn scale(&self) -> MmPerPx {
        MmPerPx::new(self.length_mm / self.distance_px()).expect("checked in new")
    }
}

impl fmt::Display for KnownLength {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [x1, y1] = self.a_px;
        let [x2, y2] = self.b_px;
        write!(f, "{x1},{y1} {x2},{y2} {}", self.length_mm)
    }
}

impl FromStr for KnownLength {
    type Err = ScaleError;

    /// `"X1,Y1 X2,Y2 MM"` (blanks or commas between the five numbers).
    fn from_str(text: &str) -> Result<KnownLength, ScaleError> {
        let syntax = || ScaleError::Syntax(text.to_string());
        let numbers: Vec<f64> = text
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<f64>().map_err(|_| syntax()))
            .collect::<Result<_, _>>()?;
        let [x1, y1, x2, y2, length_mm] = numbers[..] else {
            return Err(syntax());
        };
        KnownLength::new([x1, y1], [x2, y2], length_mm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_known_length_gives_the_scale_given_directly() {
        // 3-4-5: the points are 500 px apart, 125 mm on the specimen.
        let known: KnownLength = "100,200 400,600 125".parse().unwrap();
        assert_eq!(known.distance_px(), 500.0);
        let direct: MmPerPx = "0.25".parse().unwrap();
        assert!((known.scale().get() - direct.get()).abs() < 1e-15);
        // Commas only, as "x1,y1,x2,y2,L".
        let commas: KnownLength = "100,200,400,600,125".parse().unwrap();
        assert_eq!(commas, known);
        assert_eq!(known.to_string().parse::<KnownLength>().unwrap(), known);
        assert_eq!(direct.mm(4.0), 1.0);
    }

    #[test]
    fn bad_input_is_refused_with_its_reason() {
        let refused = |text: &str| text.parse::<KnownLength>().unwrap_err().to_string();
        assert!(refused("0,0 10,0 0").contains("0 mm, expected a distance above 0"));
        assert!(refused("0,0 10,0 -5").contains("-5 mm"));
        assert!(refused("3,4 3,4 10").contains("the two points are the same (3,4 px)"));
        assert!(refused("0,0 NaN,0 10").contains("x2 is NaN"));
        assert!(refused("0,0 10,0 inf").contains("the length is inf"));
        assert!(refused("0,0 10,0").contains("five numbers"));
        assert!(refused("0,0 10,0 ten").contains("five numbers"));
        for bad in ["0", "-0.1", "NaN", "inf", "mm"] {
            let e = bad.parse::<MmPerPx>().unwrap_err().to_string();
            assert!(e.contains("expected a finite number above 0"), "{bad}: {e}");
        }
    }
}
