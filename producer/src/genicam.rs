//! Real GenICam cameras (GigE Vision, USB3 Vision): the pure part, built always and tested
//! without a camera: pixel formats and their conversion into the `frames` payload
//! (`pixels.rs`), the region of interest (`roi.rs`), the trigger mode, and the link's
//! bookkeeping (buffer outcomes, lost/reconnect backoff, `link.rs`). The Aravis part (list,
//! open, configure, acquire, and the streaming loop) is the binary's, with its `genicam`
//! feature (`src/genicam/`): turning that feature on or off rebuilds the binary alone.

mod link;
mod pixels;
mod roi;

use std::str::FromStr;

pub use link::{
    BufferCounts, BufferStatus, Link, LinkState, FIRST_RETRY, MAX_RETRY, SILENCE, SILENT_PERIODS,
};
pub use pixels::{convert_into, ConvertError, PixelFormat};
pub use roi::{Roi, RoiError, RoiLimits};

/// When the camera takes a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Trigger {
    /// Free-running at the camera's frame rate (`TriggerMode Off`, `AcquisitionFrameRate`
    /// set from `--fps`).
    #[default]
    Free,
    /// The producer triggers each frame (`TriggerSource Software`, `TriggerSoftware` command)
    /// at `--fps`: frames at the host's pace.
    Software,
    /// An external signal on the camera's input line triggers each frame (`TriggerSource
    /// Line1`, rising edge): the test machine or a pulse generator sets the pace, `--fps` does
    /// not apply and a silent camera is not taken as lost.
    Hardware,
}

wire::named!(Trigger, "trigger", ignore_case, {
    Free => "free", Software => "software", Hardware => "hardware",
});

impl Trigger {
    /// The frame or trigger rate to set for `fps` asked: none for 0 (the camera's own rate)
    /// or under a hardware trigger (the external pulses set it).
    pub fn rate_fps(self, fps: f64) -> Option<f64> {
        (fps > 0.0 && self != Trigger::Hardware).then_some(fps)
    }
}

/// Which camera `--camera` names: `genicam` (the first found) or `genicam:ID` (an Aravis
/// device id such as `Basler-21234567`, a serial number, or an address).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CameraSpec {
    pub id: Option<String>,
}

/// Camera options refused before anything is sent to a camera.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraArgError {
    #[error(
        "--camera {text:?}: expected genicam (the first camera found) or genicam:ID (an id \
         from `dicstream cameras`)"
    )]
    Spec { text: String },
    #[error("{flag} {value}: expected a finite number{}", if *positive { " above 0" } else { "" })]
    Number {
        flag: &'static str,
        value: f64,
        positive: bool,
    },
    #[error("--trigger software needs --fps (the rate the producer triggers at)")]
    SoftwareTriggerWithoutFps,
}

/// As `--camera` takes it.
impl std::fmt::Display for CameraSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.id {
            None => f.write_str("genicam"),
            Some(id) => write!(f, "genicam:{id}"),
        }
    }
}

impl FromStr for CameraSpec {
    type Err = CameraArgError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let bad = || CameraArgError::Spec {
            text: text.to_string(),
        };
        let rest = text.strip_prefix("genicam").ok_or_else(bad)?;
        match rest.strip_prefix(':') {
            None if rest.is_empty() => Ok(CameraSpec { id: None }),
            Some(id) if !id.trim().is_empty() => Ok(CameraSpec {
                id: Some(id.trim().to_string()),
            }),
            _ => Err(bad()),
        }
    }
}

/// How to set the camera up (`dicstream producer --camera` options). `None` leaves the
/// camera's own setting.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSettings {
    pub exposure_us: Option<f64>,
    pub gain_db: Option<f64>,
    /// Frame rate (free-running) or trigger rate (software trigger), frames per second.
    pub fps: Option<f64>,
    pub pixel_format: Option<PixelFormat>,
    #[serde(with = "wire::names::empty_is_none")]
    pub roi: Option<Roi>,
    pub trigger: Trigger,
}

impl CameraSettings {
    /// Checks the numbers before anything is sent to a camera.
    pub fn check(&self) -> Result<(), CameraArgError> {
        for (name, value, min) in [
            ("--exposure-us", self.exposure_us, f64::MIN_POSITIVE),
            ("--fps", self.fps, f64::MIN_POSITIVE),
            ("--gain-db", self.gain_db, f64::MIN),
        ] {
            if let Some(v) = value {
                if !v.is_finite() || v < min {
                    return Err(CameraArgError::Number {
                        flag: name,
                        value: v,
                        positive: min > 0.0,
                    });
                }
            }
        }
        if self.trigger == Trigger::Software && self.fps.is_none() {
            return Err(CameraArgError::SoftwareTriggerWithoutFps);
        }
        Ok(())
    }

    /// The period at which frames are expected, if the camera should be sending on its own
    /// or on the producer's triggers.
    pub fn expected_period(&self) -> Option<std::time::Duration> {
        match self.trigger {
            Trigger::Hardware => None,
            Trigger::Free | Trigger::Software => Some(std::time::Duration::from_secs_f64(
                1.0 / self.fps.unwrap_or(1.0),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_spec_trigger_and_settings_parse_or_refuse_clearly() {
        assert_eq!("genicam".parse(), Ok(CameraSpec { id: None }));
        assert_eq!(
            "genicam:Aravis-Fake-GV01".parse(),
            Ok(CameraSpec {
                id: Some("Aravis-Fake-GV01".into())
            })
        );
        for bad in ["genicam:", "gige", "genicamX", ""] {
            assert!(
                bad.parse::<CameraSpec>()
                    .unwrap_err()
                    .to_string()
                    .contains("genicam:ID"),
                "{bad}"
            );
        }
        assert_eq!("Software".parse(), Ok(Trigger::Software));
        assert!("line1"
            .parse::<Trigger>()
            .unwrap_err()
            .to_string()
            .contains("free, software or hardware"));

        assert_eq!(CameraSettings::default().check(), Ok(()));
        let software = CameraSettings {
            trigger: Trigger::Software,
            ..CameraSettings::default()
        };
        assert!(software
            .check()
            .unwrap_err()
            .to_string()
            .contains("needs --fps"));
        let bad_exposure = CameraSettings {
            exposure_us: Some(0.0),
            ..CameraSettings::default()
        };
        assert!(bad_exposure
            .check()
            .unwrap_err()
            .to_string()
            .contains("--exposure-us 0"));
        let negative_gain = CameraSettings {
            gain_db: Some(-3.0),
            ..CameraSettings::default()
        };
        assert_eq!(negative_gain.check(), Ok(()));
        let nan_gain = CameraSettings {
            gain_db: Some(f64::NAN),
            ..CameraSettings::default()
        };
        assert!(nan_gain.check().is_err());
    }
}
