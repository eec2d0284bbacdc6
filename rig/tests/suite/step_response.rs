//! Step response of one actuator (X+) in displacement control: rise time (10-90 %), overshoot
//! and 2 % settling time, printed for the report.

use rig::{ActuatorId, Channel, Rig, RigCommand, RigConfig};

#[test]
fn step_response_of_one_actuator() {
    let mut rig = Rig::new(RigConfig::default(), 7).unwrap();
    rig.advance_to(0.5);
    let id = ActuatorId::XPlus;
    let start_mm = rig.state().actuators[id.index()].position_mm;
    let step_mm = 1.0;
    let t0_s = rig.state().t_s;
    rig.command(RigCommand::SetSetpoint {
        channel: Channel::Actuator(id),
        value: start_mm + step_mm,
    })
    .unwrap();
    let mut samples = Vec::new();
    let steps = (1.0 * rig.config().control_hz) as usize;
    for _ in 0..steps {
        rig.step();
        let s = rig.state();
        samples.push((s.t_s - t0_s, s.actuators[id.index()].position_mm - start_mm));
    }
    let t_10 = samples.iter().find(|(_, x)| *x >= 0.1 * step_mm).unwrap().0;
    let t_90 = samples.iter().find(|(_, x)| *x >= 0.9 * step_mm).unwrap().0;
    let peak = samples.iter().map(|(_, x)| *x).fold(f64::MIN, f64::max);
    let overshoot_pct = (peak - step_mm).max(0.0) / step_mm * 100.0;
    let settle_band = 0.02 * step_mm;
    let last_out = samples
        .iter()
        .rposition(|(_, x)| (x - step_mm).abs() > settle_band)
        .unwrap();
    let settling_s = samples[last_out + 1].0;
    let final_error_mm = step_mm - samples.last().unwrap().1;
    println!(
        "step {step_mm} mm on X+: rise 10-90 % {:.1} ms, overshoot {overshoot_pct:.2} %, \
         settling 2 % {:.1} ms, final error {final_error_mm:.2e} mm",
        (t_90 - t_10) * 1e3,
        settling_s * 1e3
    );
    assert!(t_90 - t_10 < 0.1, "rise time {} s", t_90 - t_10);
    assert!(overshoot_pct < 10.0);
    assert!(settling_s < 0.3);
    assert!(final_error_mm.abs() < 0.01);
    // The other actuators stayed put.
    for other in [ActuatorId::XMinus, ActuatorId::YPlus, ActuatorId::ZPlus] {
        assert!(rig.state().actuators[other.index()].position_mm.abs() < 0.01);
    }
}
