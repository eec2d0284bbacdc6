//! `dicstream identify --fields DIR [--forces rig.csv]`: the field route offline on a run's
//! results folder (`identifier::saved_fields::fit_saved`, the live route's own feed and fit),
//! with the run's camera view and cruciform from its `config.toml`. Prints the ranked fits (or,
//! with `--json`, the JSON alone on stdout); a fit whose parameters the fields do not identify
//! (σ ≥ |value|, or the scaled Jacobian's condition number above 1e8:
//! `identifier::identifiability`) is said on stderr and left unranked, as the gauge route does;
//! a model the states cannot separate at all is refused by the fit with its condition number.

use super::identify::IdentifyArgs;
use anyhow::{bail, Context};
use identifier::identifiability::{ranks, Identifiability};
use identifier::models::parse_model_list;
use identifier::saved_fields::{fit_saved, SavedFit};
use serde_json::{json, Value};
use std::io::Write;
use std::path::Path;

/// Fits the saved fields of results folder `dir`; `out` gets the table or the JSON alone.
pub fn run(
    args: &IdentifyArgs,
    dir: &Path,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<()> {
    let others = [
        (args.uniaxial.is_some(), "--uniaxial"),
        (args.biaxial.is_some(), "--biaxial"),
        (args.pure_shear.is_some(), "--pure-shear"),
        (args.biaxial_general.is_some(), "--biaxial-general"),
        (args.gauge_length_mm.is_some(), "--gauge-length-mm"),
        (args.section_mm2.is_some(), "--section-mm2"),
        (args.all_models, "--all-models"),
        (args.cards.is_some(), "--cards"),
    ];
    if let Some((_, flag)) = others.iter().find(|(given, _)| *given) {
        bail!(
            "{flag} does not apply to --fields (a run's saved fields, fitted by the virtual \
             fields method); give it without --fields"
        );
    }
    let config = run_config(dir)?;
    let models = match &args.model {
        Some(list) => parse_model_list(list)?,
        None => config.identifier.models.0.clone(),
    };
    let saved = fit_saved(
        dir,
        &config.field_route_settings(),
        &models,
        args.forces.as_deref(),
    )?;
    if !saved.per_grip {
        writeln!(
            err,
            "note: {}/frames.csv has no grip forces of its own (an older run): each axis's mean \
             force taken for both its grips",
            dir.display()
        )?;
    }
    let identifiability: Vec<Identifiability> = saved
        .fits
        .fits
        .iter()
        .map(|f| f.identifiability.clone())
        .collect();
    for (fit, id) in saved.fits.fits.iter().zip(&identifiability) {
        if let Some(w) = id.warning() {
            writeln!(err, "{}: {w}", fit.model.name())?;
        }
    }
    for (model, why) in &saved.fits.refused {
        writeln!(err, "not fitted: {model}: {why}")?;
    }
    if args.json {
        let value = saved_json(dir, args.forces.as_deref(), &saved, &identifiability);
        writeln!(out, "{}", serde_json::to_string_pretty(&value)?)?;
    } else {
        print_table(out, &saved, &identifiability)?;
    }
    if let Some(plot_dir) = &args.plot {
        write_states(dir, plot_dir, &saved, err)?;
    }
    if saved.fits.fits.is_empty() {
        bail!(
            "no model could be fitted to the fields of {}",
            dir.display()
        );
    }
    Ok(())
}

/// `--plot DIR`: `states.csv` (each state of the kept frames with its contribution to the best
/// ranked fit) and `stretch_states.png` coloured by it; without a ranked fit, the saved fields'
/// nodes in one colour, said on `err`.
fn write_states(
    dir: &Path,
    plot_dir: &Path,
    saved: &SavedFit,
    err: &mut dyn Write,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(plot_dir)
        .with_context(|| format!("cannot create {}", plot_dir.display()))?;
    let csv = plot_dir.join("states.csv");
    let written = match &saved.states {
        Some(Ok(states)) => {
            wire::files::write_atomic(
                &csv,
                identifier::state_contributions::states_csv(states).as_bytes(),
            )?;
            Some((csv.as_path(), states.model.as_str()))
        }
        Some(Err(e)) => {
            writeln!(err, "states.csv not written: {e}")?;
            None
        }
        None => {
            writeln!(
                err,
                "states.csv not written: no ranked fit to contribute to"
            )?;
            None
        }
    };
    live::mechanics_figures::stretch_states_png(
        &dir.join("fields"),
        written.map(|w| w.0),
        written.map(|w| w.1),
        &plot_dir.join("stretch_states.png"),
    )?;
    Ok(())
}

/// The configuration of the run whose results folder is `dir` (its `config.toml`).
pub(super) fn run_config(dir: &Path) -> anyhow::Result<live::RunConfig> {
    live::RunConfig::read(Some(&dir.join("config.toml")))
        .with_context(|| format!("{}: the run's configuration", dir.display()))
}

fn saved_json(
    dir: &Path,
    forces: Option<&Path>,
    saved: &SavedFit,
    identifiability: &[Identifiability],
) -> Value {
    let mut value = identifier::process::fits_json(&saved.fits);
    if let Some(fits) = value["fits"].as_array_mut() {
        for ((fit, id), rank) in fits
            .iter_mut()
            .zip(identifiability)
            .zip(ranks(identifiability.iter()))
        {
            fit["rank"] = json!(rank);
            fit["warning"] = json!(id.warning());
        }
    }
    value["source"] = json!({
        "fields": dir.display().to_string(),
        "forces": forces.map_or_else(|| dir.join("frames.csv").display().to_string(), |p| p.display().to_string()),
        "per_grip_forces": saved.per_grip,
    });
    value["fields_read"] = json!(saved.fields_read);
    value["counters"] = json!(saved.counters);
    value["last_dropped"] = json!(saved.last_dropped);
    value["force_balance"] = json!(saved.force_balance);
    value
}

fn print_table(
    out: &mut dyn Write,
    saved: &SavedFit,
    identifiability: &[Identifiability],
) -> std::io::Result<()> {
    let fits = &saved.fits;
    let c = &saved.counters;
    writeln!(
        out,
        "{} frames fitted of {} field files ({} not a new loading state, {} with a grip at rest, \
         {} thinned); {} virtual fields dropped; stretches reached: major {:.3}, minor {:.3}; \
         in uniaxial states {:.3}, equibiaxial {:.3}, pure shear {:.3}",
        fits.frames,
        saved.fields_read,
        c.not_loading,
        c.grips_unloaded,
        c.thinned,
        c.virtual_fields_dropped,
        fits.reach.max_stretches[0],
        fits.reach.max_stretches[1],
        fits.reach.uniaxial,
        fits.reach.equibiaxial,
        fits.reach.pure_shear,
    )?;
    writeln!(
        out,
        "{:>2} {:<22} {:>9} {:>9} {:>9} {:>9} {:>10}  params ± std",
        "#", "model", "bic", "aic", "rms_n", "equations", "condition"
    )?;
    for ((fit, rank), _) in fits
        .fits
        .iter()
        .zip(ranks(identifiability.iter()))
        .zip(identifiability)
    {
        let params: Vec<String> = fit
            .model
            .param_names()
            .iter()
            .zip(&fit.fit.params)
            .zip(&fit.fit.sigma)
            .map(|((n, v), s)| format!("{n}={v:.4e}±{s:.1e}"))
            .collect();
        writeln!(
            out,
            "{:>2} {:<22} {:>9.1} {:>9.1} {:>9.3} {:>9} {:>10.2e}  {}",
            rank.map_or("-".to_string(), |r| r.to_string()),
            fit.model.name(),
            fit.bic,
            fit.aic,
            fit.fit.rms_n,
            fit.fit.equations,
            fit.fit.condition,
            params.join(" ")
        )?;
    }
    if let Some(window) = &fits.window {
        writeln!(out, "{}", window.describe())?;
    }
    writeln!(
        out,
        "(virtual fields method: each equation a virtual field's internal work against its grip's \
         force, N; `-`: parameters not identifiable from these fields, not ranked)"
    )
}

/// The `identify --fields` tests and their helpers (a results folder, the command run
/// captured), shared with `identify_femu`'s.
#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use clap::Parser;
    use identifier::data::LoadCase;
    use identifier::models::Model;
    use std::path::PathBuf;

    #[derive(Parser)]
    pub(in crate::cmd) struct Cli {
        #[command(flatten)]
        pub args: IdentifyArgs,
    }

    /// A results folder of homogeneous equibiaxial fields (512 px square images, a 31 x 31
    /// mesh 16 px apart) whose grips pull what an arm of the default cruciform (100 mm wide, 2
    /// mm thick) carries under a Mooney law; removed on drop.
    pub(in crate::cmd) struct RunDir(pub PathBuf);

    impl Drop for RunDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    const HEADER: &str = "x,y,u,v,exx,eyy,exy,score,iterations,status,du_dx,du_dy,dv_dx,dv_dy";

    fn run_dir(tag: &str, mm_per_px: f64, stretches: &[f64]) -> RunDir {
        let dir =
            std::env::temp_dir().join(format!("identify_fields_{tag}_{}", std::process::id()));
        std::fs::create_dir_all(dir.join("fields")).unwrap();
        std::fs::write(
            dir.join("config.toml"),
            format!("[camera]\nwidth_px = 512\nheight_px = 512\nmm_per_px = {mm_per_px}\n[identifier]\nmodels = \"mooney\"\n"),
        )
        .unwrap();
        let mut frames = String::from(
            "frame_id,t_sim_s,sequence_id,force_x+_n,force_x-_n,force_y+_n,force_y-_n\n",
        );
        for (k, &l) in stretches.iter().enumerate() {
            let frame = 10 * (k + 1);
            let force = 100.0
                * 2.0
                * Model::Mooney
                    .nominal_stress_mpa(&[0.3, 0.05], LoadCase::Equibiaxial, l)
                    .unwrap();
            frames += &format!("{frame},{},0,{force},{force},{force},{force}\n", k as f64);
            let mut field = format!("{HEADER}\n");
            for row in 0..31 {
                for col in 0..31 {
                    let (x, y) = (16 + 16 * col, 16 + 16 * row);
                    let g = l - 1.0;
                    field += &format!("{x},{y},0,0,0,0,0,1,3,ok,{g},0,0,{g}\n");
                }
            }
            std::fs::write(dir.join(format!("fields/field_{frame:06}.csv")), field).unwrap();
        }
        std::fs::write(dir.join("frames.csv"), frames).unwrap();
        RunDir(dir)
    }

    /// `identify --fields DIR extra...`: its stdout, stderr and result.
    pub(in crate::cmd) fn identify(
        dir: &Path,
        extra: &[&str],
    ) -> (String, String, anyhow::Result<()>) {
        let mut argv = vec!["identify".to_string(), "--fields".into()];
        argv.push(dir.display().to_string());
        argv.extend(extra.iter().map(|s| s.to_string()));
        let cli = Cli::try_parse_from(argv).unwrap();
        let (mut out, mut err) = (vec![], vec![]);
        let result = super::super::identify::run_with(cli.args, &mut out, &mut err, false);
        (
            String::from_utf8(out).unwrap(),
            String::from_utf8(err).unwrap(),
            result,
        )
    }

    /// Rewrites the file at `path` line by line (None: the line left out); returns its text
    /// before.
    pub(in crate::cmd) fn edit_lines(path: &Path, edit: impl Fn(&str) -> Option<String>) -> String {
        let text = std::fs::read_to_string(path).unwrap();
        let edited: String = text.lines().filter_map(edit).map(|l| l + "\n").collect();
        std::fs::write(path, edited).unwrap();
        text
    }

    /// `identify --fields DIR extra...` fails with an error holding every one of `wants`.
    fn refused(dir: &Path, extra: &[&str], wants: &[&str]) {
        let e = format!("{:#}", identify(dir, extra).2.unwrap_err());
        for want in wants {
            assert!(e.contains(want), "{want:?} not in: {e}");
        }
    }

    /// The JSON alone on stdout (the notes on stderr), every frame used, each fit's rank and
    /// warning in agreement; the table says the frames. (A homogeneous field is no cruciform's
    /// equilibrium: its central ramps do not balance the grips' forces, so the law is not
    /// asserted here; tests/field_route.rs fits a run's finite-element fields.)
    #[test]
    fn json_alone_on_stdout_and_the_table_says_the_frames() {
        let run = run_dir("json", 0.36, &[1.05, 1.1, 1.15, 1.2, 1.25]);
        let (out, err, result) = identify(&run.0, &["--json"]);
        result.unwrap();
        let value: Value = serde_json::from_str(&out).expect("stdout is JSON alone");
        assert_eq!(value["frames"], 5, "{value}");
        assert_eq!(value["fields_read"], 5);
        assert_eq!(value["counters"]["kept"], 5);
        assert_eq!(value["source"]["per_grip_forces"], true);
        // Equibiaxial fields: only the equibiaxial case was reached.
        let reach = &value["reach"];
        assert_eq!(reach["max_stretches"], json!([1.25, 1.25]));
        assert_eq!(reach["equibiaxial"], 1.25, "{reach}");
        assert_eq!(
            (&reach["uniaxial"], &reach["pure_shear"]),
            (&json!(1.0), &json!(1.0))
        );
        let fit = &value["fits"][0];
        assert_eq!(fit["model"], "mooney", "the run's models: {value}");
        assert_eq!(fit["rank"].is_null(), !fit["warning"].is_null(), "{value}");
        if let Some(warning) = fit["warning"].as_str() {
            assert!(err.contains(&format!("mooney: {warning}")), "{err}");
        }
        let (table, _, result) = identify(&run.0, &[]);
        result.unwrap();
        assert!(
            table.contains("5 frames fitted of 5 field files"),
            "{table}"
        );
        assert!(table.contains(" mooney "), "{table}");
    }

    #[test]
    fn a_field_without_gradients_is_named() {
        let run = run_dir("no_gradients", 0.36, &[1.05, 1.1, 1.15]);
        // The first ten columns only, as fields were written before the gradients.
        edit_lines(&run.0.join("fields/field_000020.csv"), |l| {
            Some(l.split(',').take(10).collect::<Vec<_>>().join(","))
        });
        refused(
            &run.0,
            &["--json"],
            &["field_000020.csv: line 1: no displacement gradient columns (du_dx, du_dy, dv_dx, dv_dy missing)"],
        );
    }

    #[test]
    fn forces_without_a_matching_frame_or_time_are_named() {
        let run = run_dir("no_forces", 0.36, &[1.05, 1.1, 1.15]);
        // frames.csv without frame 30's row.
        let frames = run.0.join("frames.csv");
        let text = edit_lines(&frames, |l| (!l.starts_with("30,")).then(|| l.to_string()));
        refused(&run.0, &[], &["field_000030.csv: frame 30 has no row in"]);
        // The rig's log by time: frame 20 (rig time 1 s) after the log's end.
        std::fs::write(&frames, text).unwrap();
        let rig = run.0.join("rig.csv");
        std::fs::write(
            &rig,
            "t_s,X+_force_n,X-_force_n,Y+_force_n,Y-_force_n\n0,1,1,1,1\n0.5,2,2,2,2\n",
        )
        .unwrap();
        refused(
            &run.0,
            &["--forces", rig.to_str().unwrap()],
            &[
                "frames.csv: line 3: frame 20: rig time 1 s is outside",
                "(0 to 0.5 s): no forces to pair with it",
            ],
        );
    }

    #[test]
    fn a_view_that_crosses_no_arm_is_named() {
        // 512 px at 0.05 mm/px: ±12.8 mm, inside the central square.
        let run = run_dir("no_arm", 0.05, &[1.05, 1.1, 1.15]);
        refused(
            &run.0,
            &[],
            &["field_000010.csv: the field of view", "crosses no arm"],
        );
    }

    #[test]
    fn too_few_distinct_states_are_refused_with_the_condition_number() {
        // One loading state thrice: one frame kept.
        let run = run_dir("one_state", 0.36, &[1.1, 1.1, 1.1]);
        refused(
            &run.0,
            &[],
            &[
                "1 frame(s) kept of 3 field file(s), 3 needed for a fit (not loading: 2",
                "too few distinct states",
            ],
        );
        // Equibiaxial states alone, close together: more parameters than they separate.
        let run = run_dir("close_states", 0.36, &[1.002, 1.004, 1.006, 1.008]);
        let (out, err, result) = identify(&run.0, &["--model", "mooney,rivlin:10,01,11,20,02"]);
        result.unwrap();
        assert!(
            err.contains("not fitted: rivlin:10,01,11,20,02: the states the field reached do not separate the 5 parameters of rivlin:10,01,11,20,02: condition number"),
            "{err}"
        );
        assert!(!out.contains("rivlin"), "not ranked: {out}");
    }

    /// `--plot DIR`: `stretch_states.png`, and `states.csv` when a fit is ranked (a state per
    /// node and kept frame, its contributions summing to 1); said on stderr otherwise.
    #[test]
    fn plot_writes_the_states_coloured_by_their_contribution() {
        let run = run_dir("states", 0.36, &[1.05, 1.1, 1.15, 1.2, 1.25]);
        let plots = run.0.join("plots");
        let (out, err, result) = identify(&run.0, &["--json", "--plot", plots.to_str().unwrap()]);
        result.unwrap();
        let value: Value = serde_json::from_str(&out).unwrap();
        assert!(plots.join("stretch_states.png").exists());
        let ranked = value["fits"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| !f["rank"].is_null());
        let csv = plots.join("states.csv");
        if ranked {
            let text = std::fs::read_to_string(&csv).unwrap();
            let mut lines = text.lines();
            assert_eq!(
                lines.next().unwrap(),
                format!(
                    "{},share_C10,share_C01",
                    identifier::state_contributions::STATES_CSV_HEADER
                )
            );
            let rows: Vec<Vec<f64>> = lines
                .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
                .collect();
            // Every node of the 5 kept frames (31 x 31 each), no hole to fill.
            assert_eq!(rows.len(), 5 * 31 * 31);
            let total: f64 = rows.iter().map(|r| r[8]).sum();
            assert!((total - 1.0).abs() < 1e-9, "{total}");
        } else {
            assert!(!csv.exists());
            assert!(
                err.contains("states.csv not written: no ranked fit"),
                "{err}"
            );
        }
        // --all-models is the gauge route's.
        let (_, _, result) = identify(&run.0, &["--plot", plots.to_str().unwrap(), "--all-models"]);
        assert!(format!("{:#}", result.unwrap_err()).contains("--all-models does not apply"));
    }
}
