//! Pure: how a run ended becomes its ending, its `failure` text and the exit code of
//! `dicstream run` (see [`super::exit_code`]). The one place that decides them.

use super::{exit_code, Ending};
use crate::acceptance::Acceptance;
use crate::field_acceptance::FieldAcceptance;

/// What the end of a run knows that decides its verdict.
pub(super) struct Facts<'a> {
    /// How the loop ended (Failed with the error's chain in `failure`).
    pub(super) ending: Ending,
    pub(super) failure: Option<String>,
    pub(super) acceptance: Option<&'a Acceptance>,
    /// The acceptance was skipped (no ground truth): its absence is no doubt.
    pub(super) acceptance_skipped: bool,
    /// On a structure, the field route's acceptance (inner None: the route gave none), which
    /// decides in place of the gauge's; None on the homogeneous sheet.
    pub(super) field_acceptance: Option<Option<&'a FieldAcceptance>>,
    pub(super) frames_lost_to_faults: u64,
    /// The link the run started, if any: what it lost makes the results doubtful.
    pub(super) link: Option<&'a super::LinkReport>,
    /// Without a rig here: the campaign halted on the other host before its end.
    pub(super) campaign_halted: Option<&'a str>,
    /// The termination signal that interrupted the run.
    pub(super) signal: Option<i32>,
    pub(super) faults: &'a [String],
    /// The children killed at the stop, its timeout passed (their last results may be
    /// missing).
    pub(super) killed_at_stop: &'a [String],
    /// Results files that could not be written, each with why.
    pub(super) unwritten: &'a [String],
}

/// The ending, what makes the results doubtful or the run failed, and the exit code.
#[derive(Debug, PartialEq, Eq)]
pub(super) struct Verdict {
    pub(super) ending: Ending,
    pub(super) failure: Option<String>,
    pub(super) exit_code: u8,
}

/// The verdict of a run. A completed run passes only if its acceptance (when there is a
/// ground truth) compared something and passed, no frame was lost to a fault and the link to
/// another host, when the run started one, lost nothing; results
/// that could not be written fail a run that was not interrupted (it did not deliver them).
pub(super) fn verdict(facts: Facts) -> Verdict {
    let (failure, exit_code) = match facts.ending {
        Ending::Failed => (facts.failure, exit_code::FAILED),
        Ending::Interrupted => {
            let signal = facts.signal.unwrap_or(libc::SIGINT);
            (
                Some(format!("interrupted by {}", wire::signals::name(signal))),
                exit_code::SIGNAL_BASE.saturating_add(signal as u8),
            )
        }
        Ending::Completed => match doubts(&facts) {
            None => (None, exit_code::PASSED),
            Some(doubts) => (Some(doubts), exit_code::DOUBTFUL),
        },
    };
    let verdict = Verdict {
        ending: facts.ending,
        failure,
        exit_code,
    };
    match facts.unwritten.is_empty() || facts.ending == Ending::Interrupted {
        true => verdict,
        false => unwritten(verdict, facts.unwritten),
    }
}

/// What makes a completed run's results doubtful, if anything.
fn doubts(facts: &Facts) -> Option<String> {
    let mut doubts = Vec::new();
    match facts.field_acceptance {
        Some(field) => doubts.extend(field_doubt(field)),
        None => doubts.extend(gauge_doubt(facts)),
    }
    if facts.frames_lost_to_faults > 0 {
        doubts.push(format!(
            "{} frame(s) were lost to faults ({})",
            facts.frames_lost_to_faults,
            facts.faults.join("; ")
        ));
    }
    doubts.extend(facts.link.and_then(super::LinkReport::doubt));
    doubts.extend(facts.campaign_halted.map(str::to_string));
    if !facts.killed_at_stop.is_empty() {
        doubts.push(format!(
            "{} did not finish within the stop timeout ([run] stop_timeout_s) and {} killed: \
             {} last results (the identifier's: the fit of the last frames) may be missing",
            facts.killed_at_stop.join(", "),
            if facts.killed_at_stop.len() == 1 {
                "was"
            } else {
                "were"
            },
            if facts.killed_at_stop.len() == 1 {
                "its"
            } else {
                "their"
            }
        ));
    }
    (!doubts.is_empty()).then(|| doubts.join("; "))
}

/// The doubt the law from the whole field leaves on a structure, if any.
fn field_doubt(field: Option<&FieldAcceptance>) -> Option<String> {
    match field {
        None => Some("the field route identified nothing".to_string()),
        Some(f) if f.model.is_none() => Some(format!(
            "the field route identified nothing ({})",
            f.error.as_deref().unwrap_or("no fit")
        )),
        Some(f) if !f.passed => Some(format!(
            "the law identified from the whole field did not pass the acceptance (tolerance \
             {:.0} %)",
            100.0 * f.tolerance
        )),
        Some(_) => None,
    }
}

/// The doubt the gauge route's law leaves, if any.
fn gauge_doubt(facts: &Facts) -> Option<String> {
    match facts.acceptance {
        None if facts.acceptance_skipped => None,
        None => Some("nothing was identified".to_string()),
        Some(a) if a.tested_nothing() => Some(format!(
            "the acceptance tested nothing ({})",
            a.why_nothing_tested()
        )),
        Some(a) if !a.passed => Some(format!(
            "the identified law did not pass the acceptance (tolerance {:.0} %)",
            100.0 * a.tolerance
        )),
        Some(_) => None,
    }
}

/// A run whose results could not all be written (a full disk) failed: the files are named
/// after the failure it already had, or in place of its doubts.
fn unwritten(verdict: Verdict, notes: &[String]) -> Verdict {
    let missing = format!("results not written: {}", notes.join("; "));
    let failure = match verdict.failure {
        Some(f) if verdict.ending == Ending::Failed => format!("{f}; {missing}"),
        _ => missing,
    };
    Verdict {
        ending: Ending::Failed,
        failure: Some(failure),
        exit_code: exit_code::FAILED,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::acceptance::{accept, accept_path, true_law};
    use crate::field_acceptance::judge_route as compare;
    use identifier::law::InvariantLaw;

    /// A run that ended as `ending`, with nothing else known.
    fn facts(ending: Ending) -> Facts<'static> {
        Facts {
            ending,
            failure: None,
            acceptance: None,
            acceptance_skipped: false,
            field_acceptance: None,
            frames_lost_to_faults: 0,
            link: None,
            campaign_halted: None,
            signal: None,
            faults: &[],
            killed_at_stop: &[],
            unwritten: &[],
        }
    }

    /// The verdict of a failed run, for `failure`.
    fn failed_with(failure: &str) -> Verdict {
        Verdict {
            ending: Ending::Failed,
            failure: Some(failure.into()),
            exit_code: exit_code::FAILED,
        }
    }

    fn completed(acceptance: Option<&Acceptance>, skipped: bool) -> (Option<String>, u8) {
        let v = verdict(Facts {
            acceptance,
            acceptance_skipped: skipped,
            ..facts(Ending::Completed)
        });
        (v.failure, v.exit_code)
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
    fn on_a_structure_the_law_from_the_whole_field_decides() {
        let (truth, a, b) = true_law();
        let law = InvariantLaw::smactane();
        // The gauge's force / section fails on a structure: not the verdict there.
        let mut a_off = a.clone();
        a_off[0] += 0.3f64.ln_1p();
        let gauge = accept(&truth, &a_off, &b, Some(3.0), Some(1.1));
        assert!(!gauge.passed);
        let route = |a0: f64| {
            serde_json::json!({
                "frames": 12,
                "reach": {"max_stretches": [1.7, 1.13], "uniaxial": 1.7, "equibiaxial": 1.13,
                          "pure_shear": 1.3},
                "fits": [{"model": "lambert-diani-rey:2,2",
                          "params": {"a0": a0, "a1": -2.52e-2, "a2": 1.40e-3,
                                     "b0": -1.02, "b1": -3.92e-3, "b2": -5.30e-4}}],
            })
        };
        let on_structure = |field: Option<&FieldAcceptance>| {
            let v = verdict(Facts {
                acceptance: Some(&gauge),
                field_acceptance: Some(field),
                ..facts(Ending::Completed)
            });
            (v.failure, v.exit_code)
        };
        let good = compare(&law, &route(-1.27));
        assert_eq!(on_structure(Some(&good)), (None, exit_code::PASSED));
        let off = compare(&law, &route(-1.27 + 0.1f64.ln_1p()));
        let (failure, code) = on_structure(Some(&off));
        assert_eq!(code, exit_code::DOUBTFUL);
        assert_eq!(
            failure.as_deref(),
            Some("the law identified from the whole field did not pass the acceptance (tolerance 3 %)")
        );
        let nothing = compare(
            &law,
            &serde_json::json!({"error": "crosses no arm", "fits": null}),
        );
        let (failure, code) = on_structure(Some(&nothing));
        assert_eq!(code, exit_code::DOUBTFUL);
        assert_eq!(
            failure.as_deref(),
            Some("the field route identified nothing (crosses no arm)")
        );
        assert_eq!(on_structure(None).1, exit_code::DOUBTFUL);
        // On the homogeneous sheet the gauge's acceptance decides.
        assert_eq!(completed(Some(&gauge), false).1, exit_code::DOUBTFUL);
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
        let lost = verdict(Facts {
            acceptance_skipped: true,
            frames_lost_to_faults: 3,
            faults: &faults,
            ..facts(Ending::Completed)
        });
        assert_eq!(lost.exit_code, exit_code::DOUBTFUL);
        assert!(lost
            .failure
            .unwrap()
            .contains("3 frame(s) were lost to faults (correlator killed"));
        let failed = verdict(Facts {
            failure: Some("rig exited 75".into()),
            ..facts(Ending::Failed)
        });
        assert_eq!(failed, failed_with("rig exited 75"));
        let interrupted = verdict(Facts {
            signal: Some(libc::SIGTERM),
            ..facts(Ending::Interrupted)
        });
        assert_eq!(interrupted.exit_code, 143);
        // The identifier killed at the stop, its final fit unfinished: doubtful, said.
        let killed = ["identifier".to_string()];
        let cut_short = verdict(Facts {
            acceptance_skipped: true,
            killed_at_stop: &killed,
            ..facts(Ending::Completed)
        });
        assert_eq!(cut_short.exit_code, exit_code::DOUBTFUL);
        assert_eq!(
            cut_short.failure.as_deref(),
            Some(
                "identifier did not finish within the stop timeout ([run] stop_timeout_s) and \
                 was killed: its last results (the identifier's: the fit of the last frames) \
                 may be missing"
            )
        );
    }

    #[test]
    fn what_the_link_lost_makes_a_completed_run_doubtful() {
        let mut counts = link::LinkCounts::new("lab");
        counts.set_in(
            link::LinkedService::Fields,
            link::InCounts {
                received: 10,
                lost: 4,
                ..Default::default()
            },
        );
        let report = super::super::LinkReport {
            lost: 4,
            counts: Some(counts),
            unreadable: None,
        };
        let judged = verdict(Facts {
            acceptance_skipped: true,
            link: Some(&report),
            ..facts(Ending::Completed)
        });
        assert_eq!(judged.exit_code, exit_code::DOUBTFUL);
        assert!(judged
            .failure
            .unwrap()
            .starts_with("the link to the other host lost 4 fields"));
    }

    #[test]
    fn a_campaign_halted_on_the_other_host_makes_the_run_doubtful() {
        let judged = verdict(Facts {
            acceptance_skipped: true,
            campaign_halted: Some("the campaign halted on the other host: test 1 of 3"),
            ..facts(Ending::Completed)
        });
        assert_eq!(judged.exit_code, exit_code::DOUBTFUL);
        assert_eq!(
            judged.failure.as_deref(),
            Some("the campaign halted on the other host: test 1 of 3")
        );
    }

    #[test]
    fn results_not_written_fail_a_run_unless_it_was_interrupted() {
        let unwritten = ["latency.png: disk full".to_string()];
        let missing = "results not written: latency.png: disk full";
        for (ending, failure, expected) in [
            (Ending::Completed, None, missing.to_string()),
            (
                Ending::Failed,
                Some("rig exited 74"),
                format!("rig exited 74; {missing}"),
            ),
        ] {
            let judged = verdict(Facts {
                failure: failure.map(Into::into),
                unwritten: &unwritten,
                ..facts(ending)
            });
            assert_eq!(judged, failed_with(&expected), "{ending:?}");
        }
        let interrupted = verdict(Facts {
            unwritten: &unwritten,
            ..facts(Ending::Interrupted)
        });
        assert_eq!(interrupted.ending, Ending::Interrupted);
        assert_eq!(interrupted.exit_code, 130);
    }
}
