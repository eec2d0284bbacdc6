//! Bad command-line input refused at start with a message naming it (issue 11's smaller
//! defects): `rig` refuses what a run's configuration refuses (a law whose coefficients are not
//! finite used to publish NaN positions and never finish) and names a broken program file;
//! `identifier` refuses an output folder that does not exist before it runs (it failed at the
//! end without the path); a missing replay folder is said once, not twice.

use crate::common::dicstream;
use std::process::Command;

fn instance() -> String {
    format!("cli_refusals_{}", std::process::id())
}

/// Exit status 1, the message holds every needle, nothing started.
fn refused(args: &[&str], needles: &[&str]) -> String {
    refused_with(1, args, needles)
}

/// A word that names no choice of a flag is refused by the command line itself: clap's usage
/// error, exit status 2, with the choice's own message.
fn refused_as_usage(args: &[&str], needles: &[&str]) -> String {
    refused_with(2, args, needles)
}

fn refused_with(code: i32, args: &[&str], needles: &[&str]) -> String {
    let output = dicstream(args);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(code), "{args:?}: {stderr}");
    for needle in needles {
        assert!(stderr.contains(needle), "{needle:?} not in {stderr}");
    }
    assert!(!stderr.contains(": ready"), "{stderr}");
    stderr
}

#[test]
fn a_broken_program_file_is_named() {
    let path = std::env::temp_dir().join(format!("cli_refusals_{}.toml", std::process::id()));
    std::fs::write(&path, "bad toml [").unwrap();
    let p = path.to_str().unwrap();
    refused(
        &["rig", "--program", p, "--instance", &instance()],
        &[&format!("program {p}"), "TOML parse error"],
    );
    let _ = std::fs::remove_file(&path);
}

#[test]
fn a_missing_output_folder_is_refused_at_start() {
    refused(
        &[
            "identifier",
            "--output",
            "/nonexistent_dicstream/out.json",
            "--instance",
            &instance(),
        ],
        &["/nonexistent_dicstream/out.json", "does not exist"],
    );
}

#[test]
fn a_missing_replay_folder_is_said_once() {
    let stderr = refused(
        &[
            "producer",
            "--replay",
            "/nonexistent_dicstream",
            "--instance",
            &instance(),
        ],
        &["cannot read /nonexistent_dicstream"],
    );
    assert_eq!(
        stderr.matches("No such file or directory").count(),
        1,
        "{stderr}"
    );
}

#[test]
fn a_law_that_is_not_finite_is_refused_at_start() {
    for (flag, value, needle) in [
        ("--law-f", "nan,1", "--law-f [NaN, 1.0]"),
        ("--law-g", "1,inf", "--law-g [1.0, inf]"),
    ] {
        let output = Command::new(env!("CARGO_BIN_EXE_dicstream"))
            .args([
                "rig",
                "--test",
                "campaign",
                flag,
                value,
                "--speed",
                "max",
                "--exit-when-done",
                "--instance",
                &format!("rig_cli_{}", std::process::id()),
            ])
            .output()
            .expect("run dicstream");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains(needle), "{stderr}");
        assert!(
            stderr.contains("expected one or more finite numbers"),
            "{stderr}"
        );
        assert!(!stderr.contains("rig: ready"), "{stderr}");
    }
}

/// A program beyond the stroke is refused before the rig says it is ready, with the channel as
/// a program names it and the number readable (not 300 digits, not a Rust debug name).
#[test]
fn a_stroke_beyond_the_limit_is_refused_before_ready_and_readable() {
    let path = std::env::temp_dir().join(format!("cli_stroke_{}.toml", std::process::id()));
    std::fs::write(
        &path,
        "[[setup]]\naxis = \"x\"\ncontrol = \"centroid_displacement\"\n[[channel]]\n\
         target = \"x.elongation\"\nsegments = [{ kind = \"ramp\", to = 1e300, rate_per_s = 1.0 }]\n",
    )
    .unwrap();
    let stderr = refused(
        &[
            "rig",
            "--program",
            path.to_str().unwrap(),
            "--instance",
            &instance(),
        ],
        &["stroke", "5e299", "on x.elongation", "beyond the limit 120"],
    );
    assert!(!stderr.contains("Elongation("), "{stderr}");
    assert!(stderr.len() < 300, "{stderr}");
    let stderr = refused(
        &[
            "rig",
            "--test",
            "uniaxial",
            "--stretch",
            "1e300",
            "--instance",
            &instance(),
        ],
        &["--stretch 1e300"],
    );
    assert!(stderr.len() < 200, "{stderr}");
    let _ = std::fs::remove_file(&path);
}

#[test]
fn bad_strain_control_flags_are_refused_naming_why() {
    let i = instance();
    let rig = |extra: &[&str]| {
        let mut args = vec!["rig", "--instance", &i];
        args.extend_from_slice(extra);
        args.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let check = |extra: &[&str], needles: &[&str]| {
        let args = rig(extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refused(&args, needles);
    };
    check(
        &[
            "--control",
            "strain",
            "--kind",
            "uniaxial",
            "--ratio",
            "0.5",
        ],
        &["--control strain", "only a biaxial"],
    );
    check(
        &["--control", "strain", "--kind", "biaxial", "--ratio", "NaN"],
        &["ratio NaN"],
    );
    check(
        &[
            "--control",
            "strain",
            "--kind",
            "equibiaxial",
            "--stretch",
            "1",
        ],
        &["stretch 1"],
    );
    check(&["--control", "strain"], &["needs --kind"]);
    check(
        &["--kind", "biaxial", "--ratio", "0.5"],
        &["add --control strain"],
    );
    let words = |extra: &[&str], needles: &[&str]| {
        let args = rig(extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refused_as_usage(&args, needles);
    };
    words(
        &["--control", "force"],
        &[
            "--control <CONTROL>",
            "control \"force\": expected displacement or strain",
        ],
    );
    check(
        &[
            "--control",
            "strain",
            "--kind",
            "equibiaxial",
            "--test",
            "uniaxial",
        ],
        &["no --program, --test or --campaign"],
    );
    words(
        &[
            "--control",
            "strain",
            "--kind",
            "equibiaxial",
            "--on-interlock",
            "pause",
        ],
        &["on_interlock \"pause\": expected resume or stop"],
    );
    words(
        &["--control", "strain", "--kind", "shear"],
        &["expected uniaxial, equibiaxial"],
    );
    check(
        &[
            "--control",
            "strain",
            "--kind",
            "equibiaxial",
            "--speed",
            "max",
        ],
        &["--speed max is refused"],
    );
}

/// A `[link]` that asks `dicstream run` to start the link, in a binary built without the
/// `link` feature: refused at start, exit 78, naming the key and the feature (a build with the
/// feature starts it: tests/link.rs).
#[cfg(not(feature = "link"))]
#[test]
fn a_link_the_run_should_start_needs_the_link_feature() {
    let dir = std::env::temp_dir().join(format!("cli_refusals_link_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config = dir.join("bench.toml");
    std::fs::write(
        &config,
        "[link]\nconnect = [\"tcp/10.0.0.1:7447\"]\nuser = \"camera-pc\"\n\
         password_file = \"pw\"\nservices = [{ name = \"fields\", direction = \"out\" }]\n\
         start_with_run = true\n",
    )
    .unwrap();
    let out = dir.join("out");
    let stderr = refused_with(
        78,
        &[
            "run",
            "--instance",
            &instance(),
            "--config",
            config.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        &[
            "[link] start_with_run = true",
            "`link` feature",
            "--features link",
        ],
    );
    assert!(!out.exists(), "nothing started: {stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
