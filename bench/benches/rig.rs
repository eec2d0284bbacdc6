//! Rig speed: simulated seconds per wall second at 5 kHz with six channels under control
//! (X and Y pairs in centroid displacement ramping the equibiaxial specimen, Z pair holding),
//! on the homogeneous sheet and on the finite-element cruciform (solved on its schedule,
//! followed between solves by its condensed tangent). Prints the median over runs. Run:
//! `cargo bench -p bench --bench rig`; with logging and the journal replay:
//! `cargo run --release -p rig --example structure_realtime`.

use rig::{Loading, Program, Rig, RigCommand, RigConfig, SpecimenConfig, SpecimenModel};
use std::time::Instant;

const PROGRAM: &str = r#"
[[setup]]
axis = "x"
control = "centroid_displacement"
[[setup]]
axis = "y"
control = "centroid_displacement"
[[channel]]
target = "x.elongation"
segments = [{ kind = "ramp", to = 100.0, rate_per_s = 0.1 }]
[[channel]]
target = "y.elongation"
segments = [{ kind = "ramp", to = 100.0, rate_per_s = 0.1 }]
[[channel]]
target = "z+"
segments = [{ kind = "sine", amplitude = 1.0, frequency_hz = 1.0, cycles = 1000 }]
"#;

const RUNS: usize = 7;
const SIMULATED_S: f64 = 20.0;

fn main() {
    measure(SpecimenModel::Homogeneous, RUNS);
    measure(SpecimenModel::Structure, 3);
}

fn measure(model: SpecimenModel, runs: usize) {
    let mut ratios = Vec::with_capacity(runs);
    let mut step_ns = Vec::with_capacity(runs);
    for run in 0..runs {
        let specimen = SpecimenConfig::of(
            Loading::Equibiaxial,
            &rig::SpecimenSettings {
                model,
                ..Default::default()
            },
        );
        let config = RigConfig {
            specimen: Some(specimen),
            ..RigConfig::default()
        };
        let control_hz = config.control_hz;
        let mut rig = Rig::new(config, run as u64).expect("default config");
        let program = Program::from_toml(PROGRAM, std::path::Path::new(".")).expect("program");
        rig.command(RigCommand::StartProgram(Box::new(program)))
            .expect("start");
        let steps = (SIMULATED_S * control_hz) as u64;
        let started = Instant::now();
        for _ in 0..steps {
            rig.step();
        }
        let wall_s = started.elapsed().as_secs_f64();
        std::hint::black_box(rig.state());
        ratios.push(SIMULATED_S / wall_s);
        step_ns.push(wall_s * 1e9 / steps as f64);
    }
    ratios.sort_by(f64::total_cmp);
    step_ns.sort_by(f64::total_cmp);
    println!(
        "rig ({model} specimen): 5 kHz, 6 channels, {runs} runs of {SIMULATED_S} s simulated: \
         median {:.1}x real time (min {:.1}x, max {:.1}x), median {:.0} ns per step",
        ratios[runs / 2],
        ratios[0],
        ratios[runs - 1],
        step_ns[runs / 2]
    );
}
