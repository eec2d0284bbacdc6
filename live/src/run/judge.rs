//! The identified law against the specimen's true one ([`crate::acceptance`]), when the run
//! has a ground truth: on the uniaxial and equibiaxial curves the tests reached, or along a
//! strain-controlled path off them. Without a ground truth, why it was skipped.

use crate::acceptance::{accept, accept_path, Acceptance};
use crate::config::{BenchProcess, RigSource, RunConfig};
use crate::recorder::Recorder;
use identifier::law::InvariantLaw;
use wire::IdentificationReport;

/// The acceptance of the run's last identification, and why there is none if it was skipped.
pub(super) struct Judged {
    pub(super) acceptance: Option<Acceptance>,
    /// The field route's, from the identifier's `identification.json`.
    pub(super) field: Option<crate::field_acceptance::FieldAcceptance>,
    /// The field route's acceptance decides the run, not the gauge's: the specimen is a
    /// structure (its gauge's force / section is no stress) and the field route ran with a
    /// ground truth.
    pub(super) field_decides: bool,
    pub(super) skipped: Option<String>,
}

/// Judges the last identification the run recorded (said on stderr when skipped).
pub(super) fn judge(
    config: &RunConfig,
    recorder: &Recorder,
    identification_json: &std::path::Path,
) -> Judged {
    let identified_here = config.runs(BenchProcess::Identifier);
    let has_truth = config.camera.source.has_truth()
        && config.rig.source == RigSource::Simulated
        && identified_here;
    let skipped = match identified_here {
        // The other host's run judges the law (its identifier's files are there).
        false => Some(
            "the identifier runs on the other host ([run] processes): its run judges the law"
                .to_string(),
        ),
        true => (!has_truth && recorder.last_report.is_some()).then(|| {
            format!(
                "no ground truth with [camera] source = {:?} and [rig] source = {:?}: the \
                 identified law is not compared with [specimen]",
                config.camera.source, config.rig.source
            )
        }),
    };
    if let Some(why) = &skipped {
        eprintln!("run: acceptance skipped: {why}");
    }
    let acceptance = recorder
        .last_report
        .filter(|_| has_truth)
        .map(|report| accept_report(config, recorder, &report));
    let field_runs = config
        .identifier_routes()
        .runs(wire::identification::ReportRoute::Field)
        && has_truth;
    let field_decides = field_runs && config.specimen.model == rig::SpecimenModel::Structure;
    let field = field_runs.then_some(()).and_then(|_| {
        let truth = config.law().ok()?;
        crate::field_acceptance::judge_field(&truth, identification_json)
    });
    Judged {
        acceptance,
        field,
        field_decides,
        skipped,
    }
}

/// The acceptance of `report` against the configuration's law.
fn accept_report(
    config: &RunConfig,
    recorder: &Recorder,
    report: &IdentificationReport,
) -> Acceptance {
    let truth: InvariantLaw = config.law().expect("validated law");
    let a = &report.a[..report.a_count as usize];
    let b = &report.b[..report.b_count as usize];
    // A strain-controlled path off the uniaxial and equibiaxial curves (pure shear, any ρ but
    // 1) is compared along its own path, up to the larger stretch the gauge zone reached.
    let off_path = config
        .strain_test()
        .ok()
        .flatten()
        .filter(|t| t.kind != rig::strain::StrainKind::Equibiaxial);
    if let Some(test) = &off_path {
        let reached = recorder.max_stretch[2];
        return accept_path(&truth, a, b, test.kind.name(), test.ratio, reached);
    }
    let tested =
        |case: usize| (recorder.max_stretch[case] > 1.01).then_some(recorder.max_stretch[case]);
    accept(&truth, a, b, tested(1), tested(2))
}
