//! `dicstream rig`: the simulated ASTREE machine as a process (publishes `rig/state`, answers
//! `rig/command`, logs `rig.csv`).

use anyhow::Context;
use rig::builtin::BuiltinTest;
use rig::process::{run as run_process, ProcessOptions, RigProcessSettings};
use rig::settings::{LawCoefficients, RigSettings, RigStart, Speed};
use rig::strain::control::OnRestore;
use rig::strain::{StrainKind, TestControl};
use rig::{Campaign, CampaignTest};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct RigArgs {
    /// Every setting from this JSON file (as `dicstream run` writes them in
    /// `<results>/settings/rig.json`), instead of the other options.
    #[arg(long, exclusive = true)]
    pub settings: Option<PathBuf>,
    /// Instance name (shared-memory prefix); runs with different names never meet.
    #[arg(long, default_value_t = wire::Instance::default_name())]
    pub instance: String,
    /// Program file (TOML) started at once.
    #[arg(long, conflicts_with = "test")]
    pub program: Option<PathBuf>,
    /// Built-in test started at once: uniaxial or equibiaxial (mounts its specimen), or
    /// `campaign`: the paper's uniaxial then equibiaxial tests (see --campaign).
    #[arg(long, conflicts_with = "campaign")]
    pub test: Option<String>,
    /// Tests run one after the other, each on its own specimen, unloading between them:
    /// TEST:STRETCH@RATE,... e.g. uniaxial:3@0.08,equibiaxial:2@0.04
    #[arg(long, conflicts_with = "program")]
    pub campaign: Option<String>,
    /// Material of the campaign's specimens: ln f(I1) = Σ a_i (I1 − 3)^i, a_0,a_1,... (f in MPa;
    /// eq. 22) [default: Smactane, Table 3 n = 2]
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub law_f: Option<Vec<f64>>,
    /// ln g(I2) = Σ b_i (I2 − 3)^i, b_0,b_1,... (g in MPa; eq. 25) [default: Smactane, Table 4]
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub law_g: Option<Vec<f64>>,
    /// Stretch rate of the built-in test (/s); under --control strain, the rate of the larger
    /// log strain (/s).
    #[arg(long, alias = "rate-per-s", default_value_t = RigSettings::default().test_rate_per_s)]
    pub rate: f64,
    /// Final stretch λ of the built-in test; under --control strain, the target of the larger
    /// measured stretch.
    #[arg(long, default_value_t = RigSettings::default().test_stretch)]
    pub stretch: f64,
    /// displacement (the grips follow the program) or strain: the correlator's `fields` close
    /// the loop on the gauge zone's log strains (a cruciform specimen, --kind, --ratio).
    #[arg(long, default_value_t = TestControl::Displacement)]
    pub control: TestControl,
    /// The strain path under --control strain: uniaxial (ρ = −1/2), equibiaxial (ρ = 1),
    /// pure_shear (ρ = 0) or biaxial (--ratio).
    #[arg(long)]
    pub kind: Option<StrainKind>,
    /// ρ = ln λy / ln λx held by a biaxial strain-controlled test.
    #[arg(long, allow_hyphen_values = true)]
    pub ratio: Option<f64>,
    /// Strain control holds the grips when the newest field is older than this (s of rig time).
    #[arg(long, default_value_t = rig::strain::interlock::DEFAULT_STALE_S)]
    pub stale_s: f64,
    /// Strain control holds on a field with fewer converged nodes.
    #[arg(long, default_value_t = rig::strain::interlock::DEFAULT_MIN_VALID_NODES)]
    pub min_valid_nodes: u32,
    /// After a hold, once fields are usable again: resume the strain program, or stop
    /// (unload) there.
    #[arg(long, default_value_t = OnRestore::Resume)]
    pub on_interlock: OnRestore,
    /// realtime, a factor N (N× real time) or max.
    #[arg(long, default_value_t = RigSettings::default().speed)]
    pub speed: Speed,
    /// CSV log of the rig state, flushed as it goes.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Log rate (Hz of simulated time).
    #[arg(long, default_value_t = RigSettings::default().log_hz)]
    pub log_hz: f64,
    /// Publication rate of rig/state (Hz of simulated time).
    #[arg(long, default_value_t = RigSettings::default().publish_hz)]
    pub publish_hz: f64,
    /// Seed of the simulation (valve offsets, load-cell noise).
    #[arg(long, default_value_t = RigSettings::default().seed)]
    pub seed: u64,
    /// The specimen's model: structure (the finite-element cruciform and strip of the default
    /// `[specimen.geometry]`, grip and edge effects from the mechanics) or homogeneous (the
    /// analytic sheet, λ = the grips' nominal stretch).
    #[arg(long, default_value_t = rig::SpecimenModel::Structure)]
    pub specimen: rig::SpecimenModel,
    /// Stop after this much simulated time (s).
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Stop once the started program has finished (or was stopped).
    #[arg(long)]
    pub exit_when_done: bool,
    /// Folder of the resume journal: a rig restarted with the same settings and folder goes
    /// on where it was (same time, test and position; its --log continued, rows it lacks
    /// written again from the replay), or refuses to start (exit code 75) if it cannot do so
    /// exactly. Created if missing.
    #[arg(long)]
    pub state_dir: Option<PathBuf>,
    #[command(flatten)]
    pub follow: super::rig_follow_csv::FollowCsvArgs,
}

pub fn run(args: RigArgs) -> anyhow::Result<()> {
    let settings = match &args.settings {
        Some(file) => super::settings_file::read(file)?,
        None if args.follow.follow_csv.is_some() => RigProcessSettings::CsvFollow(Box::new(
            super::rig_follow_csv::options_of(&args.follow, args.instance.clone())?,
        )),
        None => RigProcessSettings::Simulated(Box::new(settings_of(args)?)),
    };
    let settings = match settings {
        RigProcessSettings::CsvFollow(options) => return super::rig_follow_csv::run(*options),
        RigProcessSettings::Simulated(settings) => *settings,
    };
    let options = ProcessOptions::from_settings(&settings)?;
    // The process's messages name their causes; `in_context` keeps the exit code its error
    // asks for (a results file, a journal it cannot follow).
    let summary = run_process(options).map_err(|e| wire::exit::in_context("rig process", &e))?;
    print_summary(&summary);
    Ok(())
}

/// The settings of the command line's flags, refused with the flag named.
fn settings_of(args: RigArgs) -> anyhow::Result<RigSettings> {
    let start = start_of(&args)?;
    let law = law_of(&args, &start)?;
    Ok(RigSettings {
        instance: args.instance,
        start,
        law,
        test_rate_per_s: args.rate,
        test_stretch: args.stretch,
        speed: args.speed,
        publish_hz: args.publish_hz,
        log: args.log,
        log_hz: args.log_hz,
        seed: args.seed,
        duration_s: args.duration_s,
        exit_when_done: args.exit_when_done,
        state_dir: args.state_dir,
        specimen: rig::SpecimenSettings {
            model: args.specimen,
            ..rig::SpecimenSettings::default()
        },
    })
}

/// What the flags start: a strain-controlled test, a program, a built-in test or a campaign.
fn start_of(args: &RigArgs) -> anyhow::Result<RigStart> {
    if let Some(test) = strain_test(args)? {
        return Ok(RigStart::Strain { test });
    }
    Ok(
        match (&args.program, args.test.as_deref(), &args.campaign) {
            (Some(file), _, _) => RigStart::Program { file: file.clone() },
            (None, Some("campaign"), _) => RigStart::Campaign {
                tests: Campaign::paper().tests().to_vec(),
            },
            (None, Some(name), _) => {
                let test = BuiltinTest::parse(name).ok_or_else(|| {
                    anyhow::anyhow!("--test {name:?}: expected uniaxial, equibiaxial or campaign")
                })?;
                RigStart::Builtin {
                    test: CampaignTest {
                        test,
                        stretch: args.stretch,
                        rate_per_s: args.rate,
                    },
                }
            }
            (None, None, Some(spec)) => RigStart::Campaign {
                tests: Campaign::parse(spec)?.tests().to_vec(),
            },
            (None, None, None) => RigStart::Idle,
        },
    )
}

fn print_summary(summary: &rig::process::ProcessSummary) {
    eprintln!(
        "rig: {:.1} s simulated in {:.1} s wall ({:.0}x), {} samples published, {} log rows, \
         commands {} accepted / {} refused, limits tripped {:#x}",
        summary.simulated_s,
        summary.wall_s,
        summary.simulated_s / summary.wall_s.max(1e-9),
        summary.samples_published,
        summary.rows_logged,
        summary.commands_accepted,
        summary.commands_refused,
        summary.limits_tripped
    );
}

/// The strain-controlled test of `--control strain`, refused with the flag named.
fn strain_test(args: &RigArgs) -> anyhow::Result<Option<rig::strain::StrainTest>> {
    match args.control {
        TestControl::Displacement => {
            if args.kind.is_some() || args.ratio.is_some() {
                anyhow::bail!("--kind and --ratio describe a strain path: add --control strain");
            }
            Ok(None)
        }
        TestControl::Strain => {
            if args.program.is_some() || args.test.is_some() || args.campaign.is_some() {
                anyhow::bail!(
                    "--control strain runs its own test (--kind, --stretch, --rate-per-s): no \
                     --program, --test or --campaign with it"
                );
            }
            let kind = args.kind.ok_or_else(|| {
                anyhow::anyhow!(
                    "--control strain needs --kind: {}",
                    <StrainKind as wire::names::Named>::expected()
                )
            })?;
            let test = rig::strain::StrainTest::new(kind, args.ratio, args.stretch, args.rate)
                .and_then(|t| {
                    t.with_interlocks(args.stale_s, args.min_valid_nodes, args.on_interlock)
                })
                .context("--control strain")?;
            Ok(Some(test))
        }
    }
}

/// The law of `--law-f` / `--law-g` (each SMACTANE's when not given; None when neither is),
/// which only a campaign or a strain-controlled test takes.
fn law_of(args: &RigArgs, start: &RigStart) -> anyhow::Result<Option<LawCoefficients>> {
    if args.law_f.is_none() && args.law_g.is_none() {
        return Ok(None);
    }
    if !matches!(start, RigStart::Campaign { .. } | RigStart::Strain { .. }) {
        anyhow::bail!(
            "--law-f / --law-g apply to a campaign (--campaign or --test campaign) or a \
             strain-controlled test (--control strain)"
        );
    }
    let smactane = identifier::law::InvariantLaw::smactane();
    let law = LawCoefficients {
        f: (args.law_f.clone()).unwrap_or_else(|| smactane.f.coefficients().to_vec()),
        g: (args.law_g.clone()).unwrap_or_else(|| smactane.g.coefficients().to_vec()),
    };
    // The same refusals as a run's [specimen].
    law.law().map_err(|e| match e {
        identifier::law::LawError::Coefficients {
            which,
            coefficients,
        } => anyhow::anyhow!("--law-{which} {coefficients:?}: expected one or more finite numbers"),
        identifier::law::LawError::Stiffness { .. } => anyhow::anyhow!("--law-f/--law-g: {e}"),
    })?;
    Ok(Some(law))
}
