//! `dicstream identify`: offline identification of hyperelastic potentials from CSV load cases
//! (`stretch,nominal_stress_mpa`), ranked by AIC; table, JSON, and optional PNG plots.
//!
//! Above `--max-fit-points` the fit runs on a load-path-preserving subsample, said on stderr and
//! in the JSON. When stderr is a terminal, one progress line per model (model, start k/n,
//! elapsed) is drawn there; never on stdout, which holds the JSON alone with `--json`.

use anyhow::{bail, Context};
use identifier::data::{read_curve_csv, Curve, LoadCase};
use identifier::fit::{
    evaluate, fit_ranked_with_progress, Fit, FitOptions, FitStage, ResidualKind,
};
use identifier::models::{parse_model_list, Model};
use identifier::report::fit_json;
use identifier::route::paper_route;
use identifier::subsample::{subsample, Subsample, DEFAULT_MAX_FIT_POINTS};
use serde_json::{json, Value};
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
    /// Models: NAME[,NAME...] (e.g. mooney,ogden:3,rivlin:10,01,11) or `all`.
    #[arg(long, default_value = "all")]
    pub model: String,
    /// Residual measure of the fit.
    #[arg(long, value_enum, default_value = "absolute")]
    pub residual: ResidualArg,
    /// Print JSON instead of the ranked table.
    #[arg(long)]
    pub json: bool,
    /// Write PNG plots (data and fitted curves, f(I1) and g(I2)) into this folder.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Largest number of points fitted (all load cases together); above it the fit runs on a
    /// deterministic subsample keeping each curve's ends and shape (said on stderr and in the
    /// JSON; RMS and R² are still over every point).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_FIT_POINTS as u64, value_parser = clap::value_parser!(u64).range(2..))]
    pub max_fit_points: u64,
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
    let mut curves: Vec<Curve> = Vec::new();
    for (path, case) in [
        (&args.uniaxial, LoadCase::Uniaxial),
        (&args.biaxial, LoadCase::Equibiaxial),
        (&args.pure_shear, LoadCase::PureShear),
    ] {
        if let Some(path) = path {
            curves
                .push(read_curve_csv(path, case).with_context(|| format!("reading {case} data"))?);
        }
    }
    if curves.is_empty() {
        bail!("no data: give at least one of --uniaxial, --biaxial, --pure-shear");
    }
    let models = parse_model_list(&args.model)?;
    let threads = usize::try_from(args.threads).unwrap_or(1);
    let options = FitOptions {
        residual: match args.residual {
            ResidualArg::Absolute => ResidualKind::Absolute,
            ResidualArg::Relative => ResidualKind::Relative,
        },
        threads,
        ..FitOptions::default()
    };
    let max_fit_points = usize::try_from(args.max_fit_points).unwrap_or(usize::MAX);
    let subsampled = subsample(&curves, max_fit_points);
    if let Some((_, s)) = &subsampled {
        writeln!(
            err,
            "{} points exceed --max-fit-points {}: fitting a subsample of {} (each curve's ends and shape kept); RMS and R² over every point",
            s.points_total, s.max_points, s.points_fitted
        )?;
    }
    let fitted_curves = subsampled.as_ref().map_or(&curves[..], |(c, _)| &c[..]);
    let mut line = ProgressLine::new(&models, progress, PROGRESS_REDRAW);
    let (mut fits, failures) =
        fit_ranked_with_progress(&models, fitted_curves, &options, &mut |index, stage| {
            line.update(err, index, stage)
        });
    line.finish(err);
    if subsampled.is_some() {
        for fit in &mut fits {
            (fit.rms_mpa, fit.cases) = evaluate(&fit.model, &fit.params, &curves);
        }
    }
    let route = match paper_route(&curves, 2, 2) {
        Ok(route) => Some(route),
        Err(e) => {
            writeln!(err, "paper route (eqs. 20-25) not run: {e}")?;
            None
        }
    };

    if args.json {
        let fits_json: Vec<Value> = fits.iter().map(fit_json).collect();
        let failures_json: Vec<Value> = failures
            .iter()
            .map(|(m, e)| json!({"model": m.name(), "error": e.to_string()}))
            .collect();
        let mut json_out = json!({"fits": fits_json, "failures": failures_json});
        if let Some(r) = &route {
            json_out["paper_route"] = json!({"a": r.a, "b": r.b, "c": r.c});
        }
        if let Some((_, s)) = &subsampled {
            json_out["subsample"] = subsample_json(s);
        }
        writeln!(out, "{}", serde_json::to_string_pretty(&json_out)?)?;
    } else {
        print_table(out, &fits, &curves)?;
        for (m, e) in &failures {
            writeln!(err, "not fitted: {m}: {e}")?;
        }
        if let Some(r) = &route {
            writeln!(
                out,
                "\npaper route (eqs 20-25, n = 2): ln f: a = {:?}; ln g: b = {:?}; g = Σ c_i/I2^i: c = {:?}",
                r.a, r.b, r.c
            )?;
        }
    }
    if let Some(dir) = &args.plot {
        let written = identifier::plot::write_plots(dir, &curves, &fits, route.as_ref())
            .with_context(|| format!("writing plots into {}", dir.display()))?;
        for path in written {
            writeln!(err, "wrote {}", path.display())?;
        }
    }
    if fits.is_empty() {
        bail!("no model could be fitted");
    }
    Ok(())
}

/// The JSON note of a subsampled fit.
fn subsample_json(s: &Subsample) -> Value {
    json!({
        "points_total": s.points_total,
        "points_fitted": s.points_fitted,
        "max_fit_points": s.max_points,
        "note": "parameters, stderr, objective and aic from the fitted subsample (each curve's ends and shape kept); rms and r2 over every point",
    })
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

fn print_table(out: &mut dyn Write, fits: &[Fit], curves: &[Curve]) -> std::io::Result<()> {
    let cases: Vec<&str> = curves.iter().map(|c| c.case.name()).collect();
    write!(
        out,
        "{:>2} {:<22} {:>9} {:>9}",
        "#", "model", "aic", "rms_mpa"
    )?;
    for c in &cases {
        write!(out, " {:>14}", format!("r2_{c}"))?;
    }
    writeln!(
        out,
        "  stable_up_to (uniaxial/equibiaxial/pure_shear)  params ± std"
    )?;
    for (rank, fit) in fits.iter().enumerate() {
        write!(
            out,
            "{:>2} {:<22} {:>9.1} {:>9.4}",
            rank + 1,
            fit.model.name(),
            fit.aic,
            fit.rms_mpa
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
        "(`!`: Drucker stability lost beyond that stretch; checked up to the largest data stretch)"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

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
                model: "mooney,ogden:2".into(),
                residual: ResidualArg::Absolute,
                json,
                plot: None,
                max_fit_points,
                threads: 2,
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
