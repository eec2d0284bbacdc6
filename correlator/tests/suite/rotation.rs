//! Paper section 3.c: 5° rigid rotation, s = 6, δx = 32, on the whole 512² image. Mean
//! infinitesimal strain within 3e-4 of cos 5° − 1; mean Green-Lagrange and logarithmic strains
//! and shear below 2e-4; no `ok` node more than 0.5 px off; with the default guess and with the
//! paper's (whose global (U0, V0) needs the significance test and the smaller centred square
//! here: on the whole ROI the rotation decorrelates its border).

use crate::common;

use common::{accuracy, render, rotation_deg};
use correlator::strain::node_strains;
use correlator::{Correlator, CorrelatorSettings, GuessMode, NodeStatus, StrainMeasure};

#[test]
fn five_degree_rotation() {
    let (w, h) = (512, 512);
    let centre = [(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0];
    let reference = render(w, h, 48.0, rotation_deg(0.0, centre), 0.01, 1);
    let deformed = render(w, h, 48.0, rotation_deg(5.0, centre), 0.01, 2);
    let exact_small = 5f64.to_radians().cos() - 1.0;
    for guess in [GuessMode::Auto, GuessMode::Correli, GuessMode::Predict] {
        let settings = CorrelatorSettings {
            zoi_px: 64,
            step_px: 32,
            guess,
            strain: StrainMeasure::Small,
            ..Default::default()
        };
        let mut correlator = Correlator::new(settings, w, h).unwrap();
        correlator.set_reference(&reference).unwrap();
        let field = correlator.correlate(&deformed).unwrap().clone();
        let mut means = Vec::new();
        for measure in StrainMeasure::ALL {
            let mut nodes = field.nodes.clone();
            node_strains(&mut nodes, field.nx, field.ny, 1, measure);
            let ok: Vec<_> = nodes
                .iter()
                .filter(|n| n.status == NodeStatus::Ok)
                .collect();
            let count = ok.len() as f64;
            let mean = |f: fn(&&correlator::Node) -> f64| ok.iter().map(f).sum::<f64>() / count;
            means.push((measure, mean(|n| n.exx), mean(|n| n.eyy), mean(|n| n.exy)));
        }
        eprintln!(
            "{guess:?}: valid {}/{} nodes",
            field.valid,
            field.nodes.len()
        );
        eprintln!("  refused: {}", field.refusals());
        for (measure, exx, eyy, exy) in &means {
            let g = field.gauge.get(*measure);
            eprintln!(
                "  {:7} node mean exx {exx:+.2e} eyy {eyy:+.2e} exy {exy:+.2e} | gauge exx {:+.2e} eyy {:+.2e} exy {:+.2e}",
                measure.name(),
                g.exx,
                g.eyy,
                g.exy
            );
        }
        let (s5, c5) = 5f64.to_radians().sin_cos();
        let o = accuracy(&field, 64, (w, h), |p| {
            let d = [p[0] - centre[0], p[1] - centre[1]];
            [
                centre[0] + c5 * d[0] - s5 * d[1],
                centre[1] + s5 * d[0] + c5 * d[1],
            ]
        });
        o.print(&format!("rotation 5°, ZOI 64, step 32, {guess:?}"));
        assert_eq!(o.false_ok, 0, "{o:?}");
        if guess == GuessMode::Predict {
            continue; // reported only: the live path without growth
        }
        assert!(o.valid_fraction() >= 0.95, "{o:?}");
        // The paper's figures are ROI averages (CORRELI-GAUGE): asserted on the gauge. The plain
        // mean of the per-node 3x3 least-squares strains is noisier at the mesh border: looser.
        for (measure, exx, eyy, exy) in means {
            let g = field.gauge.get(measure);
            assert!(g.exy.abs() < 2e-4, "{measure:?} gauge shear {}", g.exy);
            assert!(exy.abs() < 5e-4, "{measure:?} node-mean shear {exy}");
            let (target, gauge_tol) = match measure {
                StrainMeasure::Small => (exact_small, 3e-4),
                StrainMeasure::Green | StrainMeasure::Log => (0.0, 2e-4),
                StrainMeasure::Nominal => (0.0, 2e-4),
            };
            for e in [g.exx, g.eyy] {
                assert!(
                    (e - target).abs() < gauge_tol,
                    "{measure:?} gauge strain {e} vs {target}"
                );
            }
            for e in [exx, eyy] {
                assert!(
                    (e - target).abs() < 5e-4,
                    "{measure:?} node-mean strain {e} vs {target}"
                );
            }
        }
    }
}
