//! A build without the `genicam` feature (the default): `dicstream cameras` and `producer
//! --camera` say the build lacks it and how to get it, and fail; the options still parse.

#![cfg(not(feature = "genicam"))]

use std::process::Command;

const DICSTREAM: &str = env!("CARGO_BIN_EXE_dicstream");

fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(DICSTREAM)
        .args(args)
        .output()
        .expect("dicstream");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn cameras_and_producer_camera_say_the_build_lacks_genicam() {
    for args in [
        &["cameras"][..],
        &["cameras", "--json"],
        &[
            "producer",
            "--instance",
            "genicam_absent_never_created",
            "--camera",
            "genicam:Aravis-Fake-GV01",
            "--pixel-format",
            "Mono12",
            "--roi",
            "0,0,64,64",
            "--trigger",
            "software",
        ],
    ] {
        let (ok, stdout, stderr) = run(args);
        assert!(!ok, "{args:?} succeeded: {stdout}");
        assert!(stdout.is_empty(), "{args:?} printed on stdout: {stdout}");
        assert!(
            stderr.contains("built without the `genicam` feature")
                && stderr.contains("--features genicam")
                && stderr.contains("libaravis-dev"),
            "{args:?}: {stderr}"
        );
    }
    // A bad option value is still refused by name.
    let (ok, _, stderr) = run(&["producer", "--camera", "genicam", "--roi", "1,2,3"]);
    assert!(!ok && stderr.contains("expected x,y,w,h"), "{stderr}");
}
