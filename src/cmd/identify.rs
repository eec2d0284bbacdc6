//! `dicstream identify`: offline identification of hyperelastic potentials from CSV load cases
//! (`stretch,nominal_stress_mpa`) and general biaxial states (`--biaxial-general`:
//! `lambda1,lambda2,nominal_stress1_mpa,nominal_stress2_mpa`, both stresses fitted at once),
//! ranked by AIC; table, JSON, and optional PNG plots (of the canonical curves). A file may be
//! a test machine's export as it comes (title lines, a units row, `;` and decimal commas, a
//! force and an extension with the specimen's section and gauge length: `identifier::table`,
//! `identifier::columns`).
//!
//! Above `--max-fit-points` the fit runs on a load-path-preserving subsample, said on stderr and
//! in the JSON. When stderr is a terminal, one progress line per model (model, start k/n,
//! elapsed) is drawn there; never on stdout, which holds the JSON alone with `--json`.
//!
//! The report gives each fit's initial shear modulus, its Abaqus and Ansys cards (in the JSON;
//! as files with `--cards`), and says on stderr (and leaves unranked: `-`, `"rank": null`) a
//! fit whose parameters the data do not identify (`identifier::identifiability`).

use anyhow::{bail, Context};
use identifier::columns::Specimen;
use identifier::data::{
    read_biaxial_csv, read_curve_csv, BiaxialState, Curve, LoadCase, ReadOptions,
};
use identifier::fe_cards::write_cards;
use identifier::fit::{Fit, FitData, FitOptions, FitStage, ResidualKind};
use identifier::initial_modulus::initial_shear_modulus_mpa;
use identifier::models::{parse_model_list, Model};
use identifier::ranking::{identify, outcome_json, Outcome};
use identifier::residual_plot::write_residual_plot;
use identifier::subsample::DEFAULT_MAX_FIT_POINTS;
use identifier::table::TableOptions;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Residual measure on the command line.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum ResidualArg {
    /// P_model − P_data, MPa.
    Absolute,
    /// (P_model − P_data) / |P_data|.
    Relative,
}

#[derive(clap::Args, Debug)]
pub struct IdentifyArgs {
    /// Uniaxial tension CSV: header, then `stretch,nominal_stress_mpa`.
    #[arg(long, value_name = "F.csv")]
    pub uniaxial: Option<PathBuf>,
    /// Equibiaxial tension CSV: header, then `stretch,nominal_stress_mpa`.
    #[arg(long, value_name = "F.csv")]
    pub biaxial: Option<PathBuf>,
    /// Pure shear (planar tension) CSV: header, then `stretch,nominal_stress_mpa`.
    #[arg(long = "pure-shear", value_name = "F.csv")]
    pub pure_shear: Option<PathBuf>,
    /// General biaxial states (any λ1, λ2, e.g. Kawabata's tests on a multiaxial machine):
    /// header `lambda1,lambda2,nominal_stress1_mpa,nominal_stress2_mpa`, then one state a row;
    /// both stresses are fitted, with the other files if given.
    #[arg(long = "biaxial-general", value_name = "F.csv")]
    pub biaxial_general: Option<PathBuf>,
    /// Models: NAME[,NAME...] (e.g. mooney,ogden:3,rivlin:10,01,11) or `all` (the default;
    /// with `--fields`, the run's `[identifier] models`).
    #[arg(long)]
    pub model: Option<String>,
    /// A run's results folder: fit its saved fields (`fields/field_<frame>.csv` with each
    /// node's gradient) against the grips' forces (`frames.csv`) by the virtual fields method,
    /// the live field route's own code, with the run's camera view and cruciform
    /// (`config.toml`).
    #[arg(long, value_name = "DIR")]
    pub fields: Option<PathBuf>,
    /// With `--fields`: the grips' forces from this rig log (`t_s`, `X+_force_n` ...
    /// `Y-_force_n`), at each frame's rig time, instead of `frames.csv`'s.
    #[arg(long, value_name = "rig.csv", requires = "fields")]
    pub forces: Option<PathBuf>,
    #[command(flatten)]
    pub femu: super::identify_femu::FemuArgs,
    /// Residual measure of the fit.
    #[arg(long, value_enum, default_value = "absolute")]
    pub residual: ResidualArg,
    /// Print JSON instead of the ranked table.
    #[arg(long)]
    pub json: bool,
    /// Write PNG plots (data and fitted curves, f(I1) and g(I2), the best fit's residuals)
    /// into this folder. With --fields: `stretch_states.png`, the states of the kept frames
    /// coloured by their contribution to the best fit, and those numbers in `states.csv`.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// With --plot: f(I1) and g(I2) show every ranked model (up to six) and the route's own
    /// fitted f and g, not only the identified law (the best-ranked model) against the points.
    #[arg(long, requires = "plot")]
    pub all_models: bool,
    /// Write each fit's FE coefficient cards into this folder: `abaqus_<model>.inp`
    /// (`*HYPERELASTIC`) and `ansys_<model>.mac` (`TB,HYPER`), for the models the codes have.
    #[arg(long, value_name = "DIR")]
    pub cards: Option<PathBuf>,
    /// Largest number of points fitted (all load cases together); above it the fit runs on a
    /// deterministic subsample keeping each curve's ends and shape (said on stderr and in the
    /// JSON; RMS and R² are still over every point).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_FIT_POINTS as u64, value_parser = clap::value_parser!(u64).range(2..))]
    pub max_fit_points: u64,
    /// Lines at the top of each data file skipped before its header (a machine export's title
    /// lines; a line whose cell count differs from the header's that follows is skipped
    /// anyway).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub skip_lines: usize,
    /// Gauge length L0 (mm) of a load case's file that logs an extension (`Extension (mm)`)
    /// instead of a stretch or a strain: λ = 1 + Δl / L0.
    #[arg(long, value_name = "MM")]
    pub gauge_length_mm: Option<f64>,
    /// Reference (undeformed) section A0 (mm²) of a load case's file that logs a force
    /// (`Load (kN)`) instead of a nominal stress: P = F / A0.
    #[arg(long, value_name = "MM2")]
    pub section_mm2: Option<f64>,
    /// Threads sharing the points of each fit evaluation; the results do not depend on it.
    /// Default 1: on a shared two-core machine more threads (spawned per evaluation) measured
    /// slower, not faster.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: u64,
}

pub fn run(args: IdentifyArgs) -> anyhow::Result<()> {
    let tty = std::io::stderr().is_terminal();
    run_with(
        args,
        &mut std::io::stdout().lock(),
        &mut std::io::stderr(),
        tty,
    )
}

/// [`run`] with its outputs given: `out` gets the table or the JSON alone, `err` the notes and,
/// when `progress` (stderr is a terminal), the progress lines.
pub fn run_with(
    args: IdentifyArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
    progress: bool,
) -> anyhow::Result<()> {
    if let Some(dir) = &args.fields {
        if args.femu.femu {
            return super::identify_femu::run(&args, dir, out, err);
        }
        return super::identify_fields::run(&args, dir, out, err);
    }
    let (curves, states) = read_data(&args)?;
    let all = FitData {
        curves: &curves,
        states: &states,
    };
    let outcome = fit(&args, all, err, progress)?;
    for fit in &outcome.fits {
        if let Some(w) = fit.identifiability.warning() {
            writeln!(err, "{}: {w}", fit.model)?;
        }
    }
    if args.json {
        write_json(out, &outcome)?;
    } else {
        print_table(out, &outcome.fits, &curves, !states.is_empty())?;
        for (m, e) in &outcome.failures {
            writeln!(err, "not fitted: {m}: {e}")?;
        }
        if let Ok(r) = &outcome.route {
            writeln!(
                out,
                "\npaper route (eqs 20-25, n = 2): ln f: a = {:?}; ln g: b = {:?}; g = Σ c_i/I2^i: c = {:?}",
                r.a, r.b, r.c
            )?;
        }
    }
    if let (Some(_), false) = (&args.plot, states.is_empty()) {
        writeln!(
            err,
            "plots: the canonical curves only; the general biaxial states are not drawn"
        )?;
    }
    if let Some(dir) = &args.plot {
        let written = identifier::plot::write_plots(
            dir,
            &curves,
            &outcome.fits,
            outcome.route.as_ref().map_err(String::as_str),
            identifier::plot::PlotOptions {
                all_models: args.all_models,
            },
        )
        .with_context(|| format!("writing plots into {}", dir.display()))?;
        if let Err(why) = &outcome.route {
            writeln!(
                err,
                "plots: f(I1) and g(I2) without data points: the paper's route did not run ({why})"
            )?;
        }
        for path in written {
            writeln!(err, "wrote {}", path.display())?;
        }
        if let Some(best) = outcome.fits.first() {
            let path = dir.join("residuals.png");
            write_residual_plot(&path, all, best)
                .with_context(|| format!("writing {}", path.display()))?;
            writeln!(err, "wrote {}", path.display())?;
        }
    }
    if let Some(dir) = &args.cards {
        let written = write_cards(dir, &outcome.fits)?;
        for path in written {
            writeln!(err, "wrote {}", path.display())?;
        }
    }
    if outcome.fits.is_empty() {
        bail!("no model could be fitted");
    }
    Ok(())
}

/// The load cases' curves and the general biaxial states the arguments name; at least one.
fn read_data(args: &IdentifyArgs) -> anyhow::Result<(Vec<Curve>, Vec<BiaxialState>)> {
    for (value, flag) in [
        (args.gauge_length_mm, "--gauge-length-mm"),
        (args.section_mm2, "--section-mm2"),
    ] {
        if value.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
            bail!("{flag} must be a positive number");
        }
    }
    let options = ReadOptions {
        table: TableOptions {
            skip_lines: args.skip_lines,
        },
        specimen: Specimen {
            gauge_length_mm: args.gauge_length_mm,
            section_mm2: args.section_mm2,
        },
    };
    let mut curves: Vec<Curve> = Vec::new();
    for (path, case) in [
        (&args.uniaxial, LoadCase::Uniaxial),
        (&args.biaxial, LoadCase::Equibiaxial),
        (&args.pure_shear, LoadCase::PureShear),
    ] {
        if let Some(path) = path {
            curves.push(
                read_curve_csv(path, case, &options)
                    .with_context(|| format!("reading {case} data"))?,
            );
        }
    }
    let states: Vec<BiaxialState> = match &args.biaxial_general {
        Some(path) => read_biaxial_csv(path, &options).context("reading general biaxial data")?,
        None => Vec::new(),
    };
    if curves.is_empty() && states.is_empty() {
        bail!(
            "no data: give at least one of --uniaxial, --biaxial, --pure-shear, --biaxial-general"
        );
    }
    Ok((curves, states))
}

/// Fits the models of `args` to `all` (`identifier::ranking::identify`), with its notes and
/// progress lines on `err`.
fn fit(
    args: &IdentifyArgs,
    all: FitData,
    err: &mut dyn Write,
    progress: bool,
) -> anyhow::Result<Outcome> {
    let models = parse_model_list(args.model.as_deref().unwrap_or("all"))?;
    let options = FitOptions {
        residual: match args.residual {
            ResidualArg::Absolute => ResidualKind::Absolute,
            ResidualArg::Relative => ResidualKind::Relative,
        },
        threads: usize::try_from(args.threads).unwrap_or(1),
        ..FitOptions::default()
    };
    let max_fit_points = usize::try_from(args.max_fit_points).unwrap_or(usize::MAX);
    let mut line = ProgressLine::new(&models, progress, PROGRESS_REDRAW);
    let outcome = identify(
        &models,
        all.curves,
        all.states,
        &options,
        max_fit_points,
        &mut |index, stage| line.update(err, index, stage),
    );
    line.finish(err);
    if let Some(s) = &outcome.subsample {
        writeln!(
            err,
            "{} points exceed --max-fit-points {}: fitting a subsample of {} (each curve's ends and shape kept); RMS and R² over every point",
            s.points_total, s.max_points, s.points_fitted
        )?;
    }
    if let Err(e) = &outcome.route {
        writeln!(err, "paper route (eqs. 20-25) not run: {e}")?;
    }
    Ok(outcome)
}

/// `--json`: the fits, the failures, the paper's route and the subsample as one object.
fn write_json(out: &mut dyn Write, outcome: &Outcome) -> anyhow::Result<()> {
    writeln!(
        out,
        "{}",
        serde_json::to_string_pretty(&outcome_json(outcome))?
    )?;
    Ok(())
}

/// Least time between two redraws of the progress line.
const PROGRESS_REDRAW: Duration = Duration::from_millis(100);

/// One progress line per model on a terminal: `[k/n] model: start k/n, elapsed s`, redrawn in
/// place, ended with the model's time when the next model starts. Draws nothing when off.
struct ProgressLine {
    names: Vec<String>,
    on: bool,
    redraw: Duration,
    current: Option<(usize, Instant)>,
    last_draw: Option<Instant>,
}

impl ProgressLine {
    fn new(models: &[Model], on: bool, redraw: Duration) -> Self {
        ProgressLine {
            names: models.iter().map(Model::name).collect(),
            on,
            redraw,
            current: None,
            last_draw: None,
        }
    }

    fn update(&mut self, err: &mut dyn Write, index: usize, stage: Option<FitStage>) {
        if !self.on {
            return;
        }
        if self.current.is_none_or(|(i, _)| i != index) {
            self.finish(err);
            self.current = Some((index, Instant::now()));
            self.last_draw = None;
        }
        if self.last_draw.is_some_and(|t| t.elapsed() < self.redraw) {
            return;
        }
        self.last_draw = Some(Instant::now());
        let (_, started) = self.current.expect("set above");
        let text = progress_text(index, &self.names, stage, started.elapsed().as_secs_f64());
        // Progress is best effort: a failed write to stderr must not stop the fit.
        let _ = write!(err, "\r\x1b[2K{text}");
        let _ = err.flush();
    }

    /// Ends the current model's line with its time.
    fn finish(&mut self, err: &mut dyn Write) {
        if let Some((index, started)) = self.current.take() {
            let elapsed_s = started.elapsed().as_secs_f64();
            let _ = writeln!(
                err,
                "\r\x1b[2K[{}/{}] {}: done in {elapsed_s:.1} s",
                index + 1,
                self.names.len(),
                self.names[index]
            );
        }
    }
}

/// The text of a progress line.
fn progress_text(
    index: usize,
    names: &[String],
    stage: Option<FitStage>,
    elapsed_s: f64,
) -> String {
    let what = match stage {
        None => "starting".to_string(),
        Some(FitStage::Screening { start, starts }) => format!("screening start {start}/{starts}"),
        Some(FitStage::Refining { start, starts }) => format!("refining start {start}/{starts}"),
    };
    format!(
        "[{}/{}] {}: {what}, {elapsed_s:.1} s",
        index + 1,
        names.len(),
        names[index]
    )
}

fn print_table(
    out: &mut dyn Write,
    fits: &[Fit],
    curves: &[Curve],
    general: bool,
) -> std::io::Result<()> {
    let mut cases: Vec<&str> = curves.iter().map(|c| c.case.name()).collect();
    if general {
        cases.push(identifier::data::DataGroup::BiaxialGeneral.name());
    }
    write!(
        out,
        "{:>2} {:<22} {:>9} {:>9} {:>9}",
        "#", "model", "aic", "rms_mpa", "mu0_mpa"
    )?;
    for c in &cases {
        write!(out, " {:>14}", format!("r2_{c}"))?;
    }
    writeln!(
        out,
        "  stable_up_to (uniaxial/equibiaxial/pure_shear)  params ± std"
    )?;
    let mut rank = 0;
    for fit in fits {
        let shown_rank = match fit.identifiability.identifiable() {
            true => {
                rank += 1;
                rank.to_string()
            }
            false => "-".to_string(),
        };
        let mu0 = initial_shear_modulus_mpa(&fit.model, &fit.params)
            .map_or("?".to_string(), |m| format!("{m:.4}"));
        write!(
            out,
            "{:>2} {:<22} {:>9.1} {:>9.4} {:>9}",
            shown_rank,
            fit.model.name(),
            fit.aic,
            fit.rms_mpa,
            mu0
        )?;
        for c in &fit.cases {
            write!(out, " {:>14.4}", c.r2)?;
        }
        let stable: Vec<String> = fit
            .stability
            .iter()
            .map(|s| match s.unstable_from {
                None => format!("{:.2}", s.stable_up_to),
                Some(_) => format!("{:.2}!", s.stable_up_to),
            })
            .collect();
        let params: Vec<String> = fit
            .param_names
            .iter()
            .zip(&fit.params)
            .zip(&fit.stderr)
            .map(|((n, v), s)| match s {
                Some(s) => format!("{n}={v:.4e}±{s:.1e}"),
                None => format!("{n}={v:.4e}±?"),
            })
            .collect();
        writeln!(out, "  {:<46}  {}", stable.join("/"), params.join(" "))?;
    }
    writeln!(
        out,
        "(`!`: Drucker stability lost beyond that stretch; checked up to the largest data stretch; \
         `-`: parameters not identifiable from these data, not ranked; mu0: initial shear modulus)"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::Value;

    /// A folder of Mooney-law curves (`points` rows per case), removed on drop.
    struct Data(PathBuf);

    impl Data {
        fn new(tag: &str, points: usize) -> Data {
            let dir = std::env::temp_dir()
                .join(format!("dicstream_identify_{tag}_{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let model = Model::Mooney;
            for (file, case) in [
                ("u.csv", LoadCase::Uniaxial),
                ("b.csv", LoadCase::Equibiaxial),
            ] {
                let mut text = String::from("stretch,nominal_stress_mpa\n");
                for k in 1..=points {
                    let stretch = 1.0 + 3.0 * k as f64 / points as f64;
                    let stress = model
                        .nominal_stress_mpa(&[0.2, 0.02], case, stretch)
                        .unwrap();
                    let wobble = 1.0 + 0.01 * ((k * 7919) % 13) as f64 / 13.0;
                    text.push_str(&format!("{stretch},{}\n", stress * wobble));
                }
                std::fs::write(dir.join(file), text).unwrap();
            }
            Data(dir)
        }

        fn args(&self, json: bool, max_fit_points: u64) -> IdentifyArgs {
            IdentifyArgs {
                uniaxial: Some(self.0.join("u.csv")),
                biaxial: Some(self.0.join("b.csv")),
                pure_shear: None,
                biaxial_general: None,
                model: Some("mooney,ogden:2".into()),
                residual: ResidualArg::Absolute,
                json,
                plot: None,
                all_models: false,
                cards: None,
                max_fit_points,
                skip_lines: 0,
                gauge_length_mm: None,
                section_mm2: None,
                threads: 2,
                fields: None,
                forces: None,
                femu: Default::default(),
            }
        }
    }

    impl Drop for Data {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn run_captured(args: IdentifyArgs, tty: bool) -> (String, String) {
        let (mut out, mut err) = (Vec::new(), Vec::new());
        run_with(args, &mut out, &mut err, tty).unwrap();
        (
            String::from_utf8(out).unwrap(),
            String::from_utf8(err).unwrap(),
        )
    }

    #[test]
    fn json_stdout_is_json_alone_even_with_progress_on_a_terminal() {
        let data = Data::new("json", 60);
        let (out, err) = run_captured(data.args(true, 1_000), true);
        let value: Value = serde_json::from_str(&out).expect("stdout is one JSON document");
        assert_eq!(value["fits"].as_array().unwrap().len(), 2);
        assert!(
            value.get("subsample").is_none(),
            "120 points are under the limit"
        );
        for line in ["[1/2] mooney: done in", "[2/2] ogden:2: done in"] {
            assert!(
                err.contains(line),
                "progress line `{line}` on stderr: {err}"
            );
        }
        // Not a terminal: nothing but the notes on stderr.
        let (out_quiet, err_quiet) = run_captured(data.args(true, 1_000), false);
        assert_eq!(out_quiet, out, "same JSON with or without progress");
        assert_eq!(err_quiet, "");
    }

    #[test]
    fn a_subsampled_fit_is_said_on_stderr_and_in_the_json() {
        let data = Data::new("subsample", 60);
        let (out, err) = run_captured(data.args(true, 40), false);
        let value: Value = serde_json::from_str(&out).expect("stdout is one JSON document");
        let s = &value["subsample"];
        assert_eq!(s["points_total"], 120);
        assert_eq!(s["max_fit_points"], 40);
        assert_eq!(s["points_fitted"], 40);
        assert!(
            err.contains("120 points exceed --max-fit-points 40: fitting a subsample of 40"),
            "{err}"
        );
        // The table says it too (on stderr), and its stdout is the table.
        let (table, err_table) = run_captured(data.args(false, 40), false);
        assert!(table.starts_with(" # model"), "{table}");
        assert!(err_table.contains("fitting a subsample of 40"));
    }

    #[test]
    fn progress_line_draws_each_start_in_place_and_ends_each_model() {
        let models = [Model::Mooney, Model::Ogden(3)];
        let mut err = Vec::new();
        let mut line = ProgressLine::new(&models, true, Duration::ZERO);
        line.update(&mut err, 0, None);
        line.update(&mut err, 1, None);
        for start in 1..=3 {
            let stage = FitStage::Screening { start, starts: 3 };
            line.update(&mut err, 1, Some(stage));
        }
        line.update(
            &mut err,
            1,
            Some(FitStage::Refining {
                start: 1,
                starts: 2,
            }),
        );
        line.finish(&mut err);
        let err = String::from_utf8(err).unwrap();
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 2, "one line per model: {err:?}");
        assert!(lines[0].ends_with("[1/2] mooney: done in 0.0 s"), "{err:?}");
        assert!(
            lines[1].contains("[2/2] ogden:3: screening start 3/3, "),
            "{err:?}"
        );
        assert!(
            lines[1].contains("[2/2] ogden:3: refining start 1/2, "),
            "{err:?}"
        );
        assert!(
            lines[1].ends_with("[2/2] ogden:3: done in 0.0 s"),
            "{err:?}"
        );
        assert!(err.matches("\r\x1b[2K").count() >= 7, "redrawn in place");
        // Off (stderr not a terminal): nothing at all.
        let mut quiet = Vec::new();
        let mut off = ProgressLine::new(&models, false, Duration::ZERO);
        off.update(
            &mut quiet,
            0,
            Some(FitStage::Screening {
                start: 1,
                starts: 3,
            }),
        );
        off.finish(&mut quiet);
        assert!(quiet.is_empty());
    }

    /// A general biaxial CSV from the Smactane law along ρ = 0.5 and ρ = 1 (and ρ = 0.5 along
    /// y) up to λ = 1.8, ±0.5 % stress noise; removed on drop.
    fn general_csv(tag: &str) -> (Data, PathBuf) {
        let dir =
            std::env::temp_dir().join(format!("dicstream_identify_{tag}_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let law = identifier::law::InvariantLaw::smactane();
        let mut text = String::from("lambda1,lambda2,nominal_stress1_mpa,nominal_stress2_mpa\n");
        let mut k = 0u64;
        for (ratio, swap) in [(0.5, false), (1.0, false), (0.5, true)] {
            for step in 1..=40 {
                k += 1;
                let e = 1.8f64.ln() * step as f64 / 40.0;
                let (mut l1, mut l2) = (e.exp(), (ratio * e).exp());
                if swap {
                    std::mem::swap(&mut l1, &mut l2);
                }
                let p = law.in_plane_stress(l1, l2).nominal_stress_mpa;
                let wobble =
                    |j: u64| 1.0 + 0.005 * (((k * 7919 + j * 104_729) % 21) as f64 / 10.0 - 1.0);
                text.push_str(&format!(
                    "{l1},{l2},{},{}\n",
                    p[0] * wobble(0),
                    p[1] * wobble(1)
                ));
            }
        }
        let path = dir.join("general.csv");
        std::fs::write(&path, text).unwrap();
        (Data(dir), path)
    }

    fn general_args(path: PathBuf, model: &str) -> IdentifyArgs {
        IdentifyArgs {
            uniaxial: None,
            biaxial: None,
            pure_shear: None,
            biaxial_general: Some(path),
            model: Some(model.into()),
            residual: ResidualArg::Absolute,
            json: true,
            plot: None,
            all_models: false,
            cards: None,
            max_fit_points: DEFAULT_MAX_FIT_POINTS as u64,
            skip_lines: 0,
            gauge_length_mm: None,
            section_mm2: None,
            threads: 1,
            fields: None,
            forces: None,
            femu: Default::default(),
        }
    }

    #[test]
    fn biaxial_general_csv_gives_the_true_law_within_two_percent() {
        let (_data, path) = general_csv("general");
        let (out, err) = run_captured(general_args(path.clone(), "ldr:2,2,mooney"), false);
        let value: Value = serde_json::from_str(&out).expect("stdout is one JSON document");
        let fits = value["fits"].as_array().unwrap();
        let best = fits
            .iter()
            .min_by(|a, b| {
                a["aic"]
                    .as_f64()
                    .unwrap()
                    .total_cmp(&b["aic"].as_f64().unwrap())
            })
            .unwrap();
        assert_eq!(best["model"], "lambert-diani-rey:2,2", "{out}");
        // Up to λ = 1.8 (I1 − 3 < 1.6) the quadratic term of ln f (true a2 = 1.4e-3) is not
        // told from zero: the fit says so and is not ranked.
        let warning = best["warning"].as_str().unwrap_or_default();
        assert!(warning.contains("σ ≥ |value| for a2"), "{warning}");
        assert!(
            best["rank"].is_null()
                && err.contains("lambert-diani-rey:2,2: parameters not identifiable")
        );
        assert!(
            best["rms_by_case_mpa"]["biaxial_general"].is_number(),
            "{out}"
        );
        let model = Model::parse(best["model"].as_str().unwrap()).unwrap();
        let params: Vec<f64> = model
            .param_names()
            .iter()
            .map(|n| best["params"][n].as_f64().unwrap())
            .collect();
        let law = identifier::law::InvariantLaw::smactane();
        let mut worst: f64 = 0.0;
        for ratio in [0.5, 1.0] {
            for k in 0..=50 {
                let l1 = 1.05 + 0.75 * k as f64 / 50.0;
                let l2 = (ratio * l1.ln()).exp();
                let truth = law.in_plane_stress(l1, l2).nominal_stress_mpa;
                let sigma = model.in_plane_cauchy_stress_mpa(&params, l1, l2).unwrap();
                for (fitted, truth) in [(sigma[0] / l1, truth[0]), (sigma[1] / l2, truth[1])] {
                    worst = worst.max((fitted - truth).abs() / truth);
                }
            }
        }
        eprintln!("identify --biaxial-general: worst |ΔP|/P = {worst:.4}");
        assert!(worst < 0.02, "worst relative error {worst}");
        // No canonical curve: the paper's route says why it did not run, on stderr only.
        assert!(err.contains("paper route"), "{err}");
        // The table names the group.
        let mut args = general_args(path, "mooney");
        args.json = false;
        let (table, _) = run_captured(args, false);
        assert!(table.contains("r2_biaxial_general"), "{table}");
    }

    #[test]
    fn biaxial_general_bad_input_is_a_clear_error_naming_the_line() {
        let (data, _) = general_csv("general_bad");
        let h = "lambda1,lambda2,nominal_stress1_mpa,nominal_stress2_mpa";
        for (text, needle) in [
            (
                format!("{h}\n1.2,1.1,0.3,0.2\n1.3,1.1,NaN,0.2\n"),
                "line 3, column 3 `nominal_stress1_mpa`: `NaN` is not a finite number",
            ),
            (format!("{h}\n1.2,1.1,0.3\n"), "line 2: expected 4 cells"),
            (
                "1.2,1.1,0.3,0.2\n1.3,1.2,0.4,0.3\n".to_string(),
                "line 1: expected a header",
            ),
            (
                format!("{h}\n1.2,0,0.3,0.2\n1.3,1.2,0.4,0.3\n"),
                "line 2: lambda2 0 must be > 0",
            ),
        ] {
            let path = data.0.join("bad.csv");
            std::fs::write(&path, &text).unwrap();
            let (mut out, mut err) = (Vec::new(), Vec::new());
            let error = run_with(
                general_args(path.clone(), "mooney"),
                &mut out,
                &mut err,
                false,
            )
            .unwrap_err();
            let message = format!("{error:#}");
            assert!(
                message.contains("reading general biaxial data"),
                "{message}"
            );
            assert!(message.contains(&path.display().to_string()), "{message}");
            assert!(message.contains(needle), "{needle}: {message}");
            assert!(out.is_empty(), "nothing on stdout on error");
        }
        let missing = general_args(data.0.join("missing.csv"), "mooney");
        let (mut out, mut err) = (Vec::new(), Vec::new());
        let message = format!(
            "{:#}",
            run_with(missing, &mut out, &mut err, false).unwrap_err()
        );
        assert!(message.contains("cannot read the file"), "{message}");
    }

    #[test]
    fn ogden3_on_uniaxial_data_alone_is_warned_and_not_ranked_and_cards_are_written() {
        let data = Data::new("loose", 60);
        let mut args = data.args(true, 1_000);
        args.biaxial = None;
        args.model = Some("ogden:3,mooney".into());
        args.cards = Some(data.0.join("cards"));
        args.plot = Some(data.0.join("plots"));
        let (out, err) = run_captured(args, false);
        let residuals = data.0.join("plots/residuals.png");
        assert!(
            err.contains(&format!("wrote {}", residuals.display())),
            "{err}"
        );
        assert!(image::open(&residuals).is_ok(), "residuals.png is a PNG");
        // Uniaxial data alone: the route cannot run; f(I1) is drawn with the identified law
        // alone, its title and stderr saying why there are no points.
        assert!(
            err.contains("f(I1) and g(I2) without data points: the paper's route did not run"),
            "{err}"
        );
        assert!(image::open(data.0.join("plots/f_I1.png")).is_ok(), "{err}");
        let value: Value = serde_json::from_str(&out).expect("stdout is one JSON document");
        let fits = value["fits"].as_array().unwrap();
        eprintln!("{err}");
        let ogden = fits.iter().find(|f| f["model"] == "ogden:3").unwrap();
        let mooney = fits.iter().find(|f| f["model"] == "mooney").unwrap();
        assert_eq!(ogden["identifiable"], false, "{ogden}");
        assert!(ogden["rank"].is_null());
        assert!(ogden["warning"]
            .as_str()
            .unwrap()
            .contains("not identifiable"));
        assert_eq!(mooney["identifiable"], true, "{mooney}");
        assert_eq!(mooney["rank"], 1);
        assert_eq!(fits[0]["model"], "mooney", "the identifiable fit first");
        assert!(
            err.contains("ogden:3: parameters not identifiable from these data"),
            "{err}"
        );
        // μ0 = 2 (C10 + C01) of the fitted Mooney law, near the true 0.44 MPa.
        let mu0 = mooney["initial_shear_modulus_mpa"].as_f64().unwrap();
        let (c10, c01) = (
            mooney["params"]["C10"].as_f64().unwrap(),
            mooney["params"]["C01"].as_f64().unwrap(),
        );
        assert!(
            (mu0 - 2.0 * (c10 + c01)).abs() < 1e-12 && (mu0 - 0.44).abs() < 0.05,
            "{mu0}"
        );
        let card = mooney["fe_cards"]["abaqus"].as_str().unwrap();
        assert!(card.contains("*HYPERELASTIC, MOONEY-RIVLIN\n"), "{card}");
        let written = std::fs::read_to_string(data.0.join("cards/abaqus_mooney.inp")).unwrap();
        assert_eq!(written, card);
        let ansys = std::fs::read_to_string(data.0.join("cards/ansys_ogden_3.mac")).unwrap();
        assert!(
            ansys.contains("! WARNING: parameters not identifiable"),
            "{ansys}"
        );
        assert!(ansys.contains("TB,HYPER,1,,3,OGDEN"), "{ansys}");
    }

    #[test]
    fn progress_text_names_model_start_and_elapsed() {
        let names = vec!["mooney".to_string(), "ogden:3".to_string()];
        let stage = FitStage::Screening {
            start: 12,
            starts: 286,
        };
        assert_eq!(
            progress_text(1, &names, Some(stage), 3.04),
            "[2/2] ogden:3: screening start 12/286, 3.0 s"
        );
    }
}
