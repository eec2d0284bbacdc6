//! `dicstream identify --fields DIR --femu`: finite-element model updating on a run's saved
//! fields (`identifier::femu`), the reference of the virtual fields method, offline only. The
//! frames are the field route's (`identifier::saved_fields::fit_saved`: the same kept frames,
//! forces from `frames.csv` or `--forces`); the model family is `--model` (one) or the field
//! route's best ranked, started from the virtual fields method's parameters. Prints both
//! laws, what each fit cost, and the force balance (or, with `--json`, the JSON alone).

use super::identify::IdentifyArgs;
use anyhow::{bail, Context};
use identifier::femu::{Femu, FemuFit, FemuSettings};
use identifier::models::{parse_model_list, Model};
use identifier::saved_fields::fit_saved;
use serde_json::{json, Map, Value};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// The options of `--femu`.
#[derive(clap::Args, Debug, Default)]
pub struct FemuArgs {
    /// With `--fields`: finite-element model updating as well (slow: a finite-element solve of
    /// every kept frame per evaluation), of one model family (`--model`, or the virtual fields
    /// method's best ranked).
    #[arg(long, requires = "fields")]
    pub femu: bool,
    /// FEMU's force noise σ_F, N: each force residual is divided by it.
    #[arg(long, value_name = "N", requires = "femu", default_value_t = FemuSettings::DEFAULT_FORCE_SIGMA_N)]
    pub force_sigma_n: f64,
    /// FEMU's displacement noise σ_u, px (mm through the run's scale): each displacement
    /// residual is divided by it.
    #[arg(long, value_name = "PX", requires = "femu", default_value_t = FemuSettings::DEFAULT_DISPLACEMENT_SIGMA_PX)]
    pub displacement_sigma_px: f64,
    /// FEMU's element size, mm (default: the run's `[specimen.geometry]` cruciform's).
    #[arg(long, value_name = "MM", requires = "femu")]
    pub element_size_mm: Option<f64>,
}

/// FEMU of the saved fields of results folder `dir`; `out` gets the table or the JSON alone.
pub fn run(
    args: &IdentifyArgs,
    dir: &Path,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<()> {
    let config = super::identify_fields::run_config(dir)?;
    let models = match &args.model {
        Some(list) => {
            let models = parse_model_list(list)?;
            if models.len() != 1 {
                bail!(
                    "--femu fits one model family ({} given in --model {list}): each costs a \
                     finite-element solve of every frame per evaluation",
                    models.len()
                );
            }
            models
        }
        None => config.identifier.models.0.clone(),
    };
    let route_settings = config.field_route_settings();
    let saved = fit_saved(dir, &route_settings, &models, args.forces.as_deref())?;
    for (model, why) in &saved.fits.refused {
        writeln!(
            err,
            "not fitted by the virtual fields method: {model}: {why}"
        )?;
    }
    let vfm = match &args.model {
        Some(_) => saved.fits.fits.first(),
        None => saved.fits.fits.iter().find(|f| f.ranked()),
    };
    let Some(vfm) = vfm else {
        bail!(
            "the virtual fields method fitted no {} to the fields of {}: FEMU starts from its \
             parameters",
            models.first().map_or("model".to_string(), Model::name),
            dir.display()
        );
    };
    let mut cruciform = route_settings.cruciform;
    if let Some(size) = args.femu.element_size_mm {
        cruciform.element_size_mm = size;
    }
    let settings = FemuSettings {
        cruciform,
        force_sigma_n: args.femu.force_sigma_n,
        displacement_sigma_mm: args.femu.displacement_sigma_px * route_settings.mm_per_px,
        newton: membrane::NewtonSettings::default(),
    };
    let started = Instant::now();
    let femu = Femu::new(&saved.kept_frames, settings.clone())
        .with_context(|| format!("{}: FEMU's model of the view", dir.display()))?;
    let fit = femu
        .fit(&vfm.model, &vfm.fit.params)
        .with_context(|| format!("{}: FEMU of {}", dir.display(), vfm.model.name()))?;
    let femu_s = started.elapsed().as_secs_f64();
    let named = |values: &[f64]| -> Map<String, Value> {
        vfm.model
            .param_names()
            .into_iter()
            .zip(values.iter().map(|v| json!(v.is_finite().then_some(*v))))
            .collect()
    };
    if args.json {
        let value = json!({
            "model": vfm.model.name(),
            "frames": fit.frames,
            "femu": {
                "params": named(&fit.params),
                "sigma": named(&fit.sigma),
                "condition": fit.condition,
                "rms_force_n": fit.rms_force_n,
                "rms_displacement_mm": fit.rms_displacement_mm,
                "force_residuals": fit.force_residuals,
                "displacement_residuals": fit.displacement_residuals,
                "iterations": fit.iterations,
                "evaluations": fit.evaluations,
                "elements": femu.mesh().elements.len(),
                "weights": {
                    "force_sigma_n": settings.force_sigma_n,
                    "displacement_sigma_mm": settings.displacement_sigma_mm,
                },
                "seconds": femu_s,
                "balance": fit.balance,
            },
            "vfm": {
                "params": named(&vfm.fit.params),
                "sigma": named(&vfm.fit.sigma),
                "equations": vfm.fit.equations,
                "seconds_all_models": saved.fit_s,
                "models": models.len(),
            },
            "source": {
                "fields": dir.display().to_string(),
                "forces": args.forces.as_ref().map_or_else(|| dir.join("frames.csv").display().to_string(), |p| p.display().to_string()),
            },
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&value)?)?;
    } else {
        print_table(
            out,
            &vfm.model,
            &fit,
            &vfm.fit.params,
            (femu_s, saved.fit_s),
        )?;
    }
    Ok(())
}

fn print_table(
    out: &mut dyn Write,
    model: &Model,
    fit: &FemuFit,
    vfm_params: &[f64],
    (femu_s, vfm_s): (f64, f64),
) -> std::io::Result<()> {
    writeln!(
        out,
        "FEMU of {} over {} frames: {} force and {} displacement residuals, {} iterations, {} \
         finite-element solves of all frames, {femu_s:.2} s (the virtual fields method: \
         {vfm_s:.3} s)",
        model.name(),
        fit.frames,
        fit.force_residuals,
        fit.displacement_residuals,
        fit.iterations,
        fit.evaluations
    )?;
    writeln!(
        out,
        "{:<10} {:>14} {:>11} {:>14}",
        "param", "femu", "± std", "vfm"
    )?;
    for (((name, p), s), v) in model
        .param_names()
        .iter()
        .zip(&fit.params)
        .zip(&fit.sigma)
        .zip(vfm_params)
    {
        writeln!(out, "{name:<10} {p:>14.6e} {s:>11.1e} {v:>14.6e}")?;
    }
    writeln!(
        out,
        "rms force {:.3} N, rms displacement {:.2e} mm, condition {:.2e}",
        fit.rms_force_n, fit.rms_displacement_mm, fit.condition
    )?;
    for b in &fit.balance {
        writeln!(
            out,
            "frame {:>6} {:<3} measured {:>10.2} N, computed {:>10.2} N",
            b.frame_id, b.grip, b.measured_n, b.computed_n
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::identify_fields::tests::{edit_lines, identify, Cli, RunDir};
    use super::*;
    use clap::Parser;
    use membrane::specimens::cruciform::CruciformGeometry;
    use membrane::{GripStretch, InvariantDerivatives, Membrane, NewtonSettings, Probe, Wrinkling};

    const TRUTH: [f64; 2] = [0.3, 0.05];
    /// 512 px at 0.36 mm/px (±92 mm), nodes every 8 px from 16 to 496 px.
    const MM_PER_PX: f64 = 0.36;
    const CENTRE_PX: f64 = 255.5;
    const STRETCHES: [(f64, f64); 4] = [(1.1, 1.1), (1.2, 1.15), (1.25, 1.3), (1.4, 1.35)];

    /// A run's results folder whose fields are the default cruciform's finite-element solution
    /// under Mooney-Rivlin (C10 0.3, C01 0.05 MPa) as the run's camera maps it (node px to mm
    /// through `View::centred`), nodes off the specimen refused, and each grip's force.
    fn fe_run_dir(tag: &str) -> RunDir {
        let dir = std::env::temp_dir().join(format!("identify_femu_{tag}_{}", std::process::id()));
        std::fs::create_dir_all(dir.join("fields")).unwrap();
        std::fs::write(
            dir.join("config.toml"),
            format!(
                "[camera]\nwidth_px = 512\nheight_px = 512\nmm_per_px = {MM_PER_PX}\n\
                 [identifier]\nmodels = \"mooney\"\n"
            ),
        )
        .unwrap();
        let specimen = CruciformGeometry::default().mesh().unwrap();
        let model = Model::Mooney;
        let law = InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(&TRUTH, i1, i2));
        let sheet = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::default()).unwrap();
        let probe = Probe::new(&specimen.mesh);
        let nodes_px: Vec<[f64; 2]> = (0..61 * 61)
            .map(|k| [16.0 + 8.0 * (k % 61) as f64, 16.0 + 8.0 * (k / 61) as f64])
            .collect();
        let mut frames = String::from(
            "frame_id,t_sim_s,sequence_id,force_x+_n,force_x-_n,force_y+_n,force_y-_n\n",
        );
        for (k, &(x, y)) in STRETCHES.iter().enumerate() {
            let clamps = specimen.clamps_at(GripStretch { x, y });
            let solved = membrane::solve(&sheet, &clamps, NewtonSettings::default()).unwrap();
            let force = |name: &str| {
                let grip = specimen.grip(name).unwrap();
                let f = solved.grip_force_n(&grip.nodes);
                f[0] * grip.axis[0] + f[1] * grip.axis[1]
            };
            let frame = 10 * (k + 1);
            frames += &format!(
                "{frame},{k},0,{},{},{},{}\n",
                force("x+"),
                force("x-"),
                force("y+"),
                force("y-")
            );
            let mut field = String::from(
                "x,y,u,v,exx,eyy,exy,score,iterations,status,du_dx,du_dy,dv_dx,dv_dy\n",
            );
            for p in &nodes_px {
                let x_mm = [
                    (p[0] - CENTRE_PX) * MM_PER_PX,
                    (p[1] - CENTRE_PX) * MM_PER_PX,
                ];
                match probe.sample(&solved.displacement_mm, x_mm) {
                    Some(s) => {
                        let [u, v] = s.displacement_mm.map(|u| u / MM_PER_PX);
                        let f = s.f;
                        field += &format!(
                            "{},{},{u},{v},0,0,0,1,3,ok,{},{},{},{}\n",
                            p[0],
                            p[1],
                            f[0][0] - 1.0,
                            f[0][1],
                            f[1][0],
                            f[1][1] - 1.0
                        );
                    }
                    None => {
                        field += &format!("{},{},0,0,0,0,0,0,0,low_contrast,0,0,0,0\n", p[0], p[1])
                    }
                }
            }
            std::fs::write(dir.join(format!("fields/field_{frame:06}.csv")), field).unwrap();
        }
        std::fs::write(dir.join("frames.csv"), frames).unwrap();
        RunDir(dir)
    }

    /// A run's finite-element fields through the whole offline path (field files, frames.csv,
    /// the camera's px to mm): FEMU gives the law back, the JSON alone on stdout; then bad
    /// input (two families, an edge whose nodes are lost, `--femu` without `--fields`).
    #[test]
    fn femu_on_a_runs_fields_gives_the_law_back_and_names_bad_input() {
        let run = fe_run_dir("law");
        let (out, _, result) = identify(&run.0, &["--femu", "--json"]);
        result.unwrap();
        let value: Value = serde_json::from_str(&out).expect("stdout is JSON alone");
        assert_eq!(value["model"], "mooney", "{value}");
        assert_eq!(value["frames"], 4, "{value}");
        let params = &value["femu"]["params"];
        let errors: Vec<f64> = Model::Mooney
            .param_names()
            .iter()
            .zip(TRUTH)
            .map(|(name, want)| ((params[name].as_f64().unwrap() - want) / want).abs())
            .collect();
        println!("FEMU from a run's fields (10 mm elements, 2.88 mm grid): relative errors {errors:?}; {value}");
        assert!(errors.iter().all(|&e| e < 1e-3), "{errors:?} {value}");
        assert_eq!(value["femu"]["balance"].as_array().unwrap().len(), 16);
        let e = identify(&run.0, &["--femu", "--model", "mooney,yeoh"])
            .2
            .unwrap_err();
        assert!(
            e.to_string().contains("--femu fits one model family"),
            "{e}"
        );
        // Frame 20 lost the nodes of the last 5 columns (x ≥ 464 px, the x+ arm's edge).
        edit_lines(&run.0.join("fields/field_000020.csv"), |line| {
            let x: f64 = line.split(',').next()?.parse().unwrap_or(0.0);
            Some(if x >= 464.0 {
                line.replace(",ok,", ",low_contrast,")
            } else {
                line.to_string()
            })
        });
        let e = format!("{:#}", identify(&run.0, &["--femu"]).2.unwrap_err());
        assert!(
            e.contains("frame 20, arm x+") && e.contains("too few valid boundary nodes"),
            "{e}"
        );
        assert!(Cli::try_parse_from(["identify", "--femu"]).is_err());
    }
}
