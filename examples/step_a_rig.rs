//! Step the simulated multiaxial rig without any IPC: the paper's campaign (uniaxial tension
//! to λ 3, then equibiaxial tension to λ 2) in simulated time, as fast as the CPU goes.
//!
//! ```text
//! cargo run --release --example step_a_rig
//! ```
//! Prints a line each simulated second: time, stretches and the force of axis 1.

use rig::{Campaign, CampaignEvent, Rig, RigConfig};

fn main() -> anyhow::Result<()> {
    let mut rig = Rig::new(RigConfig::default(), 7)?;
    let mut campaign = Campaign::paper();
    let steps_per_s = rig.config().control_hz as u64;
    println!("campaign of {:.1} s simulated", campaign.duration_s());
    loop {
        match campaign.advance(&mut rig)? {
            CampaignEvent::Started { index, test } => {
                println!("test {index} started: {:?}", test.test)
            }
            CampaignEvent::Done => break,
            CampaignEvent::Busy => {}
        }
        rig.step();
        let state = rig.state();
        if state.step.is_multiple_of(steps_per_s) {
            let k = state.specimen;
            println!(
                "t {:5.1} s  stretch x {:.3} y {:.3}  axis-1 force {:7.3} kN",
                state.t_s, k.stretch_x, k.stretch_y, state.axes[0].force_kn
            );
        }
    }
    println!("campaign done at t {:.1} s", rig.state().t_s);
    Ok(())
}
