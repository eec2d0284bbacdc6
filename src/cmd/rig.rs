//! `dicstream rig`: the simulated ASTREE machine as a process (publishes `rig/state`, answers
//! `rig/command`, logs `rig.csv`).

use anyhow::Context;
use rig::builtin::BuiltinTest;
use rig::process::{run as run_process, ProcessOptions, Speed};
use rig::strain::control::OnRestore;
use rig::strain::{StrainKind, TestControl};
use rig::{Campaign, Program, RigConfig};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct RigArgs {
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
    #[arg(long, alias = "rate-per-s", default_value_t = 1e-3)]
    pub rate: f64,
    /// Final stretch λ of the built-in test; under --control strain, the target of the larger
    /// measured stretch.
    #[arg(long, default_value_t = 2.0)]
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
    #[arg(long, default_value = "realtime")]
    pub speed: String,
    /// CSV log of the rig state, flushed as it goes.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Log rate (Hz of simulated time).
    #[arg(long, default_value_t = 100.0)]
    pub log_hz: f64,
    /// Publication rate of rig/state (Hz of simulated time).
    #[arg(long, default_value_t = 500.0)]
    pub publish_hz: f64,
    /// Seed of the simulation (valve offsets, load-cell noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
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
    if args.follow.follow_csv.is_some() {
        return super::rig_follow_csv::run(args.follow, args.instance);
    }
    let speed = Speed::parse(&args.speed)?;
    let mut config = RigConfig::default();
    let strain = strain_test(&args)?;
    let campaign = campaign_of(&args, strain.is_some())?;
    let program = program_of(&args, &mut config)?;
    // The cruciform a strain-controlled test mounts, of --law-f / --law-g if given.
    let mut strain_specimen = BuiltinTest::Equibiaxial.specimen();
    if let Some(law) = law_of(&args)? {
        strain_specimen.law = law;
    }
    let options = ProcessOptions {
        instance: args.instance,
        config,
        seed: args.seed,
        program,
        campaign,
        test_rate_per_s: args.rate,
        test_stretch: args.stretch,
        speed,
        publish_hz: args.publish_hz,
        log_path: args.log.clone(),
        log_hz: args.log_hz,
        duration_s: args.duration_s,
        exit_when_done: args.exit_when_done,
        state_dir: args.state_dir.clone(),
        strain: strain.map(|test| rig::process::StrainOptions {
            test,
            specimen: strain_specimen,
        }),
    };
    // The process's messages name their causes; `in_context` keeps the exit code its error
    // asks for (a results file, a journal it cannot follow).
    let summary = run_process(options).map_err(|e| wire::exit::in_context("rig process", &e))?;
    print_summary(&summary);
    Ok(())
}

/// The campaign of `--campaign` or `--test campaign`, with the law of `--law-f` / `--law-g`
/// when given (which only a campaign or, with `strain`, a strain-controlled test takes).
fn campaign_of(args: &RigArgs, strain: bool) -> anyhow::Result<Option<Campaign>> {
    let campaign = match (&args.campaign, args.test.as_deref()) {
        (Some(spec), _) => Some(Campaign::parse(spec)?),
        (None, Some("campaign")) => Some(Campaign::paper()),
        _ => None,
    };
    Ok(match (campaign, &args.law_f, &args.law_g) {
        (Some(c), f, g) if f.is_some() || g.is_some() => {
            let (a, b) = law_coefficients(args);
            // The same refusals as a run's [specimen].
            let law = identifier::law::InvariantLaw::exp_poly(&a, &b).map_err(|e| match e {
                identifier::law::LawError::Coefficients {
                    which,
                    coefficients,
                } => anyhow::anyhow!(
                    "--law-{which} {coefficients:?}: expected one or more finite numbers"
                ),
                identifier::law::LawError::Stiffness { .. } => {
                    anyhow::anyhow!("--law-f/--law-g: {e}")
                }
            })?;
            Some(c.with_law(law))
        }
        (None, Some(_), _) | (None, _, Some(_)) if !strain => {
            anyhow::bail!(
                "--law-f / --law-g apply to a campaign (--campaign or --test campaign) or a \
                 strain-controlled test (--control strain)"
            )
        }
        (c, _, _) => c,
    })
}

/// The program of `--program FILE` or of a built-in `--test` (which mounts its specimen in
/// `config`).
fn program_of(args: &RigArgs, config: &mut RigConfig) -> anyhow::Result<Option<Program>> {
    let test = args.test.as_deref().filter(|t| *t != "campaign");
    Ok(match (&args.program, test) {
        (Some(path), _) => {
            let program = || format!("program {}", path.display());
            let text = std::fs::read_to_string(path).with_context(program)?;
            let base = path.parent().map(PathBuf::from).unwrap_or_default();
            Some(Program::from_toml(&text, &base).with_context(program)?)
        }
        (None, Some(name)) => {
            let test = BuiltinTest::parse(name).ok_or_else(|| {
                anyhow::anyhow!("--test {name:?}: expected uniaxial, equibiaxial or campaign")
            })?;
            config.specimen = Some(test.specimen());
            Some(test.program(args.rate, args.stretch)?)
        }
        (None, None) => None,
    })
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

/// The coefficients of `--law-f` and `--law-g`, each SMACTANE's when not given.
fn law_coefficients(args: &RigArgs) -> (Vec<f64>, Vec<f64>) {
    let smactane = identifier::law::InvariantLaw::smactane();
    let a = args
        .law_f
        .clone()
        .unwrap_or_else(|| smactane.f.coefficients().to_vec());
    let b = args
        .law_g
        .clone()
        .unwrap_or_else(|| smactane.g.coefficients().to_vec());
    (a, b)
}

/// The law of --law-f / --law-g (None: the specimen's own).
fn law_of(args: &RigArgs) -> anyhow::Result<Option<identifier::law::InvariantLaw>> {
    if args.law_f.is_none() && args.law_g.is_none() {
        return Ok(None);
    }
    let (a, b) = law_coefficients(args);
    identifier::law::InvariantLaw::exp_poly(&a, &b)
        .map(Some)
        .map_err(|e| anyhow::anyhow!("--law-f/--law-g: {e}"))
}
