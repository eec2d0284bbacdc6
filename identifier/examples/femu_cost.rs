//! What finite-element model updating costs against the virtual fields method on the same data
//! (issue 25 deliverable 5): the noise-free cruciform of `tests/suite/femu_structure.rs` (5 mm
//! elements, Mooney-Rivlin C10 0.3, C01 0.05 MPa, four grip stretches, a 1 mm grid over ±80
//! mm), each fit from its preparation (the virtual fields' quadrature and compiled equations;
//! FEMU's clipped mesh, edge displacements and located nodes) to its parameters, timed in the
//! same run, median of `RUNS`.
//!
//! `cargo run --release -j 2 -p identifier --example femu_cost`

#[path = "../tests/common/cruciform.rs"]
mod cruciform;

use cruciform::{observations, ramp_quadratures, solved_frames, GRID_STEP_MM};
use identifier::femu::{Femu, FemuFrame, FemuSettings};
use identifier::field_layout::GRIPS;
use identifier::models::Model;
use identifier::vfm;
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::{InvariantDerivatives, NewtonSettings, Probe};
use std::time::Instant;

const RUNS: usize = 3;
const STRETCHES: [(f64, f64); 4] = [(1.1, 1.1), (1.25, 1.25), (1.35, 1.2), (1.2, 1.35)];

fn median(mut seconds: Vec<f64>) -> f64 {
    seconds.sort_by(f64::total_cmp);
    seconds[seconds.len() / 2]
}

fn main() {
    let model = Model::Mooney;
    let truth = [0.3, 0.05];
    let law = InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(&truth, i1, i2));
    let (mesh, frames) = solved_frames(&law, &STRETCHES, 5.0, GRID_STEP_MM);
    let probe = Probe::new(&mesh);
    let femu_frames: Vec<FemuFrame> = frames
        .iter()
        .enumerate()
        .map(|(k, f)| FemuFrame {
            frame_id: k as u64,
            field: f.displacements.clone(),
            forces_n: GRIPS.map(|g| f.force(g)),
        })
        .collect();
    let settings = FemuSettings {
        cruciform: CruciformGeometry {
            element_size_mm: 5.0,
            ..CruciformGeometry::default()
        },
        force_sigma_n: FemuSettings::DEFAULT_FORCE_SIGMA_N,
        displacement_sigma_mm: 0.0072,
        newton: NewtonSettings::default(),
    };
    // Seconds of each run: [preparation, fit].
    let (mut vfm_s, mut femu_s) = (vec![], vec![]);
    let (mut by_vfm, mut by_femu) = (None, None);
    for _ in 0..RUNS {
        let started = Instant::now();
        let ramps = ramp_quadratures(&frames, &|x| probe.locate(x).is_some());
        let equations = vfm::compile(&observations(&frames, Some(&ramps))).unwrap();
        let prepared = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let fit = vfm::fit_equations(&model, &equations, &[0.0, 0.0]).unwrap();
        vfm_s.push([prepared, started.elapsed().as_secs_f64()]);
        by_vfm = Some(fit);
        let started = Instant::now();
        let femu = Femu::new(&femu_frames, settings.clone()).unwrap();
        let prepared = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let fit = femu.fit(&model, &[0.39, 0.03]).unwrap();
        femu_s.push([prepared, started.elapsed().as_secs_f64()]);
        by_femu = Some((fit, femu.mesh().elements.len()));
    }
    let (by_vfm, (by_femu, elements)) = (by_vfm.unwrap(), by_femu.unwrap());
    println!(
        "{} frames, {} grid nodes a frame; VFM: {} equations, params {:?}; FEMU: {elements} \
         elements, {} + {} residuals, {} iterations, {} solves of all frames, params {:?}",
        frames.len(),
        frames[0].grid.gradients.len(),
        by_vfm.equations,
        by_vfm.params,
        by_femu.force_residuals,
        by_femu.displacement_residuals,
        by_femu.iterations,
        by_femu.evaluations,
        by_femu.params
    );
    let column = |runs: &[[f64; 2]], k: usize| median(runs.iter().map(|r| r[k]).collect());
    let (vfm_fit, femu_fit) = (column(&vfm_s, 1), column(&femu_s, 1));
    println!(
        "median of {RUNS} runs, s: VFM preparation {:.3}, fit {vfm_fit:.4}; FEMU preparation \
         {:.3}, fit {femu_fit:.2}; FEMU fit / VFM fit = {:.0}, FEMU fit / VFM preparation and \
         fit = {:.1} (runs [preparation, fit]: VFM {vfm_s:.4?}, FEMU {femu_s:.3?})",
        column(&vfm_s, 0),
        column(&femu_s, 0),
        femu_fit / vfm_fit,
        femu_fit / (column(&vfm_s, 0) + vfm_fit)
    );
}
