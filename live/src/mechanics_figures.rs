//! The run's mechanical figures, drawn at the end from what the run wrote: each actuator's
//! force against time (`forces.png`, from `rig.csv`: on a cruciform, each arm's), and the
//! states the measured field reached in the (λ1, λ2) plane (`stretch_states.png`, the paper's
//! Fig. 5) with the canonical paths (uniaxial λ2 = λ1^-1/2, pure shear λ2 = 1, equibiaxial
//! λ2 = λ1) that the gauge route is limited to: a point per node and frame the field route
//! kept, coloured by its contribution to the route's best fit (`states.csv`, the identifier's,
//! or `identify --fields --plot`'s), or, without a fit, every valid node of every saved field
//! in one colour.

use identifier::plot::{chart, Series};
use std::path::{Path, PathBuf};

/// The λ axis of `stretch_states.png` reaches this at least.
const MIN_MAX_STRETCH: f64 = 1.1;

/// Points per canonical path drawn.
const PATH_SAMPLES: usize = 60;

/// The CSV `text`'s header (`what` names the file in errors) and its data lines.
pub(crate) type Columns<'a> = (Vec<&'a str>, std::str::Lines<'a>);

pub(crate) fn header<'a>(text: &'a str, what: &str) -> anyhow::Result<Columns<'a>> {
    let mut lines = text.lines();
    let names = lines
        .next()
        .ok_or_else(|| anyhow::anyhow!("{what} is empty"))?
        .split(',')
        .collect();
    Ok((names, lines))
}

/// The index of column `name` of `names`, or an error naming it and the file.
pub(crate) fn column(names: &[&str], name: &str, what: &str) -> anyhow::Result<usize> {
    names
        .iter()
        .position(|h| *h == name)
        .ok_or_else(|| anyhow::anyhow!("{what} has no column {name}"))
}

/// Each actuator's force (N, as `rig.csv` logs it) against time (s): one series per
/// actuator that carried a load (`wire::rig::loaded_actuators`).
pub fn actuator_forces(rig_csv: &str) -> anyhow::Result<Vec<Series>> {
    let (names, lines) = header(rig_csv, "rig.csv")?;
    let column = |name: &str| column(&names, name, "rig.csv");
    let time = column("t_s")?;
    let actuators = rig::ids::ActuatorId::ALL
        .iter()
        .map(|id| Ok((id.name(), column(&format!("{}_force_n", id.name()))?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut series: Vec<Series> = actuators
        .iter()
        .map(|(name, _)| Series {
            label: format!("actuator {name}"),
            points: Vec::new(),
            markers: false,
        })
        .collect();
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        let number = |k: usize| cells.get(k).and_then(|c| c.parse::<f64>().ok());
        // A row cut by a kill (the log's last) lacks cells: it is left out.
        let Some(t_s) = number(time) else { continue };
        for (s, (_, k)) in series.iter_mut().zip(&actuators) {
            if let Some(force_n) = number(*k).filter(|f| f.is_finite()) {
                s.points.push((t_s, force_n));
            }
        }
    }
    let peak = |s: &Series| s.points.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    let peaks: Vec<f64> = series.iter().map(peak).collect();
    let mut loaded = wire::rig::loaded_actuators(&peaks).into_iter();
    series.retain(|_| loaded.next().unwrap_or(false));
    Ok(series)
}

/// `forces.png` from the run's `rig.csv`; false when there is none (a run following a
/// machine's CSV) or no actuator carried a force.
pub fn forces_png(rig_csv: &Path, path: &Path) -> anyhow::Result<bool> {
    let text = match std::fs::read_to_string(rig_csv) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => anyhow::bail!("{}: {e}", rig_csv.display()),
    };
    let series = actuator_forces(&text)?;
    if series.is_empty() {
        return Ok(false);
    }
    chart(path, "actuator forces", "time (s)", "force (N)", &series)?;
    Ok(true)
}

/// The in-plane principal stretches (λ1 ≥ λ2) of every `ok` node of a field CSV (the
/// correlator's contract: `status` and the gradient `du_dx,du_dy,dv_dx,dv_dy`).
pub fn node_stretches(field_csv: &str) -> anyhow::Result<Vec<(f64, f64)>> {
    let (names, lines) = header(field_csv, "the field file")?;
    let column = |name: &str| column(&names, name, "the field file");
    let status = column("status")?;
    let gradient = [
        column("du_dx")?,
        column("du_dy")?,
        column("dv_dx")?,
        column("dv_dy")?,
    ];
    let mut points = Vec::new();
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.get(status) != Some(&"ok") {
            continue;
        }
        let g: Option<Vec<f64>> = gradient
            .iter()
            .map(|&k| cells.get(k).and_then(|c| c.parse().ok()))
            .collect();
        let Some(g) = g else { continue };
        let f = [[1.0 + g[0], g[1]], [g[2], 1.0 + g[3]]];
        if let Some([l1, l2]) = identifier::field_stress::principal_stretches(&f) {
            points.push((l1, l2));
        }
    }
    Ok(points)
}

/// The field files of `fields_dir` (`field_*.csv`), in frame order.
fn field_files(fields_dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(fields_dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.extension().is_some_and(|e| e == "csv")
                && p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with("field_"))
        })
        .collect();
    files.sort();
    files
}

/// The canonical paths over λ1 in [1, `max_l1`]: uniaxial, pure shear, equibiaxial.
fn canonical_paths(max_l1: f64) -> Vec<Series> {
    let path = |label: &str, l2: &dyn Fn(f64) -> f64| Series {
        label: label.to_string(),
        points: (0..=PATH_SAMPLES)
            .map(|i| 1.0 + (max_l1 - 1.0) * i as f64 / PATH_SAMPLES as f64)
            .map(|l1| (l1, l2(l1)))
            .collect(),
        markers: false,
    };
    vec![
        path("uniaxial (λ2 = λ1^-1/2)", &|l1| 1.0 / l1.sqrt()),
        path("pure shear (λ2 = 1)", &|_| 1.0),
        path("equibiaxial (λ2 = λ1)", &|l1| l1),
    ]
}

/// The states of `states.csv` (the field route's, [`identifier::state_contributions`]):
/// (λ1, λ2, contribution) of each.
pub fn contributed_states(states_csv: &str) -> anyhow::Result<Vec<(f64, f64, f64)>> {
    let (names, lines) = header(states_csv, "states.csv")?;
    let column = |name: &str| column(&names, name, "states.csv");
    let (l1, l2, share) = (
        column("lambda1")?,
        column("lambda2")?,
        column("contribution")?,
    );
    lines
        .enumerate()
        .filter(|(_, line)| !line.is_empty())
        .map(|(k, line)| {
            let cells: Vec<&str> = line.split(',').collect();
            let number = |i: usize| cells.get(i).and_then(|c| c.parse::<f64>().ok());
            match (number(l1), number(l2), number(share)) {
                (Some(a), Some(b), Some(c)) => Ok((a, b, c)),
                _ => anyhow::bail!("states.csv: line {}: not a state: {line}", k + 2),
            }
        })
        .collect()
}

/// What `stretch_states.png` drew.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatesDrawn {
    /// No valid node with a gradient: no figure.
    Nothing,
    /// The saved fields' nodes in one colour (no field-route fit), how many.
    OneColour(usize),
    /// The field route's states coloured by their contribution to its fit, how many.
    Contributions(usize),
}

/// The bar's title of the coloured figure: what the colour is and how it is normalised.
pub const CONTRIBUTION_BAR_TITLE: &str =
    "contribution: share of the fit's sensitivity to its parameters (all states sum to 1)";

/// `stretch_states.png`: with the field route's `states_csv` (a file that exists), its states
/// coloured by their contribution to the fit of `model` (viridis from 0 to the largest, the
/// largest drawn last); otherwise every valid node of the saved fields in `fields_dir`, one
/// colour, the title saying why.
pub fn stretch_states_png(
    fields_dir: &Path,
    states_csv: Option<&Path>,
    model: Option<&str>,
    path: &Path,
) -> anyhow::Result<StatesDrawn> {
    if let Some(csv) = states_csv.filter(|p| p.exists()) {
        let text =
            std::fs::read_to_string(csv).map_err(|e| anyhow::anyhow!("{}: {e}", csv.display()))?;
        let mut states =
            contributed_states(&text).map_err(|e| anyhow::anyhow!("{}: {e}", csv.display()))?;
        if !states.is_empty() {
            states.sort_by(|a, b| a.2.total_cmp(&b.2));
            draw_contributions(&states, model, path)?;
            return Ok(StatesDrawn::Contributions(states.len()));
        }
    }
    let mut states = Vec::new();
    for file in field_files(fields_dir) {
        let text = std::fs::read_to_string(&file)
            .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        states
            .extend(node_stretches(&text).map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?);
    }
    if states.is_empty() {
        return Ok(StatesDrawn::Nothing);
    }
    let mut series = vec![Series {
        label: format!("nodes of the saved fields ({} states)", states.len()),
        points: states.clone(),
        markers: true,
    }];
    series.extend(canonical_paths(max_l1(states.iter().map(|s| s.0))));
    chart(
        path,
        "states the field reached (paper Fig. 5); no field-route fit: one colour",
        L1_DESC,
        "λ2",
        &series,
    )?;
    Ok(StatesDrawn::OneColour(states.len()))
}

const L1_DESC: &str = "λ1 (larger in-plane principal stretch)";

/// The λ1 axis' reach: the largest λ1, at least [`MIN_MAX_STRETCH`] (a field at rest, λ1 = 1
/// everywhere, still has axes).
fn max_l1(l1: impl Iterator<Item = f64>) -> f64 {
    l1.fold(MIN_MAX_STRETCH, f64::max)
}

/// The coloured figure of `states` (λ1, λ2, contribution), sorted by contribution.
fn draw_contributions(
    states: &[(f64, f64, f64)],
    model: Option<&str>,
    path: &Path,
) -> anyhow::Result<()> {
    let largest = states.iter().map(|s| s.2).fold(0.0, f64::max);
    let scale = wire::colour_map::ColourScale {
        map: wire::colour_map::ColourMap::Viridis,
        low: 0.0,
        high: if largest > 0.0 { largest } else { 1.0 },
    };
    let title = format!(
        "states the field route used (paper Fig. 5), {} of them, coloured by contribution to {}",
        states.len(),
        model.map_or_else(|| "its fit".to_string(), |m| format!("the {m} fit"))
    );
    let label = |v: f64| format!("{v:.1e}");
    identifier::plot::chart_coloured(
        path,
        &title,
        L1_DESC,
        "λ2",
        &canonical_paths(max_l1(states.iter().map(|s| s.0))),
        &identifier::plot::ColouredPoints {
            points: states,
            scale,
            bar_title: CONTRIBUTION_BAR_TITLE,
            label: &label,
        },
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_actuators_force_is_read_against_time_and_idle_ones_left_out() {
        let mut header = String::from("t_s,program");
        for id in rig::ids::ActuatorId::ALL {
            header.push_str(&format!(",{}_force_n", id.name()));
        }
        let row = |t: f64, x: f64| {
            let mut r = format!("{t},1");
            for id in rig::ids::ActuatorId::ALL {
                // The others show their load cell's noise.
                let f = if id.name().starts_with('X') { x } else { 0.01 };
                r.push_str(&format!(",{f}"));
            }
            r
        };
        // The last row was cut by a kill.
        let text = format!("{header}\n{}\n{}\n0.2,1,0.", row(0.0, 0.0), row(0.1, 1.5));
        let series = actuator_forces(&text).unwrap();
        let labels: Vec<&str> = series.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(labels, ["actuator X+", "actuator X-"]);
        assert_eq!(series[0].points, [(0.0, 0.0), (0.1, 1.5), (0.2, 0.0)]);
        assert!(actuator_forces("t_s,x\n1,2").is_err());
    }

    #[test]
    fn a_nodes_principal_stretches_come_from_its_gradient_and_only_ok_nodes_count() {
        let header = correlator::output::CSV_HEADER;
        // Equibiaxial 1.2 rotated by 30°: F = R diag(1.2, 1.2); a uniaxial 1.44 along y:
        // F = diag(1/1.2, 1.44).
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let rotated = [1.2 * c - 1.0, -1.2 * s, 1.2 * s, 1.2 * c - 1.0];
        let uniaxial = [1.0 / 1.2 - 1.0, 0.0, 0.0, 0.44];
        let row = |status: &str, g: [f64; 4]| {
            format!(
                "0,0,0,0,0,0,0,1,3,{status},{},{},{},{}",
                g[0], g[1], g[2], g[3]
            )
        };
        let text = format!(
            "{header}\n{}\n{}\n{}",
            row("ok", rotated),
            row("ok", uniaxial),
            row("low_zncc", uniaxial)
        );
        let points = node_stretches(&text).unwrap();
        assert_eq!(points.len(), 2);
        let close =
            |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12;
        assert!(close(points[0], (1.2, 1.2)), "{points:?}");
        assert!(close(points[1], (1.44, 1.0 / 1.2)), "{points:?}");
        assert!(node_stretches("x,y,u,v\n1,2,3,4").is_err());
    }

    #[test]
    fn a_field_at_rest_still_makes_its_figure() {
        let dir =
            std::env::temp_dir().join(format!("dicstream-stretch-states-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let row = "0,0,0,0,0,0,0,1,3,ok,0,0,0,0";
        let header = correlator::output::CSV_HEADER;
        std::fs::write(
            dir.join("field_000010.csv"),
            format!("{header}\n{row}\n{row}\n"),
        )
        .unwrap();
        let png = dir.join("stretch_states.png");
        assert_eq!(
            stretch_states_png(&dir, None, None, &png).unwrap(),
            StatesDrawn::OneColour(2)
        );
        assert!(png.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The field route's `states.csv` colours the figure; a line that is no state is named.
    #[test]
    fn the_field_routes_states_are_drawn_coloured_by_their_contribution() {
        let dir = std::env::temp_dir().join(format!("dicstream-states-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let header = identifier::state_contributions::STATES_CSV_HEADER;
        let csv = dir.join("states.csv");
        std::fs::write(
            &csv,
            format!(
                "{header},share_C10\n3,0,0,-80,-80,1.2,1.1,0,0e0,0e0\n3,1,0,-77.5,-80,1.5,0.8,0,7.5e-1,7.5e-1\n3,2,0,-75,-80,1.3,1.3,1,2.5e-1,2.5e-1\n"
            ),
        )
        .unwrap();
        let states = contributed_states(&std::fs::read_to_string(&csv).unwrap()).unwrap();
        assert_eq!(states[1], (1.5, 0.8, 0.75));
        let png = dir.join("stretch_states.png");
        assert_eq!(
            stretch_states_png(&dir, Some(&csv), Some("mooney"), &png).unwrap(),
            StatesDrawn::Contributions(3)
        );
        assert!(std::fs::metadata(&png).unwrap().len() > 1000);
        // No states.csv and no saved field: nothing drawn.
        std::fs::remove_file(&png).unwrap();
        assert_eq!(
            stretch_states_png(&dir, Some(&dir.join("none.csv")), None, &png).unwrap(),
            StatesDrawn::Nothing
        );
        assert!(!png.exists());
        let error = contributed_states(&format!("{header}\n3,0,0,0,0,1.2,x,0,0.1\n"))
            .unwrap_err()
            .to_string();
        assert!(error.contains("line 2: not a state"), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
