//! Virtual strain gauges and extensometers the user places on the specimen, and the control
//! gauge: the one a field's header carries (strain control closes its loop on it, the
//! identifier's gauge route reads it).
//!
//! A gauge is placed in the image the mesh is defined in (the first reference; px, x = column,
//! y = row) and selects the mesh's nodes by their position there, so its nodes are followed
//! with the mesh whatever the specimen does:
//! - a **strain gauge** (a rectangle or a polygon) reads the mean strain of the valid nodes
//!   inside it: one affine least-squares fit of their displacements (CORRELI-GAUGE over the
//!   region), in the four measures;
//! - an **extensometer** (two points) reads its length: each point's displacement from an
//!   affine fit of the valid nodes within 1.5 mesh steps of it, the same point followed in every
//!   frame.
//!
//! A reading that cannot be made says why ([`NoReading`]), never a silent zero. The text form
//! (`--gauge`, `[correlator] gauges`) is `NAME=rect:X,Y,W,H`, `NAME=polygon:x,y x,y x,y ...` or
//! `NAME=extensometer:x,y x,y`.

mod reading;

pub use reading::{
    read, read_control, ControlRegion, GaugeNode, GaugeReading, GaugeValue, NoReading,
};

use crate::region::{Polygon, RegionParseError};
use std::fmt;
use std::str::FromStr;

/// Where a gauge reads.
#[derive(Clone, Debug, PartialEq)]
pub enum GaugeShape {
    /// A strain gauge: the valid nodes inside the polygon (a rectangle is one too).
    Region(Polygon),
    /// An extensometer between two points (px in the mesh's image).
    Extensometer { a_px: (f64, f64), b_px: (f64, f64) },
}

/// One named gauge.
#[derive(Clone, Debug, PartialEq)]
pub struct Gauge {
    pub name: String,
    pub shape: GaugeShape,
}

/// Which gauge the field's header carries: the mesh's central region (half its width and
/// height, the default), every valid node (the gauge before named gauges existed), or a
/// user's strain gauge by name.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum ControlGauge {
    #[default]
    Centre,
    All,
    Named(String),
}

/// The names a user's gauge may not take: the control gauge's built-in choices.
pub const RESERVED_NAMES: [&str; 2] = ["centre", "all"];

impl fmt::Display for ControlGauge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ControlGauge::Centre => f.write_str("centre"),
            ControlGauge::All => f.write_str("all"),
            ControlGauge::Named(name) => f.write_str(name),
        }
    }
}

impl FromStr for ControlGauge {
    type Err = GaugeParseError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Ok(match text.trim() {
            "centre" | "center" => ControlGauge::Centre,
            "all" => ControlGauge::All,
            name => ControlGauge::Named(checked_name(name, text)?.to_owned()),
        })
    }
}

/// Why a gauge's text was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GaugeParseError {
    #[error("gauge \"{text}\": expected NAME=rect:X,Y,W,H, NAME=polygon:x,y x,y x,y ... or NAME=extensometer:x,y x,y")]
    Form { text: String },
    #[error("gauge \"{text}\": the name \"{name}\" must be letters, digits, '_' or '-' (it names CSV columns), and not \"centre\" or \"all\" (the control gauge's built-in choices)")]
    Name { text: String, name: String },
    #[error("gauge \"{text}\": {reason}")]
    Shape { text: String, reason: String },
}

fn checked_name<'a>(name: &'a str, text: &str) -> Result<&'a str, GaugeParseError> {
    let fine = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        && !RESERVED_NAMES.contains(&name);
    if fine {
        Ok(name)
    } else {
        Err(GaugeParseError::Name {
            text: text.to_owned(),
            name: name.to_owned(),
        })
    }
}

impl FromStr for Gauge {
    type Err = GaugeParseError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let form = || GaugeParseError::Form {
            text: text.to_owned(),
        };
        let shape_error = |reason: String| GaugeParseError::Shape {
            text: text.to_owned(),
            reason,
        };
        let (name, rest) = text.split_once('=').ok_or_else(form)?;
        let name = checked_name(name.trim(), text)?.to_owned();
        let (kind, points) = rest.split_once(':').ok_or_else(form)?;
        let polygon = |p: &str| {
            p.parse::<Polygon>()
                .map_err(|e: RegionParseError| shape_error(e.to_string()))
        };
        let shape = match kind.trim() {
            "rect" => {
                let n: Vec<f64> = points
                    .split(',')
                    .map(|v| v.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
                    .collect::<Option<_>>()
                    .filter(|n: &Vec<f64>| n.len() == 4)
                    .ok_or_else(|| shape_error("a rectangle is X,Y,W,H in px".into()))?;
                let (x, y, w, h) = (n[0], n[1], n[2], n[3]);
                if w <= 0.0 || h <= 0.0 {
                    return Err(shape_error(format!(
                        "the rectangle's width and height must be positive, not {w} and {h}"
                    )));
                }
                GaugeShape::Region(Polygon {
                    vertices_px: vec![(x, y), (x + w, y), (x + w, y + h), (x, y + h)],
                })
            }
            "polygon" => {
                let p = polygon(points)?;
                if p.vertices_px.len() < 3 {
                    return Err(shape_error(format!(
                        "a polygon needs at least 3 vertices, not {}",
                        p.vertices_px.len()
                    )));
                }
                GaugeShape::Region(p)
            }
            "extensometer" => match polygon(points)?.vertices_px[..] {
                [a_px, b_px] if a_px != b_px => GaugeShape::Extensometer { a_px, b_px },
                [_, _] => return Err(shape_error("the two points are the same".into())),
                _ => {
                    return Err(shape_error(
                        "an extensometer is two points: x,y x,y in px".into(),
                    ))
                }
            },
            _ => return Err(form()),
        };
        Ok(Gauge { name, shape })
    }
}

/// As it is read (a rectangle is written as its polygon).
impl fmt::Display for Gauge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.shape {
            GaugeShape::Region(p) => write!(f, "{}=polygon:{p}", self.name),
            GaugeShape::Extensometer { a_px, b_px } => write!(
                f,
                "{}=extensometer:{},{} {},{}",
                self.name, a_px.0, a_px.1, b_px.0, b_px.1
            ),
        }
    }
}

impl Gauge {
    /// `strain` or `extensometer`, as summaries say it.
    pub fn kind(&self) -> &'static str {
        match self.shape {
            GaugeShape::Region(_) => "strain",
            GaugeShape::Extensometer { .. } => "extensometer",
        }
    }

    /// Refused when a point lies outside the `width_px` x `height_px` image.
    pub fn check_inside(&self, width_px: usize, height_px: usize) -> Result<(), String> {
        let points: Vec<(f64, f64)> = match &self.shape {
            GaugeShape::Region(p) => p.vertices_px.clone(),
            GaugeShape::Extensometer { a_px, b_px } => vec![*a_px, *b_px],
        };
        let (w, h) = (width_px as f64, height_px as f64);
        match points
            .iter()
            .find(|(x, y)| !(0.0..=w).contains(x) || !(0.0..=h).contains(y))
        {
            Some((x, y)) => Err(format!(
                "gauge {}: point {x},{y} is outside the {width_px}x{height_px} px image",
                self.name
            )),
            None => Ok(()),
        }
    }
}

text_serde!(Gauge);
text_serde!(ControlGauge);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauges_read_from_text_and_write_back() {
        let g: Gauge = "centre_sg=rect:10,20,30,40".parse().unwrap();
        assert_eq!(g.name, "centre_sg");
        assert_eq!(
            g.shape,
            GaugeShape::Region(Polygon {
                vertices_px: vec![(10.0, 20.0), (40.0, 20.0), (40.0, 60.0), (10.0, 60.0)]
            })
        );
        assert_eq!(g.to_string().parse::<Gauge>().unwrap(), g);
        let e: Gauge = "arm-x=extensometer:100,200 300.5,200".parse().unwrap();
        assert_eq!(
            e.shape,
            GaugeShape::Extensometer {
                a_px: (100.0, 200.0),
                b_px: (300.5, 200.0)
            }
        );
        assert_eq!(e.kind(), "extensometer");
        assert_eq!(e.to_string().parse::<Gauge>().unwrap(), e);
        let p: Gauge = "fillet=polygon:0,0 10,0 0,10".parse().unwrap();
        assert_eq!(p.kind(), "strain");
    }

    #[test]
    fn bad_gauges_are_refused_saying_why() {
        let error = |t: &str| t.parse::<Gauge>().unwrap_err().to_string();
        assert!(error("rect:1,2,3,4").contains("expected NAME="));
        assert!(error("a b=rect:1,2,3,4").contains("letters, digits"));
        assert!(error("centre=rect:1,2,3,4").contains("built-in"));
        assert!(error("g=rect:1,2,3").contains("X,Y,W,H"));
        assert!(error("g=rect:1,2,0,4").contains("positive"));
        assert!(error("g=polygon:1,2 3,4").contains("at least 3"));
        assert!(error("g=extensometer:1,2 1,2").contains("same"));
        assert!(error("g=extensometer:1,2 3,4 5,6").contains("two points"));
        assert!(error("g=circle:1,2,3").contains("expected NAME="));
        let g: Gauge = "g=extensometer:1,2 3,400".parse().unwrap();
        assert!(g.check_inside(100, 100).unwrap_err().contains("3,400"));
        assert!(g.check_inside(100, 400).is_ok());
    }

    #[test]
    fn the_control_gauge_is_centre_all_or_a_name() {
        assert_eq!("centre".parse(), Ok(ControlGauge::Centre));
        assert_eq!("all".parse(), Ok(ControlGauge::All));
        assert_eq!("mid".parse(), Ok(ControlGauge::Named("mid".to_owned())));
        assert!("no good".parse::<ControlGauge>().is_err());
        assert_eq!(ControlGauge::default().to_string(), "centre");
    }
}
