//! The configuration's refusals and round trips.

use super::*;

#[test]
fn defaults_round_trip_and_validate() {
    RunConfig::default().validate().unwrap();
    let round = RunConfig::from_toml(&RunConfig::default().to_toml(), "round").unwrap();
    assert_eq!(round, RunConfig::default());
    assert_eq!(
        RunConfig::default().campaign_spec(),
        "uniaxial:3@0.08,equibiaxial:2@0.04"
    );
}

#[test]
fn the_example_configs_are_valid_strain_controlled_runs() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/configs");
    for (name, ratio) in [
        ("strain_equibiaxial.toml", 1.0),
        ("strain_biaxial_rho05.toml", 0.5),
    ] {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        let config = RunConfig::from_toml(&text, name).unwrap();
        config.validate().unwrap();
        let test = config.strain_test().unwrap().expect(name);
        assert_eq!((test.ratio, test.stretch), (ratio, 1.8), "{name}");
    }
}

#[test]
fn strain_controlled_tests_are_checked_and_the_default_is_unchanged() {
    // Displacement control stays the default, and its config file does not change.
    let d = RunConfig::default();
    assert!(d.strain_test().unwrap().is_none());
    assert!(!d.to_toml().contains("\ncontrol ="), "{}", d.to_toml());
    let strain = |body: &str| {
        RunConfig::from_toml(&format!("[[rig.tests]]\n{body}"), "t.toml")
            .and_then(|config| config.validate())
    };
    strain("kind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.8\nrate_per_s = 0.02\n")
        .unwrap();
    strain("kind = \"pure_shear\"\ncontrol = \"strain\"\nstretch = 1.8\nrate_per_s = 0.02\n")
        .unwrap();
    let config = RunConfig::from_toml(
        "[[rig.tests]]\nkind = \"biaxial\"\ncontrol = \"strain\"\nratio = 0.5\nstretch = 1.5\n\
         rate_per_s = 0.02\nmin_valid_nodes = 50\n",
        "t.toml",
    )
    .unwrap();
    let test = config.strain_test().unwrap().unwrap();
    assert_eq!((test.ratio, test.stretch), (0.5, 1.5));
    assert_eq!(test.limits.min_valid_nodes, 50);
    assert_eq!(test.limits.stale_s, rig::strain::interlock::DEFAULT_STALE_S);
    // Round trip through the results' config.toml.
    let round = RunConfig::from_toml(&config.to_toml(), "round").unwrap();
    assert_eq!(round, config);
    let refused = |body: &str, expected: &str| {
        let error = format!("{:#}", strain(body).unwrap_err());
        assert!(error.contains(expected), "{body}: {error}");
    };
    refused(
        "kind = \"uniaxial\"\ncontrol = \"strain\"\nratio = 0.5\nstretch = 1.5\nrate_per_s = 0.02\n",
        "only a biaxial",
    );
    refused(
        "kind = \"biaxial\"\ncontrol = \"strain\"\nratio = nan\nstretch = 1.5\nrate_per_s = 0.02\n",
        "ratio NaN",
    );
    refused(
        "kind = \"biaxial\"\ncontrol = \"strain\"\nstretch = 1.5\nrate_per_s = 0.02\n",
        "needs its ratio",
    );
    refused(
        "kind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.0\nrate_per_s = 0.02\n",
        "stretch 1",
    );
    refused(
        "kind = \"equibiaxial\"\ncontrol = \"force\"\nstretch = 1.5\nrate_per_s = 0.02\n",
        "expected displacement or strain",
    );
    refused(
        "kind = \"equibiaxial\"\nratio = 1.0\nstretch = 1.5\nrate_per_s = 0.02\n",
        "ratio applies to control = \"strain\" only",
    );
    refused(
        "kind = \"pure_shear\"\nstretch = 1.5\nrate_per_s = 0.02\n",
        "set control = \"strain\"",
    );
    refused(
        "kind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.5\nrate_per_s = 0.02\n\
         on_interlock = \"pause\"\n",
        "resume or stop",
    );
    refused(
        "kind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.5\nrate_per_s = 0.02\n\
         [[rig.tests]]\nkind = \"uniaxial\"\nstretch = 2.0\nrate_per_s = 0.08\n",
        "runs alone",
    );
    let csv = RunConfig::from_toml(
        "[camera]\nsource = \"watch\"\nwatch_dir = \"/tmp/x\"\n[rig]\nsource = \"csv-follow\"\n\
         [rig.csv]\nfile = \"m.csv\"\ntime_column = \"t\"\nforce_x_column = \"F\"\n\
         [[rig.tests]]\nkind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.5\n\
         rate_per_s = 0.02\n",
        "t.toml",
    )
    .unwrap();
    let error = format!("{:#}", csv.strain_test().unwrap_err());
    assert!(error.contains("csv-follow"), "{error}");
}

#[test]
fn bad_configurations_are_refused_with_the_key_named() {
    let unknown = RunConfig::from_toml("[camera]\nwidht_px = 512\n", "my.toml").unwrap_err();
    let unknown = format!("{unknown:#}");
    assert!(
        unknown.contains("my.toml") && unknown.contains("widht_px"),
        "{unknown}"
    );
    // A word that names no choice is refused as the file is read, the rest by `validate`.
    let refuse = |toml: &str, expected: &str| {
        let checked = RunConfig::from_toml(toml, "t.toml").and_then(|config| config.validate());
        let error = format!("{:#}", checked.unwrap_err());
        assert!(error.contains(expected), "{toml}: {error}");
    };
    refuse(
        "[camera]\nwidth_px = 128\nheight_px = 128\n[correlator]\nzoi_px = 256\n",
        "larger than the ROI",
    );
    refuse(
        "[correlator]\nmethod = \"correli\"\nzoi_px = 48\n",
        "power of two",
    );
    refuse("[correlator]\nmethod = \"icgn1\"\nzoi_px = 8\n", "9 to 256");
    refuse("[correlator]\nmethod = \"icgn3\"\n", "method");
    refuse(
        "[[rig.tests]]\nkind = \"uniaxial\"\nstretch = 7.0\nrate_per_s = 0.08\n",
        "stroke",
    );
    refuse(
        "[[rig.tests]]\nkind = \"equibiaxial\"\nstretch = 1.5\nrate_per_s = 50.0\n",
        "rate",
    );
    refuse(
        "[[rig.tests]]\nkind = \"shear\"\nstretch = 1.5\nrate_per_s = 0.1\n",
        "kind \"shear\": expected uniaxial, equibiaxial, pure_shear or biaxial",
    );
    refuse("[rig]\ntests = []\n", "at least one");
    refuse("[rig]\nspeed = 1000.0\n", "speed");
    refuse("[camera]\nfps = -1.0\n", "fps");
    refuse("[camera]\nbit_depth = 9\n", "bit_depth");
    refuse("[specimen]\nlaw_f = []\n", "law_f");
    refuse("[identifier]\nmodels = \"nope\"\n", "models");
    refuse("[correlator]\nreference = \"sometimes\"\n", "reference");
    refuse("[camera]\nsource = \"webcam\"\n", "source");
    refuse("[camera]\nsource = \"watch\"\n", "watch_dir");
    refuse("[camera]\nsource = \"replay\"\n", "replay_files");
    refuse(
        "[camera]\nsource = \"genicam\"\ngenicam_pixel_format = \"RGB8\"\n",
        "Mono16",
    );
    refuse("[camera]\ngenicam_roi = \"1,2,3\"\n", "x,y,w,h");
    refuse("[rig]\nsource = \"csv\"\n", "csv-follow");
    refuse("[rig]\nsource = \"csv-follow\"\n", "simulated camera");
    let real =
        "[camera]\nsource = \"watch\"\nwatch_dir = \"/tmp/x\"\n[rig]\nsource = \"csv-follow\"\n";
    refuse(real, "file is empty");
    refuse(
        &format!("{real}[rig.csv]\nfile = \"m.csv\"\ntime_column = \"t\"\n"),
        "no force column",
    );
    refuse(
        &format!(
            "{real}[rig.csv]\nfile = \"m.csv\"\ntime_column = \"t\"\nforce_x_column = \"F\"\n\
             force_unit = \"lbf\"\n"
        ),
        "force_unit",
    );
    let ok = RunConfig::from_toml(
        &format!(
            "{real}[rig.csv]\nfile = \"m.csv\"\ntime_column = \"t\"\nforce_x_column = \"F\"\n"
        ),
        "ok.toml",
    )
    .unwrap();
    ok.validate().unwrap();
    assert_eq!(ok.camera.source, CameraSource::Watch);
    assert_eq!(ok.rig.source, RigSource::CsvFollow);
    let round = RunConfig::from_toml(&ok.to_toml(), "round").unwrap();
    assert_eq!(round, ok);
}

/// A bare word as a value (the commonest slip in a hand-edited file) is named with what to
/// write instead, not only as the parser's "invalid boolean".
#[test]
fn a_bare_word_value_is_named_with_the_fix() {
    let error = RunConfig::from_toml("[camera]\nfps = ten\n", "run.toml").unwrap_err();
    let text = format!("{error:#}");
    assert!(text.starts_with("run.toml: "), "{text}");
    assert!(text.contains("line 2"), "{text}");
    assert!(
        text.contains("`ten` is not a TOML value: numbers are written in digits"),
        "{text}"
    );
    // Other errors keep the parser's own words.
    let error = RunConfig::from_toml("[camera]\nfps = \"ten\"\n", "run.toml").unwrap_err();
    let text = format!("{error:#}");
    assert!(!text.contains("not a TOML value"), "{text}");
    assert!(text.contains("run.toml"), "{text}");
}

/// `[correlator.region]`: read typed, unknown keys and bad shapes refused naming the key, and
/// the region passed to the correlator with its mask's path made absolute.
#[test]
fn the_region_is_read_checked_and_passed_on() {
    let config = RunConfig::from_toml(
        "[correlator.region]\nroi = \"centred-pow2\"\npolygons = [\"100,100 900,100 500,900\"]\n",
        "t.toml",
    )
    .unwrap();
    config.validate().unwrap();
    let settings = config.correlator_settings().unwrap();
    assert_eq!(settings.region.roi, correlator::RoiChoice::CentredPow2);
    assert_eq!(
        settings.region.polygons[0].to_string(),
        "100,100 900,100 500,900"
    );
    let round = RunConfig::from_toml(&config.to_toml(), "round").unwrap();
    assert_eq!(round, config);
    let refuse = |toml: &str, expected: &str| {
        let checked = RunConfig::from_toml(toml, "t.toml").and_then(|config| config.validate());
        let error = format!("{:#}", checked.unwrap_err());
        assert!(error.contains(expected), "{toml}: {error}");
    };
    refuse("[correlator.region]\nrio = \"margin\"\n", "rio");
    refuse("[correlator.region]\nroi = \"whole\"\n", "centred-pow2");
    refuse(
        "[correlator.region]\npolygons = [\"1,1 2,2\"]\n",
        "[correlator.region] polygons",
    );
    refuse(
        "[correlator.region]\npolygons = [\"10,10 2000,10 10,500\"]\n",
        "outside the 1024x1024 px image",
    );
    refuse(
        "[correlator.region]\nmask = \"no_such_mask.png\"\n",
        "[correlator.region] mask",
    );
    // A relative mask is the run's folder's: the correlator gets it absolute.
    let dir = std::env::temp_dir().join(format!("region_mask_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mask = dir.join("mask.png");
    image::GrayImage::from_pixel(1024, 1024, image::Luma([1]))
        .save(&mask)
        .unwrap();
    let config = RunConfig::from_toml(
        &format!("[correlator.region]\nmask = {:?}\n", mask.to_str().unwrap()),
        "t.toml",
    )
    .unwrap();
    config.validate().unwrap();
    assert!(config
        .correlator_settings()
        .unwrap()
        .region
        .mask
        .unwrap()
        .is_absolute());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `[correlator] gauges` and `control_gauge`: read typed, passed to the correlator and the
/// recorder, bad ones refused naming the key and the gauge.
#[test]
fn gauges_are_read_checked_and_passed_on() {
    let config = RunConfig::from_toml(
        "[correlator]\ngauges = [\"mid=rect:400,400,224,224\", \"arm=extensometer:100,512 300,512\"]\ncontrol_gauge = \"mid\"\n",
        "t.toml",
    )
    .unwrap();
    config.validate().unwrap();
    let settings = config.correlator_settings().unwrap();
    assert_eq!(settings.gauges.len(), 2);
    assert_eq!(settings.gauges[1].kind(), "extensometer");
    assert_eq!(
        settings.control_gauge,
        correlator::ControlGauge::Named("mid".into())
    );
    let round = RunConfig::from_toml(&config.to_toml(), "round").unwrap();
    assert_eq!(round, config);
    assert_eq!(
        RunConfig::default()
            .correlator_settings()
            .unwrap()
            .control_gauge,
        correlator::ControlGauge::Centre
    );
    let refuse = |toml: &str, expected: &str| {
        let checked = RunConfig::from_toml(toml, "t.toml").and_then(|config| config.validate());
        let error = format!("{:#}", checked.unwrap_err());
        assert!(error.contains(expected), "{toml}: {error}");
    };
    refuse("[correlator]\ngauges = [\"mid=rect:1,2,3\"]\n", "X,Y,W,H");
    refuse(
        "[correlator]\ngauges = [\"far=rect:1000,1000,100,100\"]\n",
        "outside the 1024x1024 px image",
    );
    refuse(
        "[correlator]\ngauges = [\"a=rect:1,1,50,50\", \"a=rect:60,60,50,50\"]\n",
        "two gauges are named a",
    );
    refuse(
        "[correlator]\ncontrol_gauge = \"nosuch\"\n",
        "control gauge nosuch is not one of the gauges (none is placed)",
    );
    refuse(
        "[correlator]\ngauges = [\"e=extensometer:1,1 50,50\"]\ncontrol_gauge = \"e\"\n",
        "is an extensometer",
    );
}

#[test]
fn a_link_section_is_read_checked_and_written_back() {
    let text = "[link]\nlisten = [\"tcp/10.0.0.1:7447\"]\nuser = \"rig-pc\"\n\
                password_file = \"pw\"\npeers_file = \"peers\"\n\
                services = [{ name = \"rig/state\", direction = \"out\" }]\n";
    let config = RunConfig::from_toml(text, "t.toml").unwrap();
    config.validate().unwrap();
    let link = config.link.as_ref().unwrap();
    assert_eq!(link.plan().unwrap().routes.len(), 1);
    let round = RunConfig::from_toml(&config.to_toml(), "round").unwrap();
    assert_eq!(round, config);
    assert!(RunConfig::default().link.is_none());

    let everywhere = text.replace("10.0.0.1", "0.0.0.0");
    let error = RunConfig::from_toml(&everywhere, "t.toml")
        .and_then(|config| config.validate())
        .unwrap_err();
    assert!(
        error
            .to_string()
            .starts_with("[link] listen: tcp/0.0.0.0:7447 listens on every"),
        "{error}"
    );
}

#[test]
fn a_hosts_part_of_a_split_bench_is_read_and_checked() {
    let config = RunConfig::from_toml(
        "[run]\nprocesses = [\"camera\", \"correlator\", \"identifier\"]\n",
        "b.toml",
    )
    .unwrap();
    config.validate().unwrap();
    assert!(config.is_split());
    assert!(!config.runs(BenchProcess::Rig));
    assert!(config.runs(BenchProcess::Producer));
    assert!(!RunConfig::default().is_split());
    assert!(!config.link_started_by_run());
    for (text, start) in [
        ("[run]\nprocesses = []\n", "[run] processes is empty"),
        (
            "[run]\nprocesses = [\"rig\", \"rig\"]\n",
            "[run] processes: rig is named twice",
        ),
    ] {
        let error = RunConfig::from_toml(text, "t.toml")
            .and_then(|config| config.validate())
            .unwrap_err();
        assert!(error.to_string().starts_with(start), "{error}");
    }
    assert!(RunConfig::from_toml("[run]\nprocesses = [\"link\"]\n", "t.toml").is_err());
}
