//! How each child process of a run is started (`dicstream <role> ...`), from the run's
//! configuration alone: pure, so a restart gets the same settings but for where the camera's
//! frame ids start. Each child gets its process's settings, typed, as a JSON file
//! (`--settings FILE`, the struct its command line's flags make too); a rig following a
//! machine's CSV log still gets flags.

use crate::children::Role;
use crate::config::{CameraSection, CameraSource, RigSource, RunConfig};
use crate::results::ResultsDir;
use std::path::{Path, PathBuf};

/// Relative margin of the camera's stretch envelope beyond the campaign's largest stretch.
const STRETCH_MARGIN: f64 = 0.05;

/// What a child is started with: its process's settings, written as JSON to `file` and
/// passed as `--settings FILE`.
#[derive(Clone, Debug, PartialEq)]
pub struct ChildLaunch {
    pub file: PathBuf,
    pub json: String,
}

impl ChildLaunch {
    /// The settings of `settings` in the results' settings file of `role`.
    fn new(role: Role, results: &ResultsDir, settings: &impl serde::Serialize) -> ChildLaunch {
        ChildLaunch {
            file: results.settings_file(role.name()),
            json: serde_json::to_string_pretty(settings)
                .expect("process settings serialise to JSON"),
        }
    }

    /// The arguments after the role, once the settings file is written.
    pub fn into_args(self) -> Result<Vec<String>, wire::files::FileError> {
        if let Some(folder) = self.file.parent() {
            std::fs::create_dir_all(folder).map_err(|reason| wire::files::FileError {
                path: folder.to_path_buf(),
                what: "create",
                reason,
            })?;
        }
        wire::files::write_atomic(&self.file, self.json.as_bytes())?;
        Ok(vec!["--settings".into(), text(&self.file)])
    }
}

/// How each child is started. `first_frame_id` is where the camera's frame ids start (past the
/// last id seen when a camera is restarted, so ids never go back). Refused for settings the
/// run's validation refuses.
pub fn child_launch(
    role: Role,
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
    first_frame_id: u64,
) -> anyhow::Result<ChildLaunch> {
    use rig::process::RigProcessSettings;
    Ok(match role {
        Role::Rig => {
            let settings = match config.rig.source {
                RigSource::CsvFollow => RigProcessSettings::CsvFollow(Box::new(
                    csv_follow_settings(config, instance, results),
                )),
                RigSource::Simulated => RigProcessSettings::Simulated(Box::new(rig_settings(
                    config, instance, results,
                )?)),
            };
            ChildLaunch::new(role, results, &settings)
        }
        Role::Producer => ChildLaunch::new(
            role,
            results,
            &producer_settings(config, instance, results, first_frame_id),
        ),
        Role::Correlator => ChildLaunch::new(
            role,
            results,
            &correlator_settings(config, instance, results)?,
        ),
        Role::Identifier => ChildLaunch::new(
            role,
            results,
            &identifier_settings(config, instance, results),
        ),
        Role::Link => ChildLaunch::new(role, results, &link_settings(config, instance, results)?),
    })
}

/// The link to the other host: `[link]` as written, its counts kept in the results (resumed
/// by a link started again, read back for the verdict).
pub fn link_settings(
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
) -> anyhow::Result<link::LinkSettings> {
    let section = config
        .link
        .clone()
        .ok_or_else(|| anyhow::anyhow!("no [link] section: the run starts no link"))?;
    Ok(link::LinkSettings {
        instance: instance.to_string(),
        link: section,
        counts_json: Some(results.link_counts_json()),
    })
}

/// A path as an argument.
fn text(path: &Path) -> String {
    path.to_string_lossy().into_owned()
}

/// The simulated rig: the campaign (or a strain-controlled test) on the specimen's law, its
/// log and journal in the results.
pub fn rig_settings(
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
) -> anyhow::Result<rig::settings::RigSettings> {
    use rig::settings::{LawCoefficients, RigSettings, RigStart, Speed};
    let g = &config.rig;
    let start = match config.strain_test()? {
        Some(test) => RigStart::Strain { test },
        None => RigStart::Campaign {
            tests: config.campaign()?.tests().to_vec(),
        },
    };
    Ok(RigSettings {
        instance: instance.to_string(),
        start,
        law: Some(LawCoefficients {
            f: config.specimen.law_f.clone(),
            g: config.specimen.law_g.clone(),
        }),
        speed: Speed::Factor(g.speed),
        publish_hz: g.publish_hz,
        log: Some(results.rig_csv()),
        log_hz: g.log_hz,
        seed: g.seed,
        state_dir: Some(results.rig_state()),
        exit_when_done: true,
        specimen: rig::SpecimenSettings {
            model: config.specimen.model,
            geometry: config.specimen.geometry.clone(),
        },
        ..RigSettings::default()
    })
}

/// The camera: the simulated one following the rig (its pattern and model as
/// `dicstream producer`'s defaults, but for what `[camera]` sets), a watched folder, a replay
/// or a GenICam camera.
pub fn producer_settings(
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
    first_frame_id: u64,
) -> producer::settings::ProducerSettings {
    use producer::settings::{ProducerSettings, SourceSettings};
    let c = &config.camera;
    let source = match c.source {
        CameraSource::Simulated => {
            let (camera, follow) = rig_camera(config);
            SourceSettings::FollowRig { camera, follow }
        }
        CameraSource::Watch => SourceSettings::Watch {
            dir: c.watch_dir.clone(),
            from_start: c.watch_from_start,
            idle_timeout_s: (c.watch_idle_timeout_s > 0.0).then_some(c.watch_idle_timeout_s),
            settle_ms: c.watch_settle_ms,
            log: Some(results.path("watched_frames.csv")),
        },
        CameraSource::Replay => SourceSettings::Replay {
            files: PathBuf::from(&c.replay_files),
            looping: false,
        },
        CameraSource::Genicam => {
            let trigger = c.genicam_trigger.unwrap_or_default();
            SourceSettings::Genicam {
                camera: producer::genicam::CameraSpec {
                    id: Some(c.genicam_id.trim().to_string()).filter(|id| !id.is_empty()),
                },
                settings: producer::genicam::CameraSettings {
                    exposure_us: c.genicam_exposure_us,
                    gain_db: c.genicam_gain_db,
                    fps: trigger.rate_fps(c.fps),
                    pixel_format: c.genicam_pixel_format,
                    roi: c.genicam_roi,
                    trigger,
                },
                log: None,
            }
        }
    };
    ProducerSettings {
        instance: instance.to_string(),
        source,
        fps: (c.fps > 0.0 && matches!(c.source, CameraSource::Simulated | CameraSource::Replay))
            .then_some(c.fps),
        max_frames: None,
        first_frame_id,
    }
}

/// The simulated camera following the rig, as `[camera]` and the campaign make it: the camera
/// and how it follows.
pub(crate) fn rig_camera(
    config: &RunConfig,
) -> (producer::SimulatedConfig, producer::RigFollowConfig) {
    let c = &config.camera;
    let follow = producer::RigFollowConfig {
        mm_per_px: c.mm_per_px,
        strip_mm_per_px: c.strip_mm_per_px,
        envelope: producer::RigEnvelope {
            // The rig overshoots a level by a little: the camera covers a margin beyond it.
            max_stretch: config.max_stretch() * (1.0 + STRETCH_MARGIN),
            ..producer::RigEnvelope::default()
        },
    };
    (simulated_camera(c), follow)
}

/// The simulated camera of `[camera]`: `dicstream producer`'s defaults (pattern, noise, the
/// fast renderer) for what it does not set.
fn simulated_camera(c: &CameraSection) -> producer::SimulatedConfig {
    let mut camera = producer::SimulatedConfig::new(c.width_px, c.height_px);
    camera.speckle.size_px = c.speckle_size_px;
    camera.speckle.seed = c.seed;
    camera.camera = producer::CameraModel {
        seed: c.seed,
        ..producer::CameraModel::with_bit_depth(c.bit_depth)
    };
    camera.threads = c.threads.max(1);
    camera
}

/// The correlator's settings, its state in the results (refused as the run's validation
/// refuses them).
pub fn correlator_settings(
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
) -> anyhow::Result<correlator::process::ProcessConfig> {
    Ok(correlator::process::ProcessConfig {
        state_dir: Some(results.correlator_state()),
        ..correlator::process::ProcessConfig::new(instance, config.correlator_settings()?)
    })
}

/// The identifier's models, its routes (the field route with the camera's view and the
/// cruciform), its output and journal in the results.
pub fn identifier_settings(
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
) -> identifier::process::ProcessConfig {
    identifier::process::ProcessConfig {
        instance: instance.to_string(),
        output_json: results.identification_json(),
        journal: Some(results.journal()),
        max_fields: None,
        idle_timeout: None,
        online: identifier::online::OnlineConfig {
            models: config.identifier.models.0.clone(),
            ..Default::default()
        },
        routes: config.identifier_routes(),
        field: config
            .identifier_routes()
            .runs(wire::identification::ReportRoute::Field)
            .then(|| config.field_route_settings()),
        states_csv: config
            .identifier_routes()
            .runs(wire::identification::ReportRoute::Field)
            .then(|| results.states_csv()),
    }
}

/// A rig following the machine's CSV log of `[rig.csv]`, its counts kept beside the results.
pub fn csv_follow_settings(
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
) -> rig::csv_follow::process::FollowOptions {
    use rig::csv_follow::ColumnSpec;
    let v = &config.rig.csv;
    let column = |name: &str| (!name.trim().is_empty()).then(|| ColumnSpec::new(name, None));
    rig::csv_follow::process::FollowOptions {
        instance: instance.to_string(),
        path: v.file.clone(),
        columns: rig::csv_follow::CsvColumns {
            time: ColumnSpec::new(&v.time_column, None),
            force: [
                column(&v.force_x_column),
                column(&v.force_y_column),
                column(&v.force_z_column),
            ],
            displacement: [
                column(&v.displacement_x_column),
                column(&v.displacement_y_column),
                column(&v.displacement_z_column),
            ],
            time_unit: v.time_unit,
            force_unit: v.force_unit,
            displacement_unit: v.displacement_unit,
            delimiter: v.delimiter.as_char(),
        },
        offset_s: v.offset_s,
        sections_mm2: [v.section_x_mm2, v.section_y_mm2],
        poll: std::time::Duration::from_millis(rig::csv_follow::process::DEFAULT_POLL_MS),
        idle_timeout: (v.idle_timeout_s > 0.0)
            .then(|| std::time::Duration::from_secs_f64(v.idle_timeout_s)),
        counts_json: Some(results.machine_csv_json()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn results() -> ResultsDir {
        ResultsDir {
            root: PathBuf::from("/results/run"),
        }
    }

    /// The settings file of a child and its settings' JSON (a rig's under its source).
    fn settings(role: Role, config: &RunConfig) -> (PathBuf, serde_json::Value) {
        let launch = child_launch(role, config, "bench_7", &results(), 0).unwrap();
        let json: serde_json::Value = serde_json::from_str(&launch.json).unwrap();
        match role {
            Role::Rig => {
                let source = config.rig.source.name();
                assert_eq!(json["source"], source.replace('-', "_"), "{json}");
                (launch.file, json["settings"].clone())
            }
            _ => (launch.file, json),
        }
    }

    /// The default configuration with a link the run starts.
    fn with_link() -> RunConfig {
        RunConfig {
            link: Some(link::LinkSection {
                start_with_run: true,
                ..link::LinkSection::default()
            }),
            ..RunConfig::default()
        }
    }

    #[test]
    fn every_child_runs_on_the_instance() {
        for role in Role::ALL {
            let (file, json) = settings(role, &with_link());
            assert_eq!(json["instance"], "bench_7", "{role:?}");
            assert_eq!(
                file,
                PathBuf::from(format!("/results/run/settings/{}.json", role.name()))
            );
        }
    }

    #[test]
    fn the_link_keeps_its_counts_in_the_results_and_none_is_started_without_link() {
        let (_, json) = settings(Role::Link, &with_link());
        assert_eq!(
            json["counts_json"], "/results/run/link_counts.json",
            "{json}"
        );
        assert_eq!(json["link"]["start_with_run"], true, "{json}");
        let error = child_launch(Role::Link, &RunConfig::default(), "i", &results(), 0);
        assert!(error.is_err());
    }

    #[test]
    fn a_settings_file_is_written_and_named_on_the_command_line() {
        let dir = std::env::temp_dir().join(format!("child_launch_{}", std::process::id()));
        let results = ResultsDir { root: dir.clone() };
        let launch =
            child_launch(Role::Correlator, &RunConfig::default(), "i", &results, 0).unwrap();
        let args = launch.into_args().unwrap();
        let file = results.settings_file("correlator");
        assert_eq!(args, ["--settings".to_string(), text(&file)]);
        let back: correlator::process::ProcessConfig =
            serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
        assert_eq!(
            back.settings,
            RunConfig::default().correlator_settings().unwrap()
        );
        std::fs::remove_dir_all(&dir).unwrap();
        // A folder that cannot be made is an error naming it.
        let results = ResultsDir {
            root: PathBuf::from("/proc/no_such_run"),
        };
        let launch =
            child_launch(Role::Identifier, &RunConfig::default(), "i", &results, 0).unwrap();
        let error = launch.into_args().unwrap_err().to_string();
        assert!(
            error.starts_with("cannot create /proc/no_such_run/settings"),
            "{error}"
        );
    }

    #[test]
    fn the_rig_runs_the_campaign_on_the_specimen_and_journals_in_the_results() {
        use rig::settings::{RigStart, Speed};
        let mut config = RunConfig::default();
        config.rig.speed = 4.0;
        config.rig.seed = 11;
        config.specimen.law_f = vec![0.5, -0.25];
        let typed = rig_settings(&config, "bench_7", &results()).unwrap();
        let RigStart::Campaign { tests } = &typed.start else {
            panic!("{:?}", typed.start)
        };
        let campaign: Vec<String> = tests
            .iter()
            .map(|t| format!("{}:{}@{}", t.test.name(), t.stretch, t.rate_per_s))
            .collect();
        assert_eq!(campaign, ["uniaxial:3@0.08", "equibiaxial:2@0.04"]);
        assert_eq!(typed.law.as_ref().unwrap().f, [0.5, -0.25]);
        assert_eq!(typed.speed, Speed::Factor(4.0));
        assert_eq!(typed.seed, 11);
        assert_eq!(
            typed.log.as_deref(),
            Some(Path::new("/results/run/rig.csv"))
        );
        assert_eq!(
            typed.state_dir.as_deref(),
            Some(Path::new("/results/run/rig_state"))
        );
        assert!(typed.exit_when_done);
        // The process's options of them: the campaign on the law.
        let options = rig::process::ProcessOptions::from_settings(&typed).unwrap();
        assert_eq!(options.campaign.unwrap().tests().len(), 2);
        let (_, json) = settings(Role::Rig, &config);
        assert_eq!(json["start"]["kind"], "campaign");
        assert_eq!(json["speed"], "4");
    }

    #[test]
    fn a_strain_controlled_test_gives_the_rig_its_strain_test_instead_of_a_campaign() {
        use rig::settings::RigStart;
        let config = RunConfig::from_toml(
            "[[rig.tests]]\nkind = \"biaxial\"\ncontrol = \"strain\"\nratio = 0.5\n\
             stretch = 1.6\nrate_per_s = 0.02\non_interlock = \"stop\"\nstale_s = 0.8\n",
            "t.toml",
        )
        .unwrap();
        config.validate().unwrap();
        let typed = rig_settings(&config, "bench_7", &results()).unwrap();
        let RigStart::Strain { test } = typed.start else {
            panic!("{:?}", typed.start)
        };
        assert_eq!(test.kind, rig::strain::StrainKind::Biaxial);
        assert_eq!(test.ratio, 0.5);
        assert_eq!(test.stretch, 1.6);
        assert_eq!(test.rate_log_per_s, 0.02);
        assert_eq!(test.limits.stale_s, 0.8);
        assert_eq!(test.limits.min_valid_nodes, 16);
        assert_eq!(test.on_interlock, rig::strain::control::OnRestore::Stop);
        let (_, json) = settings(Role::Rig, &config);
        assert_eq!(json["start"]["kind"], "strain");
        assert_eq!(json["start"]["test"]["kind"], "biaxial");
        assert_eq!(json["start"]["test"]["on_interlock"], "stop");
        let back: rig::settings::RigSettings = serde_json::from_value(json).unwrap();
        assert_eq!(back.strain().unwrap().unwrap().0, test);
    }

    #[test]
    fn the_camera_follows_the_rig_beyond_the_largest_stretch_from_the_given_frame_id() {
        use producer::settings::SourceSettings;
        let mut config = RunConfig::default();
        config.camera.threads = 3;
        config.camera.width_px = 640;
        config.camera.bit_depth = 12;
        let typed = producer_settings(&config, "bench_7", &results(), 1234);
        let SourceSettings::FollowRig { camera, follow } = typed.source else {
            panic!("{:?}", typed.source)
        };
        assert_eq!(camera.threads, 3);
        assert_eq!(camera.width, 640);
        // The simulated camera's own defaults for the rest, as `dicstream producer` has them.
        assert_eq!(
            camera.camera,
            producer::CameraModel {
                seed: config.camera.seed,
                ..producer::CameraModel::with_bit_depth(12)
            }
        );
        assert_eq!(typed.first_frame_id, 1234);
        assert_eq!(typed.fps, Some(10.0));
        let max_stretch = follow.envelope.max_stretch;
        assert!((max_stretch - 3.0 * (1.0 + STRETCH_MARGIN)).abs() < 1e-12);
    }

    #[test]
    fn the_correlator_gets_its_method_threads_and_state_folder() {
        let mut config = RunConfig::default();
        config.correlator.method = "icgn2".parse().unwrap();
        config.correlator.threads = 5;
        config.correlator.zoi_px = 31;
        config.correlator.gradient_correction = false;
        let typed = correlator_settings(&config, "bench_7", &results()).unwrap();
        assert_eq!(typed.settings.method, correlator::Method::Icgn2);
        assert_eq!(typed.settings.threads, 5);
        assert_eq!(typed.settings.zoi_px, 31);
        assert!(!typed.settings.gradient_correction);
        assert_eq!(typed.settings.reference.kind(), config.correlator.reference);
        assert_eq!(typed.settings.guess, config.correlator.guess);
        assert_eq!(
            typed.state_dir.as_deref(),
            Some(Path::new("/results/run/correlator_state"))
        );
        // As the file says it: units in the names, names for the enums.
        let (_, json) = settings(Role::Correlator, &config);
        assert_eq!(json["settings"]["method"], "icgn2");
        assert_eq!(json["settings"]["zoi_px"], 31);
        assert_eq!(json["status_interval_s"], 1.0);
        assert_eq!(json["idle_timeout_s"], serde_json::Value::Null);
        // Settings the run's validation refuses are refused here too.
        config.correlator.zoi_px = 4;
        assert!(child_launch(Role::Correlator, &config, "i", &results(), 0).is_err());
    }

    #[test]
    fn the_identifier_writes_and_journals_in_the_results() {
        let mut config = RunConfig::default();
        config.identifier.models = "yeoh,gent".parse().unwrap();
        let typed = identifier_settings(&config, "bench_7", &results());
        assert_eq!(
            typed.output_json,
            Path::new("/results/run/identification.json")
        );
        assert_eq!(
            typed.journal.as_deref(),
            Some(Path::new("/results/run/identification_points.csv"))
        );
        assert_eq!(typed.online.models, config.identifier.models.0);
        let (_, json) = settings(Role::Identifier, &config);
        assert_eq!(
            json["online"]["models"],
            serde_json::json!(["yeoh", "gent"])
        );
    }

    #[test]
    fn only_the_camera_depends_on_the_first_frame_id() {
        let config = with_link();
        for role in Role::ALL {
            let launch = |first| {
                format!(
                    "{:?}",
                    child_launch(role, &config, "bench_7", &results(), first).unwrap()
                )
            };
            assert_eq!(launch(0) == launch(99), role != Role::Producer, "{role:?}");
        }
    }

    #[test]
    fn a_csv_follow_rig_gets_its_columns_units_and_offset() {
        let mut config = RunConfig::default();
        config.rig.source = "csv-follow".parse().unwrap();
        let v = &mut config.rig.csv;
        v.file = "/lab/test.csv".into();
        v.time_column = "Time".into();
        v.force_x_column = "Fx".into();
        v.force_unit = Some("kN".parse().unwrap());
        v.offset_s = -0.5;
        v.section_x_mm2 = 40.0;
        let typed = csv_follow_settings(&config, "bench_7", &results());
        assert_eq!(typed.path, Path::new("/lab/test.csv"));
        assert_eq!(typed.columns.time.name, "Time");
        assert_eq!(typed.columns.force[0].as_ref().unwrap().name, "Fx");
        assert_eq!(typed.columns.force[1], None);
        assert_eq!(typed.columns.force_unit.unwrap().name(), "kN");
        assert_eq!(typed.offset_s, -0.5);
        assert_eq!(typed.sections_mm2, [40.0, 0.0]);
        assert_eq!(
            typed.counts_json.as_deref(),
            Some(Path::new("/results/run/machine_csv.json"))
        );
        typed.check().unwrap();
        let (_, json) = settings(Role::Rig, &config);
        assert_eq!(json["poll_s"], 0.01);
        assert_eq!(json["columns"]["force_unit"], "kN");
    }

    #[test]
    fn real_cameras_get_their_source_options_and_no_rendering_ones() {
        use producer::settings::SourceSettings;
        let mut config = RunConfig::default();
        config.camera.source = "watch".parse().unwrap();
        config.camera.watch_dir = "/lab/images".into();
        config.camera.watch_from_start = true;
        config.camera.watch_idle_timeout_s = 3.0;
        let watch = producer_settings(&config, "bench_7", &results(), 7);
        assert_eq!(
            watch.source,
            SourceSettings::Watch {
                dir: "/lab/images".into(),
                from_start: true,
                idle_timeout_s: Some(3.0),
                settle_ms: config.camera.watch_settle_ms,
                log: Some("/results/run/watched_frames.csv".into()),
            }
        );
        assert_eq!((watch.first_frame_id, watch.fps), (7, None));
        config.camera.source = "replay".parse().unwrap();
        config.camera.replay_files = "/lab/images/*.tif".into();
        let replay = producer_settings(&config, "bench_7", &results(), 0);
        assert_eq!(
            replay.source,
            SourceSettings::Replay {
                files: "/lab/images/*.tif".into(),
                looping: false
            }
        );
        assert_eq!(replay.fps, Some(10.0));
        config.camera.source = "genicam".parse().unwrap();
        config.camera.genicam_id = "Fake_1".into();
        config.camera.genicam_exposure_us = Some(2000.0);
        config.camera.genicam_gain_db = Some(-1.5);
        config.camera.genicam_pixel_format = Some("Mono12".parse().unwrap());
        config.camera.genicam_roi = Some("0,0,512,512".parse().unwrap());
        config.camera.genicam_trigger = Some("software".parse().unwrap());
        let genicam = producer_settings(&config, "bench_7", &results(), 0);
        let SourceSettings::Genicam {
            camera, settings, ..
        } = genicam.source
        else {
            panic!("{:?}", genicam.source)
        };
        assert_eq!(camera.to_string(), "genicam:Fake_1");
        assert_eq!(settings.exposure_us, Some(2000.0));
        assert_eq!(settings.gain_db, Some(-1.5));
        assert_eq!(settings.fps, Some(10.0));
        assert_eq!(settings.pixel_format.unwrap().to_string(), "Mono12");
        assert_eq!(settings.roi.unwrap().to_string(), "0,0,512,512");
        assert_eq!(settings.trigger, producer::genicam::Trigger::Software);
        assert_eq!(genicam.fps, None);
    }
}
