//! How each child process of a run is started (`dicstream <role> ...`), from the run's
//! configuration alone: pure, so a restart gets the same settings but for where the camera's
//! frame ids start. The rig, the correlator and the identifier get their process's settings,
//! typed, as a JSON file (`--settings FILE`, the struct their command line's flags make too);
//! the camera still gets flags.

use crate::children::Role;
use crate::config::{CameraSection, CameraSource, RigSource, RunConfig};
use crate::results::ResultsDir;
use std::path::{Path, PathBuf};

/// Relative margin of the camera's stretch envelope beyond the campaign's largest stretch.
const STRETCH_MARGIN: f64 = 0.05;

/// What a child is started with.
#[derive(Clone, Debug)]
pub enum ChildLaunch {
    /// Its process's settings: written as JSON to `file`, passed as `--settings FILE`.
    Settings { file: PathBuf, json: String },
    /// Flags of its subcommand.
    Args(Vec<String>),
}

impl ChildLaunch {
    /// The settings of `settings` in the results' settings file of `role`.
    fn settings(role: Role, results: &ResultsDir, settings: &impl serde::Serialize) -> ChildLaunch {
        ChildLaunch::Settings {
            file: results.settings_file(role.name()),
            json: serde_json::to_string_pretty(settings)
                .expect("process settings serialise to JSON"),
        }
    }

    /// The arguments after the role (writing the settings file first, if any).
    pub fn into_args(self) -> Result<Vec<String>, wire::files::FileError> {
        match self {
            ChildLaunch::Args(args) => Ok(args),
            ChildLaunch::Settings { file, json } => {
                if let Some(folder) = file.parent() {
                    std::fs::create_dir_all(folder).map_err(|reason| wire::files::FileError {
                        path: folder.to_path_buf(),
                        what: "create",
                        reason,
                    })?;
                }
                wire::files::write_atomic(&file, json.as_bytes())?;
                Ok(vec!["--settings".into(), text(&file)])
            }
        }
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
    let flags = |more: Vec<String>| {
        let mut args = vec!["--instance".to_string(), instance.to_string()];
        args.extend(more);
        ChildLaunch::Args(args)
    };
    Ok(match role {
        Role::Rig if config.rig.source == RigSource::CsvFollow => {
            flags(csv_follow_args(config, results))
        }
        Role::Producer if config.camera.source != CameraSource::Simulated => {
            flags(real_camera_args(config, results, first_frame_id))
        }
        Role::Rig => {
            ChildLaunch::settings(role, results, &rig_settings(config, instance, results)?)
        }
        Role::Producer => flags(simulated_camera_args(config, first_frame_id)),
        Role::Correlator => ChildLaunch::settings(
            role,
            results,
            &correlator_settings(config, instance, results)?,
        ),
        Role::Identifier => ChildLaunch::settings(
            role,
            results,
            &identifier_settings(config, instance, results),
        ),
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
        ..RigSettings::default()
    })
}

/// The simulated camera, following the rig.
fn simulated_camera_args(config: &RunConfig, first_frame_id: u64) -> Vec<String> {
    let c = &config.camera;
    vec![
        "--follow-rig".into(),
        "--fps".into(),
        c.fps.to_string(),
        "--width".into(),
        c.width_px.to_string(),
        "--height".into(),
        c.height_px.to_string(),
        "--bit-depth".into(),
        c.bit_depth.to_string(),
        "--mm-per-px".into(),
        c.mm_per_px.to_string(),
        "--max-stretch".into(),
        // The rig overshoots a level by a little: the camera covers a margin beyond it.
        (config.max_stretch() * (1.0 + STRETCH_MARGIN)).to_string(),
        "--speckle-size-px".into(),
        c.speckle_size_px.to_string(),
        "--seed".into(),
        c.seed.to_string(),
        "--threads".into(),
        c.threads.to_string(),
        "--first-frame-id".into(),
        first_frame_id.to_string(),
    ]
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

/// The identifier's models, its output and journal in the results.
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
    }
}

/// `rig --follow-csv FILE ...`: the machine's log of `[rig.csv]`, its counts kept beside the
/// results.
fn csv_follow_args(config: &RunConfig, results: &ResultsDir) -> Vec<String> {
    let v = &config.rig.csv;
    let mut args = vec!["--follow-csv".to_string(), text(&v.file)];
    let mut named = |flag: &str, value: &str| {
        if !value.trim().is_empty() {
            args.push(flag.to_string());
            args.push(value.to_string());
        }
    };
    named("--time-column", &v.time_column);
    named("--force-x-column", &v.force_x_column);
    named("--force-y-column", &v.force_y_column);
    named("--force-z-column", &v.force_z_column);
    named("--displacement-x-column", &v.displacement_x_column);
    named("--displacement-y-column", &v.displacement_y_column);
    named("--displacement-z-column", &v.displacement_z_column);
    let unit = |u: Option<&str>| u.unwrap_or("").to_string();
    named("--time-unit", &unit(v.time_unit.map(|u| u.name())));
    named("--force-unit", &unit(v.force_unit.map(|u| u.name())));
    named(
        "--displacement-unit",
        &unit(v.displacement_unit.map(|u| u.name())),
    );
    named("--delimiter", v.delimiter.name());
    args.extend([
        format!("--offset-s={}", v.offset_s),
        "--section-x-mm2".into(),
        v.section_x_mm2.to_string(),
        "--section-y-mm2".into(),
        v.section_y_mm2.to_string(),
        "--idle-timeout-s".into(),
        v.idle_timeout_s.to_string(),
        "--counts-json".into(),
        text(&results.machine_csv_json()),
    ]);
    args
}

/// The producer's options for a watched folder, a replay or a GenICam camera.
fn real_camera_args(config: &RunConfig, results: &ResultsDir, first_frame_id: u64) -> Vec<String> {
    let c = &config.camera;
    let mut args = match c.source {
        CameraSource::Watch => watch_args(c, results),
        CameraSource::Replay => vec![
            "--replay".into(),
            c.replay_files.clone(),
            "--fps".into(),
            c.fps.to_string(),
        ],
        CameraSource::Genicam | CameraSource::Simulated => genicam_args(c),
    };
    args.extend(["--first-frame-id".into(), first_frame_id.to_string()]);
    args
}

/// A watched folder, which file each frame is written beside the results.
fn watch_args(c: &CameraSection, results: &ResultsDir) -> Vec<String> {
    let mut args = vec![
        "--watch".to_string(),
        text(&c.watch_dir),
        "--settle-ms".into(),
        c.watch_settle_ms.to_string(),
        "--log".into(),
        text(&results.path("watched_frames.csv")),
    ];
    if c.watch_from_start {
        args.push("--from-start".into());
    }
    if c.watch_idle_timeout_s > 0.0 {
        args.extend([
            "--idle-timeout-s".into(),
            c.watch_idle_timeout_s.to_string(),
        ]);
    }
    args
}

/// A GenICam camera (the first one, or the one named) with the settings given.
fn genicam_args(c: &CameraSection) -> Vec<String> {
    let mut args = vec![
        "--camera".to_string(),
        match c.genicam_id.trim() {
            "" => "genicam".to_string(),
            id => format!("genicam:{id}"),
        },
        "--fps".into(),
        c.fps.to_string(),
    ];
    if let Some(us) = c.genicam_exposure_us {
        args.extend(["--exposure-us".into(), us.to_string()]);
    }
    if let Some(db) = c.genicam_gain_db {
        args.push(format!("--gain-db={db}"));
    }
    for (flag, value) in [
        (
            "--pixel-format",
            c.genicam_pixel_format.map(|f| f.to_string()),
        ),
        ("--roi", c.genicam_roi.map(|r| r.to_string())),
        ("--trigger", c.genicam_trigger.map(|t| t.to_string())),
    ] {
        if let Some(value) = value {
            args.extend([flag.to_string(), value]);
        }
    }
    args
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// The value after `flag` (exactly one occurrence).
    fn value<'a>(args: &'a [String], flag: &str) -> &'a str {
        let at: Vec<usize> = (0..args.len()).filter(|&i| args[i] == flag).collect();
        assert_eq!(at.len(), 1, "{flag} in {args:?}");
        &args[at[0] + 1]
    }

    fn results() -> ResultsDir {
        ResultsDir {
            root: PathBuf::from("/results/run"),
        }
    }

    /// The flags of a child started with flags.
    fn args(role: Role, config: &RunConfig, first_frame_id: u64) -> Vec<String> {
        match child_launch(role, config, "bench_7", &results(), first_frame_id).unwrap() {
            ChildLaunch::Args(args) => args,
            settings => panic!("{role:?} started with {settings:?}"),
        }
    }

    /// The JSON settings of a child started with a settings file, and the file.
    fn settings(role: Role, config: &RunConfig) -> (PathBuf, serde_json::Value) {
        match child_launch(role, config, "bench_7", &results(), 0).unwrap() {
            ChildLaunch::Settings { file, json } => (file, serde_json::from_str(&json).unwrap()),
            args => panic!("{role:?} started with {args:?}"),
        }
    }

    #[test]
    fn every_child_runs_on_the_instance() {
        let args = args(Role::Producer, &RunConfig::default(), 0);
        assert_eq!(args[..2], ["--instance", "bench_7"]);
        for role in [Role::Rig, Role::Correlator, Role::Identifier] {
            let (file, json) = settings(role, &RunConfig::default());
            assert_eq!(json["instance"], "bench_7", "{role:?}");
            assert_eq!(
                file,
                PathBuf::from(format!("/results/run/settings/{}.json", role.name()))
            );
        }
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
        let mut config = RunConfig::default();
        config.camera.threads = 3;
        config.camera.width_px = 640;
        let args = args(Role::Producer, &config, 1234);
        assert!(args.contains(&"--follow-rig".to_string()));
        assert_eq!(value(&args, "--threads"), "3");
        assert_eq!(value(&args, "--width"), "640");
        assert_eq!(value(&args, "--first-frame-id"), "1234");
        let max_stretch: f64 = value(&args, "--max-stretch").parse().unwrap();
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
        let config = RunConfig::default();
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
        let args = args(Role::Rig, &config, 0);
        assert_eq!(value(&args, "--follow-csv"), "/lab/test.csv");
        assert_eq!(value(&args, "--time-column"), "Time");
        assert_eq!(value(&args, "--force-x-column"), "Fx");
        assert_eq!(value(&args, "--force-unit"), "kN");
        assert!(!args.contains(&"--force-y-column".to_string()), "{args:?}");
        assert!(args.contains(&"--offset-s=-0.5".to_string()), "{args:?}");
        assert_eq!(value(&args, "--section-x-mm2"), "40");
        assert_eq!(
            value(&args, "--counts-json"),
            "/results/run/machine_csv.json"
        );
        assert!(!args.contains(&"--campaign".to_string()));
    }

    #[test]
    fn real_cameras_get_their_source_options_and_no_rendering_ones() {
        let mut config = RunConfig::default();
        config.camera.source = "watch".parse().unwrap();
        config.camera.watch_dir = "/lab/images".into();
        config.camera.watch_from_start = true;
        config.camera.watch_idle_timeout_s = 3.0;
        let watch = args(Role::Producer, &config, 7);
        assert_eq!(value(&watch, "--watch"), "/lab/images");
        assert_eq!(value(&watch, "--idle-timeout-s"), "3");
        assert_eq!(value(&watch, "--log"), "/results/run/watched_frames.csv");
        assert_eq!(value(&watch, "--first-frame-id"), "7");
        assert!(watch.contains(&"--from-start".to_string()));
        for flag in ["--follow-rig", "--fps", "--max-stretch", "--width"] {
            assert!(!watch.contains(&flag.to_string()), "{flag} in {watch:?}");
        }
        config.camera.source = "replay".parse().unwrap();
        config.camera.replay_files = "/lab/images/*.tif".into();
        let replay = args(Role::Producer, &config, 0);
        assert_eq!(value(&replay, "--replay"), "/lab/images/*.tif");
        assert_eq!(value(&replay, "--fps"), "10");
        config.camera.source = "genicam".parse().unwrap();
        config.camera.genicam_id = "Fake_1".into();
        config.camera.genicam_exposure_us = Some(2000.0);
        config.camera.genicam_gain_db = Some(-1.5);
        config.camera.genicam_pixel_format = Some("Mono12".parse().unwrap());
        config.camera.genicam_roi = Some("0,0,512,512".parse().unwrap());
        config.camera.genicam_trigger = Some("software".parse().unwrap());
        let genicam = args(Role::Producer, &config, 0);
        assert_eq!(value(&genicam, "--camera"), "genicam:Fake_1");
        assert_eq!(value(&genicam, "--exposure-us"), "2000");
        assert!(genicam.contains(&"--gain-db=-1.5".to_string()));
        assert_eq!(value(&genicam, "--pixel-format"), "Mono12");
        assert_eq!(value(&genicam, "--roi"), "0,0,512,512");
        assert_eq!(value(&genicam, "--trigger"), "software");
    }
}
