//! `dicstream rig` refuses what a run's configuration refuses, before it starts: a law whose
//! coefficients are not finite (it used to publish NaN positions and never finish).

use std::process::Command;

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
