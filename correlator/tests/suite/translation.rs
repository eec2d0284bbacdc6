//! Sub-pixel translation sweep 0..1 px (issue 3): |mean error| <= 0.01 px, std <= 0.02 px,
//! 1 % noise, 32 px ZOI. Prints the bias curve.

use crate::common;

use common::{mean_std, render, translation};
use correlator::{Correlator, CorrelatorSettings, GuessMode, NodeStatus};

#[test]
fn subpixel_translation_sweep() {
    let (w, h) = (256, 256);
    let reference = render(w, h, 8.0, translation(0.0, 0.0), 0.01, 100);
    let settings = CorrelatorSettings {
        zoi_px: 32,
        step_px: 16,
        guess: GuessMode::Correli,
        ..Default::default()
    };
    let mut correlator = Correlator::new(settings, w, h).unwrap();
    correlator.set_reference(&reference).unwrap();
    eprintln!("u_px  v_px  mean_err_u  std_u  mean_err_v  std_v  mean_iter");
    for step in 0..=10 {
        let shift = step as f64 * 0.1;
        let (u, v) = (shift, 0.5 * shift + 0.25);
        let deformed = render(w, h, 8.0, translation(u, v), 0.01, 200 + step);
        let field = correlator.correlate(&deformed).unwrap();
        let bad: Vec<_> = field
            .nodes
            .iter()
            .filter(|n| n.status != NodeStatus::Ok)
            .collect();
        assert!(
            bad.is_empty(),
            "all nodes must converge at shift {shift}: {bad:?}"
        );
        let worst = field
            .nodes
            .iter()
            .map(|n| (n.u_px - u).hypot(n.v_px - v))
            .fold(0.0, f64::max);
        assert!(worst <= common::FALSE_OK_PX, "a node is {worst} px off");
        let eu: Vec<f64> = field.nodes.iter().map(|n| n.u_px - u).collect();
        let ev: Vec<f64> = field.nodes.iter().map(|n| n.v_px - v).collect();
        let iters: Vec<f64> = field.nodes.iter().map(|n| n.iterations as f64).collect();
        let (mu, su) = mean_std(&eu);
        let (mv, sv) = mean_std(&ev);
        eprintln!(
            "{u:5.2} {v:5.2} {mu:+10.5} {su:7.5} {mv:+10.5} {sv:7.5} {:6.2}",
            mean_std(&iters).0
        );
        assert!(
            mu.abs() <= 0.01 && mv.abs() <= 0.01,
            "bias at shift {shift}: {mu} {mv}"
        );
        assert!(su <= 0.02 && sv <= 0.02, "std at shift {shift}: {su} {sv}");
    }
}
