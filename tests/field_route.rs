//! The field route in the live bench (issue 25 deliverable 3): `dicstream run` on the
//! finite-element cruciform filmed wide enough to cross its arms, one equibiaxial test, the
//! identifier running both routes; the field route's law against the true one in
//! `summary.json`, the gauge route's beside it. Then the same run's saved fields identified
//! offline (`dicstream identify --fields`, issue 25 deliverable 4) against the live fit and
//! the truth.

mod common;

use common::bench_run::{completed_summary, config, start_run};
use common::Run;
use identifier::data::LoadCase;
use identifier::models::Model;
use identifier::reach::Reach;
use live::field_acceptance::judge_route;
use serde_json::Value;
use std::path::Path;

/// One equibiaxial test to a grip stretch of 1.5.
const EQUIBIAXIAL: &str =
    "[[rig.tests]]\nkind = \"equibiaxial\"\nstretch = 1.5\nrate_per_s = 0.08\n";

#[test]
fn the_field_route_identifies_the_law_from_one_equibiaxial_cruciform_test() {
    let mut run = Run::new("run_field_route");
    // 512 px at 0.5 mm/px: ±128 mm, the default camera's view (1024 px at 0.25 mm/px) at
    // half its pixels: the central square, the fillets and the arms to beyond the fillets'
    // reach, room for the central ramps' taper past the fillets (`field_layout`); 8 mm steps.
    // At 0.36 mm/px (±92 mm, nodes to ±81 mm, the taper along the fillets) the equibiaxial
    // stress missed by 2.4-2.8 %.
    let extra =
        format!("{EQUIBIAXIAL}[specimen]\nmodel = \"structure\"\n[identifier]\nroute = \"both\"\n");
    // A field file every 2nd frame (10 by default): the offline fit's frames as many as the
    // live route keeps.
    let config = config(&run, "fields_every = 2", &extra);
    let text = std::fs::read_to_string(&config).unwrap().replace(
        "width_px = 256\nheight_px = 256\n",
        "width_px = 512\nheight_px = 512\nmm_per_px = 0.5\n",
    );
    std::fs::write(&config, text).unwrap();
    let out = run.dir.join("out");
    start_run(&mut run, "run", &config, &out, &["--no-dashboard"]);
    let (summary, _) = completed_summary(&mut run, &out);
    offline_agrees_with_the_live_fit(&out);
    let field = &summary["field_acceptance"];
    println!(
        "field route: {}\ngauge route: {}",
        serde_json::to_string_pretty(field).unwrap(),
        serde_json::to_string_pretty(&summary["acceptance"]).unwrap()
    );
    assert!(field["error"].is_null(), "{field}");
    // The identified law drawn against the true one, and the grip forces it balances.
    for name in ["field_route_law.png", "force_balance.png"] {
        let figure = std::fs::metadata(out.join(name)).map(|m| m.len());
        assert!(
            figure.as_ref().is_ok_and(|&bytes| bytes > 1000),
            "{name}: {figure:?}"
        );
    }
    // Every kept frame's grips balanced under the law found, within 5 % plus three times the
    // load cells' noise (σ 2 N, `[rig] load_cell_noise_kn`): what the virtual fields compute
    // from the field matches each measured force. Measured when written on the default
    // campaign: 2.7 % at worst above a fifth of the peak force, 3.4 N off at 36.6 N.
    let balance = field["force_balance"].as_array().unwrap();
    let force = |b: &serde_json::Value, key: &str| b[key].as_f64().unwrap();
    assert!(balance.len() >= 4 * 10, "{field}");
    for b in balance {
        let (measured, computed) = (force(b, "measured_n"), force(b, "computed_n"));
        assert!((computed - measured).abs() < 0.05 * measured + 6.0, "{b}");
    }
    let counters = &field["counters"];
    // The frames kept stay spread over the loading (thinned at `DEFAULT_MAX_FRAMES`).
    assert!(field["frames"].as_u64().unwrap() >= 10, "{field}");
    assert!(!field["fits"].as_array().unwrap().is_empty(), "{field}");
    assert_eq!(counters["without_forces"], 0, "{field}");
    assert_eq!(counters["without_gradients"], 0, "{field}");
    // Every virtual field of every kept frame holds: the nodes the correlator loses along
    // the specimen's edge are borrowed from, the fillets' nodes are not refused as outliers.
    let kept_now = counters["kept"].as_u64().unwrap() - counters["thinned"].as_u64().unwrap();
    let dropped = counters["virtual_fields_dropped"].as_u64().unwrap();
    assert!(dropped * 10 <= kept_now, "{field}");
    // The states reached by the frames kept: the arms' near-uniaxial states to λ 1.29 (8 mm
    // steps: the nodes nearest the fillets' edges are 4 mm farther in than at 5.8 mm), the
    // centre's equibiaxial ones.
    let reach = &field["reach"];
    let max_stretches = reach["max_stretches"].as_array().unwrap();
    assert!(max_stretches[0].as_f64().unwrap() > 1.25, "{field}");
    assert!(max_stretches[1].as_f64().unwrap() > 1.05, "{field}");
    println!("reach: {reach}");
    // The first ranked law's nominal stresses against the truth over the stretches reached.
    // Issue 25's target is 2 %. The true law (Smactane, `[specimen] law_f, law_g`) is
    // Mooney-Rivlin's C10 0.277, C01 0.364 MPa within 0.5 % (least squares over uniaxial and
    // pure shear to λ 1.4, equibiaxial to 1.1); its own family is not identifiable from one
    // test (2σ ≥ |a2|, |b2|). Before `model_window` and the BIC over forces rather than
    // equations (`field_route::information_criteria`), Hart-Smith ranked first in 5 of 10
    // runs and missed the uniaxial stress by 10-16 % at λ 1.35 (its forces within the noise
    // of Mooney-Rivlin's). Mooney-Rivlin first, measured on 10 runs: uniaxial 1.3-1.5 %,
    // equibiaxial 1.9-2.8 %, pure shear 1.7-2.0 % (camera noise moves them), each case then
    // judged up to the largest major (equibiaxial: minor) stretch of any node. Judged since up
    // to each case's own states (`identifier::reach`), one run: uniaxial 1.2 % to λ 1.33,
    // equibiaxial 2.8 % to 1.09, pure shear 1.4 % to 1.20 (at 0.36 mm/px). At the default's
    // framing (0.5 mm/px), the central ramps' taper past the fillets, two runs: uniaxial
    // 1.15 / 1.38 % to λ 1.29-1.30, equibiaxial 0.81 / 0.63 % to 1.085, pure shear 0.23 /
    // 0.27 % to 1.27 (Mooney-Rivlin's C10 0.307, C01 0.333: the sum right, the split off by
    // about 4σ); the same framing with the taper along the fillets: 0.61 / 1.35 / 0.72 %
    // (C10 0.250, C01 0.397). Asserted with the spread's margin over the 2 % target.
    for case in ["uniaxial", "equibiaxial", "pure_shear"] {
        let error = field[case]["max_relative_error"].as_f64().unwrap();
        assert!(error < 0.025, "{case}: {field}");
    }
}

/// `dicstream identify --fields` on the run's results: the JSON alone on stdout, the live
/// route's best model fitted offline within `AGREEMENT` of its live fit, the offline best law
/// within the live test's margin of the truth.
fn offline_agrees_with_the_live_fit(out: &Path) {
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_dicstream"))
        .args(["identify", "--fields"])
        .arg(out)
        .arg("--json")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let offline: Value = serde_json::from_slice(&output.stdout).expect("stdout is JSON alone");
    let live_json: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("identification.json")).unwrap())
            .unwrap();
    let live_route = &live_json["field_route"];
    println!(
        "offline: frames {} of {} files, counters {}, fits {}\nstderr: {stderr}",
        offline["frames"], offline["fields_read"], offline["counters"], offline["fits"]
    );
    assert_eq!(offline["source"]["per_grip_forces"], true, "{offline}");
    assert!(offline["frames"].as_u64().unwrap() >= 6, "{offline}");
    let config = live::RunConfig::read(Some(&out.join("config.toml"))).unwrap();
    let truth = config.law().unwrap();
    let (offline_law, live_law) = (
        judge_route(&truth, &offline),
        judge_route(&truth, live_route),
    );
    // The truth: the live test's margin (see above).
    for (case, c) in [
        ("uniaxial", offline_law.uniaxial),
        ("equibiaxial", offline_law.equibiaxial),
        ("pure_shear", offline_law.pure_shear),
    ] {
        let c = c.unwrap_or_else(|| panic!("{case}: {offline}"));
        println!("offline best law against the truth, {case}: {c:?}");
        assert!(c.max_relative_error < 0.035, "{case}: {c:?}\n{offline}");
    }
    // The live fit: the live route's best model, as fitted offline, against its live fit,
    // nominal stress over the stretches both reached.
    let best = live_law.model.clone().unwrap();
    let fit_of = |route: &Value| -> Value {
        let fits = route["fits"].as_array().unwrap();
        let fit = fits.iter().find(|f| f["model"] == best.as_str());
        fit.unwrap_or_else(|| panic!("{best} not fitted: {route}"))
            .clone()
    };
    let law = |fit: &Value| -> Vec<f64> {
        let model = Model::parse(&best).unwrap();
        let names = model.param_names();
        names
            .iter()
            .map(|n| fit["params"][n].as_f64().unwrap())
            .collect()
    };
    let model = Model::parse(&best).unwrap();
    let (live_p, offline_p) = (law(&fit_of(live_route)), law(&fit_of(&offline)));
    let reached = |route: &Value, case: LoadCase| {
        let reach: Reach = serde_json::from_value(route["reach"].clone()).unwrap();
        reach.case(case)
    };
    for case in [
        LoadCase::Uniaxial,
        LoadCase::Equibiaxial,
        LoadCase::PureShear,
    ] {
        let max = reached(live_route, case).min(reached(&offline, case));
        let worst = (1..=100)
            .map(|i| {
                let l = 1.0 + (max - 1.0) * i as f64 / 100.0;
                let a = model.nominal_stress_mpa(&live_p, case, l).unwrap();
                let b = model.nominal_stress_mpa(&offline_p, case, l).unwrap();
                ((b - a) / a).abs()
            })
            .fold(0.0, f64::max);
        println!("{best} {case}: offline against live {worst:.4} up to {max:.3}");
        assert!(worst < AGREEMENT, "{case}: {worst}\n{offline}");
    }
}

/// Largest relative difference in nominal stress between the offline and the live fit of one
/// model. The two fit different frames of one test (the saved fields are every 2nd frame, kept
/// and thinned by their own loading levels; the live route saw every frame), each with its
/// camera noise: measured for Mooney-Rivlin on 10 runs, 0.02-0.7 %; asserted at the issue's
/// 2 %. (A model of three parameters moves more: Hart-Smith fitted offline once differed by
/// 2.7 % from its live fit at λ 1.35, its k1 ± 21 %.)
const AGREEMENT: f64 = 0.02;
