//! The command line of each child process of a run (`dicstream <role> <args...>`), from the
//! run's configuration alone: pure, so a restart gets the same arguments but for where the
//! camera's frame ids start.

use crate::children::Role;
use crate::config::RunConfig;
use crate::results::ResultsDir;
use std::path::PathBuf;

/// Relative margin of the camera's stretch envelope beyond the campaign's largest stretch.
const STRETCH_MARGIN: f64 = 0.05;

fn fmt_list(values: &[f64]) -> String {
    values
        .iter()
        .map(|v| format!("{v:e}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// The command line of each child. `first_frame_id` is where the camera's frame ids start
/// (past the last id seen when a camera is restarted, so ids never go back).
pub fn child_args(
    role: Role,
    config: &RunConfig,
    instance: &str,
    results: &ResultsDir,
    first_frame_id: u64,
) -> Vec<String> {
    let path = |p: PathBuf| p.to_string_lossy().into_owned();
    let mut args = vec!["--instance".to_string(), instance.to_string()];
    let c = &config.camera;
    let k = &config.correlator;
    let g = &config.rig;
    let extra: Vec<String> = match role {
        Role::Rig => vec![
            "--campaign".into(),
            config.campaign_spec(),
            format!("--law-f={}", fmt_list(&config.specimen.law_f)),
            format!("--law-g={}", fmt_list(&config.specimen.law_g)),
            "--speed".into(),
            g.speed.to_string(),
            "--publish-hz".into(),
            g.publish_hz.to_string(),
            "--log".into(),
            path(results.rig_csv()),
            "--log-hz".into(),
            g.log_hz.to_string(),
            "--seed".into(),
            g.seed.to_string(),
            "--state-dir".into(),
            path(results.rig_state()),
            "--exit-when-done".into(),
        ],
        Role::Producer => vec![
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
        ],
        Role::Correlator => vec![
            "--method".into(),
            k.method.clone(),
            "--zoi".into(),
            k.zoi_px.to_string(),
            "--step".into(),
            k.step_px.to_string(),
            "--threads".into(),
            k.threads.to_string(),
            "--strain".into(),
            k.strain.clone(),
            "--reference-mode".into(),
            k.reference.clone(),
            "--guess".into(),
            k.guess.clone(),
            "--min-zncc".into(),
            k.min_zncc.to_string(),
            "--gradient-correction".into(),
            k.gradient_correction.to_string(),
            "--state-dir".into(),
            path(results.correlator_state()),
        ],
        Role::Identifier => vec![
            "--output".into(),
            path(results.identification_json()),
            "--journal".into(),
            path(results.journal()),
            "--model".into(),
            config.identifier.models.clone(),
        ],
    };
    args.extend(extra);
    args
}

#[cfg(test)]
mod tests {
    use super::*;

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

    fn args(role: Role, config: &RunConfig, first_frame_id: u64) -> Vec<String> {
        child_args(role, config, "bench_7", &results(), first_frame_id)
    }

    #[test]
    fn every_child_runs_on_the_instance() {
        for role in Role::ALL {
            let args = args(role, &RunConfig::default(), 0);
            assert_eq!(args[..2], ["--instance", "bench_7"], "{role:?}");
        }
    }

    #[test]
    fn the_rig_runs_the_campaign_on_the_specimen_and_journals_in_the_results() {
        let mut config = RunConfig::default();
        config.rig.speed = 4.0;
        config.rig.seed = 11;
        config.specimen.law_f = vec![0.5, -0.25];
        let args = args(Role::Rig, &config, 0);
        assert_eq!(
            value(&args, "--campaign"),
            "uniaxial:3@0.08,equibiaxial:2@0.04"
        );
        assert!(
            args.contains(&"--law-f=5e-1,-2.5e-1".to_string()),
            "{args:?}"
        );
        assert_eq!(value(&args, "--speed"), "4");
        assert_eq!(value(&args, "--seed"), "11");
        assert_eq!(value(&args, "--log"), "/results/run/rig.csv");
        assert_eq!(value(&args, "--state-dir"), "/results/run/rig_state");
        assert_eq!(args.last().map(String::as_str), Some("--exit-when-done"));
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
        config.correlator.method = "icgn2".into();
        config.correlator.threads = 5;
        config.correlator.zoi_px = 31;
        config.correlator.gradient_correction = false;
        let args = args(Role::Correlator, &config, 0);
        assert_eq!(value(&args, "--method"), "icgn2");
        assert_eq!(value(&args, "--threads"), "5");
        assert_eq!(value(&args, "--zoi"), "31");
        assert_eq!(value(&args, "--gradient-correction"), "false");
        assert_eq!(
            value(&args, "--reference-mode"),
            config.correlator.reference
        );
        assert_eq!(value(&args, "--guess"), config.correlator.guess);
        assert_eq!(value(&args, "--state-dir"), "/results/run/correlator_state");
    }

    #[test]
    fn the_identifier_writes_and_journals_in_the_results() {
        let mut config = RunConfig::default();
        config.identifier.models = "yeoh,gent".into();
        let args = args(Role::Identifier, &config, 0);
        assert_eq!(value(&args, "--output"), "/results/run/identification.json");
        assert_eq!(
            value(&args, "--journal"),
            "/results/run/identification_points.csv"
        );
        assert_eq!(value(&args, "--model"), "yeoh,gent");
    }

    #[test]
    fn only_the_camera_depends_on_the_first_frame_id() {
        let config = RunConfig::default();
        for role in Role::ALL {
            let same = args(role, &config, 0) == args(role, &config, 99);
            assert_eq!(same, role != Role::Producer, "{role:?}");
        }
    }
}
