//! `dicstream identify`: offline identification of hyperelastic potentials from CSV load cases
//! (`stretch,nominal_stress_mpa`), ranked by AIC; table, JSON, and optional PNG plots.

use anyhow::{bail, Context};
use identifier::data::{read_curve_csv, Curve, LoadCase};
use identifier::fit::{fit_ranked, Fit, FitOptions, ResidualKind};
use identifier::models::parse_model_list;
use identifier::report::fit_json;
use identifier::route::paper_route;
use serde_json::{json, Value};
use std::path::PathBuf;

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
}

pub fn run(args: IdentifyArgs) -> anyhow::Result<()> {
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
    let models = parse_model_list(&args.model).map_err(anyhow::Error::msg)?;
    let options = FitOptions {
        residual: match args.residual {
            ResidualArg::Absolute => ResidualKind::Absolute,
            ResidualArg::Relative => ResidualKind::Relative,
        },
        ..FitOptions::default()
    };
    let (fits, failures) = fit_ranked(&models, &curves, &options);
    let route = match paper_route(&curves, 2, 2) {
        Ok(route) => Some(route),
        Err(e) => {
            eprintln!("paper route (eqs. 20-25) not run: {e}");
            None
        }
    };

    if args.json {
        let fits_json: Vec<Value> = fits.iter().map(fit_json).collect();
        let failures_json: Vec<Value> = failures
            .iter()
            .map(|(m, e)| json!({"model": m.name(), "error": e.to_string()}))
            .collect();
        let mut out = json!({"fits": fits_json, "failures": failures_json});
        if let Some(r) = &route {
            out["paper_route"] = json!({"a": r.a, "b": r.b, "c": r.c});
        }
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_table(&fits, &curves);
        for (m, e) in &failures {
            eprintln!("not fitted: {m}: {e}");
        }
        if let Some(r) = &route {
            println!(
                "\npaper route (eqs 20-25, n = 2): ln f: a = {:?}; ln g: b = {:?}; g = Σ c_i/I2^i: c = {:?}",
                r.a, r.b, r.c
            );
        }
    }
    if let Some(dir) = &args.plot {
        let written = identifier::plot::write_plots(dir, &curves, &fits, route.as_ref())
            .with_context(|| format!("writing plots into {}", dir.display()))?;
        for path in written {
            eprintln!("wrote {}", path.display());
        }
    }
    if fits.is_empty() {
        bail!("no model could be fitted");
    }
    Ok(())
}

fn print_table(fits: &[Fit], curves: &[Curve]) {
    let cases: Vec<&str> = curves.iter().map(|c| c.case.name()).collect();
    print!("{:>2} {:<22} {:>9} {:>9}", "#", "model", "aic", "rms_mpa");
    for c in &cases {
        print!(" {:>14}", format!("r2_{c}"));
    }
    println!("  stable_up_to (uniaxial/equibiaxial/pure_shear)  params ± std");
    for (rank, fit) in fits.iter().enumerate() {
        print!(
            "{:>2} {:<22} {:>9.1} {:>9.4}",
            rank + 1,
            fit.model.name(),
            fit.aic,
            fit.rms_mpa
        );
        for c in &fit.cases {
            print!(" {:>14.4}", c.r2);
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
        println!("  {:<46}  {}", stable.join("/"), params.join(" "));
    }
    println!(
        "(`!`: Drucker stability lost beyond that stretch; checked up to the largest data stretch)"
    );
}
