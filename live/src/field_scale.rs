//! The scale of a run's fields, mm per px, for their mm columns (`fields/field_*.csv`
//! `x_mm,y_mm,u_mm,v_mm`, the `.vts` `displacement_mm`): the user's (`[camera]
//! scale_mm_per_px` or `scale_known_length`), else the simulated camera's own framing (known
//! exactly: `mm_per_px` on a cruciform or the homogeneous sheet, `strip_mm_per_px` on a
//! strip), else none (a real camera without a calibration: px only).

use crate::config::RunConfig;
use wire::scale::MmPerPx;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldScale {
    /// The user's, for every field.
    User(MmPerPx),
    /// The simulated camera's, per specimen.
    Framing(producer::Framing),
    /// Unknown: px only.
    None,
}

impl FieldScale {
    /// The run's scale from its configuration (checked by `validate`).
    pub fn of(config: &RunConfig) -> FieldScale {
        let c = &config.camera;
        if let Some(known) = c.scale_known_length {
            return FieldScale::User(known.scale());
        }
        if let Ok(scale) = MmPerPx::new(c.scale_mm_per_px) {
            return FieldScale::User(scale);
        }
        match c.source.has_truth() {
            true => FieldScale::Framing(c.framing()),
            false => FieldScale::None,
        }
    }

    /// The scale of a field whose specimen is held by `grips` grips (None: the homogeneous
    /// sheet, or a specimen unknown), or None when it is not known.
    pub fn of_field(&self, grips: Option<usize>) -> Option<MmPerPx> {
        match self {
            FieldScale::User(s) => Some(*s),
            FieldScale::Framing(f) => {
                let mm_per_px = match grips {
                    Some(2) => f.strip_mm_per_px,
                    _ => f.mm_per_px,
                };
                MmPerPx::new(mm_per_px).ok()
            }
            FieldScale::None => None,
        }
    }

    /// The scale of every field when it can be known without the specimen's solves (which
    /// `dicstream monitor` does not receive): the user's, or the simulated camera's when one
    /// framing serves every test (`structure`: the specimen is `membrane`'s, whose strip may
    /// be framed apart from the cruciform). None otherwise: px only.
    pub fn without_solves(&self, structure: bool) -> Option<MmPerPx> {
        match self {
            FieldScale::Framing(f) if structure && f.strip_mm_per_px != f.mm_per_px => None,
            _ => self.of_field(None),
        }
    }

    /// Whether the fields have mm at all: `frames.csv`'s extensometers get mm columns, the
    /// dashboard shows them in mm.
    pub fn in_mm(&self) -> bool {
        self.of_field(None).is_some()
    }

    /// What `units.json` says of it.
    pub fn note(&self) -> String {
        match self {
            FieldScale::User(s) => format!("scale: {s} mm per px, the user's ([camera])"),
            FieldScale::Framing(f) => format!(
                "scale: the simulated camera's, per test: {} mm per px on a cruciform or the \
                 homogeneous sheet, {} mm per px on a strip; a file's own is x_mm / x",
                f.mm_per_px, f.strip_mm_per_px
            ),
            FieldScale::None => {
                "no scale known (a real camera without [camera] scale_mm_per_px or \
                 scale_known_length): px only, no mm columns"
                    .to_string()
            }
        }
    }
}

/// The run's scale as `summary.json` says it: mm per px (on a strip too, when the simulated
/// camera re-frames on it) and where it came from.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ScaleReport {
    /// None: no scale known (px only).
    pub mm_per_px: Option<f64>,
    /// The simulated camera's on a strip, when it differs from `mm_per_px`'s framing.
    pub strip_mm_per_px: Option<f64>,
    pub from: String,
}

impl ScaleReport {
    pub fn of(config: &RunConfig) -> ScaleReport {
        let c = &config.camera;
        let user = |scale: MmPerPx, from: String| ScaleReport {
            mm_per_px: Some(scale.get()),
            strip_mm_per_px: None,
            from,
        };
        match FieldScale::of(config) {
            FieldScale::User(scale) => match c.scale_known_length {
                Some(known) => user(
                    scale,
                    format!(
                        "[camera] scale_known_length = \"{known}\": {} mm over {:.3} px",
                        known.length_mm,
                        known.distance_px()
                    ),
                ),
                None => user(scale, "[camera] scale_mm_per_px".to_string()),
            },
            FieldScale::Framing(f) => ScaleReport {
                mm_per_px: Some(f.mm_per_px),
                strip_mm_per_px: Some(f.strip_mm_per_px),
                from: "the simulated camera's framing ([camera] mm_per_px; strip_mm_per_px \
                       on a strip)"
                    .to_string(),
            },
            FieldScale::None => ScaleReport {
                mm_per_px: None,
                strip_mm_per_px: None,
                from: FieldScale::None.note(),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_users_scale_wins_the_simulated_cameras_is_the_default_a_real_camera_has_none() {
        let config = |toml: &str| {
            let c = RunConfig::from_toml(toml, "t.toml").unwrap();
            c.validate().unwrap();
            FieldScale::of(&c)
        };
        let simulated = config("");
        assert_eq!(
            simulated.of_field(None),
            MmPerPx::new(producer::DEFAULT_MM_PER_PX).ok()
        );
        assert_eq!(
            simulated.of_field(Some(2)),
            MmPerPx::new(producer::DEFAULT_STRIP_MM_PER_PX).ok()
        );
        // Without the solves (a monitor): the homogeneous sheet's framing serves every field, a
        // structure's strip is framed apart.
        assert_eq!(simulated.without_solves(false), simulated.of_field(None));
        assert_ne!(
            producer::DEFAULT_STRIP_MM_PER_PX,
            producer::DEFAULT_MM_PER_PX
        );
        assert_eq!(simulated.without_solves(true), None);
        let direct = config("[camera]\nscale_mm_per_px = 0.05\n");
        assert_eq!(direct.of_field(Some(2)), MmPerPx::new(0.05).ok());
        assert_eq!(direct.without_solves(true), MmPerPx::new(0.05).ok());
        let known = config("[camera]\nscale_known_length = \"0,0 300,400 25\"\n");
        assert_eq!(known.of_field(None), MmPerPx::new(0.05).ok());
        let report = |toml: &str| ScaleReport::of(&RunConfig::from_toml(toml, "t.toml").unwrap());
        let from_length = report("[camera]\nscale_known_length = \"0,0 300,400 25\"\n");
        assert_eq!(from_length.mm_per_px, Some(0.05));
        assert!(
            from_length.from.contains("scale_known_length")
                && from_length.from.contains("500.000 px"),
            "{from_length:?}"
        );
        let direct = report("[camera]\nscale_mm_per_px = 0.05\n");
        assert_eq!(
            (direct.mm_per_px, direct.from.as_str()),
            (Some(0.05), "[camera] scale_mm_per_px")
        );
        let framing = report("");
        assert_eq!(framing.mm_per_px, Some(producer::DEFAULT_MM_PER_PX));
        assert_eq!(
            framing.strip_mm_per_px,
            Some(producer::DEFAULT_STRIP_MM_PER_PX)
        );
        assert!(framing.from.contains("simulated camera"));
        let none = report("[camera]\nsource = \"replay\"\n");
        assert_eq!(none.mm_per_px, None);
        assert!(none.from.contains("no scale known"), "{none:?}");
        let real = RunConfig::from_toml("[camera]\nsource = \"replay\"\n", "t.toml").unwrap();
        let real = FieldScale::of(&real);
        assert_eq!(real.of_field(None), None);
        assert!(real.note().contains("px only"));
    }

    #[test]
    fn a_bad_scale_is_refused_before_the_run() {
        let refused = |toml: &str| {
            let read = RunConfig::from_toml(toml, "t.toml");
            let e = match read {
                Err(e) => e,
                Ok(c) => c.validate().unwrap_err(),
            };
            format!("{e:#}")
        };
        let e = refused("[camera]\nscale_mm_per_px = -0.1\n");
        assert!(e.contains("scale_mm_per_px = -0.1"), "{e}");
        let e = refused("[camera]\nscale_known_length = \"1,1 1,1 10\"\n");
        assert!(e.contains("the two points are the same"), "{e}");
        let e = refused("[camera]\nscale_mm_per_px = 0.1\nscale_known_length = \"0,0 10,0 1\"\n");
        assert!(e.contains("one of"), "{e}");
    }
}
