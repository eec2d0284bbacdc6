//! The camera process's settings, one struct: what `dicstream run` writes for its camera
//! (`<results>/settings/producer.json`, `dicstream producer --settings FILE`) and what the
//! command line's flags make. Pure data: the process (`stream`) runs them.

use crate::genicam::{CameraSettings, CameraSpec};
use crate::{RigFollowConfig, SimulatedConfig};
use std::path::PathBuf;

/// Where the frames come from.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SourceSettings {
    /// The simulated camera rendering each frame from the newest `rig/state` sample.
    FollowRig {
        camera: SimulatedConfig,
        follow: RigFollowConfig,
    },
    /// The simulated camera playing a scenario (`NAME` or `NAME:key=value,...`) over `frames`.
    Scenario {
        camera: SimulatedConfig,
        scenario: String,
        frames: u64,
    },
    /// Image files: a folder (natural order) or a glob, once or endlessly.
    Replay { files: PathBuf, looping: bool },
    /// The images another program writes into a folder, each once it is complete.
    Watch {
        dir: PathBuf,
        /// Also the images already there at start.
        from_start: bool,
        /// End after this long without a new image (None: never).
        idle_timeout_s: Option<f64>,
        /// A file unchanged this long is complete.
        settle_ms: u64,
        /// One CSV row per frame: which file.
        log: Option<PathBuf>,
    },
    /// A GenICam camera (feature `genicam`).
    Genicam {
        #[serde(with = "wire::names::text")]
        camera: CameraSpec,
        settings: CameraSettings,
        /// One CSV row per frame: the camera's frame id and timestamp.
        log: Option<PathBuf>,
    },
}

/// Everything the camera process needs to start.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProducerSettings {
    pub instance: String,
    pub source: SourceSettings,
    /// Frames per second to pace to (None: as fast as the source gives them).
    pub fps: Option<f64>,
    /// Stop after this many frames (the source may end earlier).
    pub max_frames: Option<u64>,
    /// Id of the first frame (a restarted camera continues the numbering).
    pub first_frame_id: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_round_trip_through_json_with_their_source_named() {
        let mut camera = SimulatedConfig::new(320, 240);
        camera.threads = 1;
        camera.camera.bit_depth = 12;
        let settings = ProducerSettings {
            instance: "bench".into(),
            source: SourceSettings::FollowRig {
                camera,
                follow: RigFollowConfig::default(),
            },
            fps: Some(10.0),
            max_frames: None,
            first_frame_id: 7,
        };
        let json = serde_json::to_value(&settings).unwrap();
        assert_eq!(json["source"]["kind"], "follow_rig");
        assert_eq!(json["source"]["camera"]["width_px"], 320);
        assert_eq!(json["source"]["camera"]["renderer"], "fast");
        assert_eq!(json["source"]["camera"]["camera"]["bit_depth"], 12);
        let back: ProducerSettings = serde_json::from_value(json).unwrap();
        assert_eq!(back, settings);
        let genicam = SourceSettings::Genicam {
            camera: "genicam:Fake_1".parse().unwrap(),
            settings: CameraSettings {
                roi: Some("0,0,64,48".parse().unwrap()),
                pixel_format: Some("Mono12".parse().unwrap()),
                ..CameraSettings::default()
            },
            log: None,
        };
        let json = serde_json::to_value(&genicam).unwrap();
        assert_eq!(json["camera"], "genicam:Fake_1");
        assert_eq!(json["settings"]["roi"], "0,0,64,48");
        assert_eq!(json["settings"]["pixel_format"], "Mono12");
        assert_eq!(
            serde_json::from_value::<SourceSettings>(json).unwrap(),
            genicam
        );
        let error = serde_json::from_str::<SourceSettings>(
            r#"{"kind": "replay", "files": "a", "looping": false, "colour": 1}"#,
        )
        .unwrap_err();
        assert!(
            error.to_string().contains("unknown field `colour`"),
            "{error}"
        );
    }
}
