//! Pure: how a run ended becomes its `failure` text and the exit code of `dicstream run`
//! (see [`super::exit_code`]). The one place that decides them.

use super::{exit_code, Ending};
use crate::acceptance::Acceptance;

/// What makes the results doubtful or the run failed, and the exit code. A completed run
/// passes only if its acceptance (when there is a ground truth) compared something and
/// passed, and no frame was lost to a fault; `signal` is the one that interrupted it.
pub(super) fn verdict(
    ending: Ending,
    failure: Option<String>,
    acceptance: Option<&Acceptance>,
    acceptance_skipped: bool,
    frames_lost_to_faults: u64,
    signal: Option<i32>,
    faults: &[String],
) -> (Option<String>, u8) {
    match ending {
        Ending::Failed => (failure, exit_code::FAILED),
        Ending::Interrupted => {
            let signal = signal.unwrap_or(libc::SIGINT);
            (
                Some(format!("interrupted by {}", wire::signals::name(signal))),
                exit_code::SIGNAL_BASE.saturating_add(signal as u8),
            )
        }
        Ending::Completed => {
            let mut doubts = Vec::new();
            match acceptance {
                None if acceptance_skipped => {}
                None => doubts.push("nothing was identified".to_string()),
                Some(a) if a.tested_nothing() => doubts.push(format!(
                    "the acceptance tested nothing ({})",
                    a.why_nothing_tested()
                )),
                Some(a) if !a.passed => doubts.push(format!(
                    "the identified law did not pass the acceptance (tolerance {:.0} %)",
                    100.0 * a.tolerance
                )),
                Some(_) => {}
            }
            if frames_lost_to_faults > 0 {
                doubts.push(format!(
                    "{frames_lost_to_faults} frame(s) were lost to faults ({})",
                    faults.join("; ")
                ));
            }
            match doubts.is_empty() {
                true => (None, exit_code::PASSED),
                false => (Some(doubts.join("; ")), exit_code::DOUBTFUL),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::acceptance::{accept, accept_path, true_law};

    fn completed(acceptance: Option<&Acceptance>, skipped: bool) -> (Option<String>, u8) {
        verdict(Ending::Completed, None, acceptance, skipped, 0, None, &[])
    }

    #[test]
    fn a_strain_path_decides_a_completed_run() {
        let (truth, a, b) = true_law();
        let ok = accept_path(&truth, &a, &b, "pure_shear", 0.0, 1.5);
        assert_eq!(completed(Some(&ok), false), (None, exit_code::PASSED));
        // f 10 % stiffer: the path's error is past the tolerance, the run is doubtful.
        let mut a_off = a.clone();
        a_off[0] += 0.1f64.ln_1p();
        let bad = accept_path(&truth, &a_off, &b, "pure_shear", 0.0, 1.5);
        let (failure, code) = completed(Some(&bad), false);
        assert_eq!(code, exit_code::DOUBTFUL);
        assert!(failure.unwrap().contains("did not pass the acceptance"));
    }

    #[test]
    fn an_acceptance_that_tested_nothing_is_said_and_doubtful() {
        let (truth, a, b) = true_law();
        for nothing in [
            accept(&truth, &a, &b, None, None),
            accept_path(&truth, &a, &b, "biaxial", 0.5, 1.0),
        ] {
            let (failure, code) = completed(Some(&nothing), false);
            assert_eq!(code, exit_code::DOUBTFUL);
            assert_eq!(
                failure.as_deref(),
                Some("the acceptance tested nothing (no test stretched the specimen)")
            );
        }
        // Nothing identified with a ground truth: doubtful; without one (a real camera): the
        // skipped acceptance is no doubt.
        let (failure, code) = completed(None, false);
        assert_eq!(
            (failure.as_deref(), code),
            (Some("nothing was identified"), exit_code::DOUBTFUL)
        );
        assert_eq!(completed(None, true), (None, exit_code::PASSED));
    }

    #[test]
    fn faults_failures_and_signals_keep_their_codes() {
        let faults = ["correlator killed by signal 9".to_string()];
        let (failure, code) = verdict(Ending::Completed, None, None, true, 3, None, &faults);
        assert_eq!(code, exit_code::DOUBTFUL);
        assert!(failure
            .unwrap()
            .contains("3 frame(s) were lost to faults (correlator killed"));
        let failed = verdict(
            Ending::Failed,
            Some("rig exited 75".into()),
            None,
            false,
            0,
            None,
            &[],
        );
        assert_eq!(failed, (Some("rig exited 75".into()), exit_code::FAILED));
        let (_, code) = verdict(
            Ending::Interrupted,
            None,
            None,
            false,
            0,
            Some(libc::SIGTERM),
            &[],
        );
        assert_eq!(code, 143);
    }
}
