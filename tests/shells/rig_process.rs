//! The process shell over iceoryx2: rig/state is published, rig/command answers accepted or
//! refused with a reason. Runs under its own instance prefix and removes its files.

use crate::rig_options::rig_options;

use iceoryx2::prelude::*;
use rig::process::{run, ProcessOptions, Speed};
use std::time::{Duration, Instant};
use wire::rig::{RigCommandKind, RigReply, RigState};

fn request(
    client: &iceoryx2::port::client::Client<ipc::Service, wire::RigCommand, (), RigReply, ()>,
    command: wire::RigCommand,
) -> RigReply {
    let pending = client.send_copy(command).unwrap();
    let deadline = Instant::now() + testkit::HANG_GUARD;
    loop {
        if let Some(reply) = pending.receive().unwrap() {
            return *reply;
        }
        assert!(Instant::now() < deadline, "no reply from the rig");
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn state_is_published_and_commands_are_answered() {
    // Its files are removed when it is dropped, also when the test fails.
    let test_instance = testkit::TestInstance::new("rig_process");
    let name = test_instance.name().to_string();
    let options = ProcessOptions {
        speed: Speed::Factor(5.0),
        duration_s: Some(15.0),
        ..rig_options(&name)
    };
    let rig_thread = std::thread::spawn(move || run(options).unwrap());

    let instance = wire::Instance::new(&name).unwrap();
    let (node, _) = instance.create_node("rig_test_client").unwrap();
    let states =
        wire::pubsub::ValueSubscriber::<RigState>::create(&node, &wire::services::RIG_STATE)
            .unwrap();
    let service = node
        .service_builder(&ServiceName::new(wire::services::RIG_COMMAND).unwrap())
        .request_response::<wire::RigCommand, RigReply>()
        .open_or_create()
        .unwrap();
    let client = service.client_builder().create().unwrap();
    // The server exists once the first state is out: a request sent before would be lost.
    let deadline = Instant::now() + testkit::HANG_GUARD;
    while states.receive().unwrap().is_none() {
        assert!(Instant::now() < deadline, "no rig/state sample");
        std::thread::sleep(Duration::from_millis(2));
    }

    // A NaN set-point is refused with its reason.
    let mut nan = wire::RigCommand::new(RigCommandKind::SetPoint);
    nan.value = f64::NAN;
    let reply = request(&client, nan);
    assert_eq!(reply.accepted, 0);
    assert!(reply.reason().contains("finite"), "{}", reply.reason());
    // Beyond the stroke: refused.
    let mut far = wire::RigCommand::new(RigCommandKind::SetPoint);
    far.value = 300.0;
    let reply = request(&client, far);
    assert_eq!(reply.accepted, 0);
    assert!(reply.reason().contains("stroke"), "{}", reply.reason());
    // A move of X+ to 2 mm: accepted, and seen on rig/state.
    let mut set = wire::RigCommand::new(RigCommandKind::SetPoint);
    set.value = 2.0;
    assert_eq!(request(&client, set).accepted, 1, "set-point");
    let deadline = Instant::now() + testkit::HANG_GUARD;
    let mut last: Option<RigState> = None;
    while Instant::now() < deadline {
        while let Some(s) = states.receive().unwrap() {
            last = Some(s);
        }
        if last.is_some_and(|s| (s.actuators[0].position_mm - 2.0).abs() < 0.05) {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let last = last.expect("rig/state samples");
    assert_eq!(last.layout_version, wire::LAYOUT_VERSION);
    assert!(
        (last.actuators[0].position_mm - 2.0).abs() < 0.05,
        "{:?}",
        last.actuators[0]
    );
    let reply = request(
        &client,
        wire::RigCommand::new(RigCommandKind::EmergencyStop),
    );
    assert_eq!(reply.accepted, 1);

    let summary = rig_thread.join().unwrap();
    println!("process: {summary:?}");
    assert!(summary.samples_published > 100);
    assert_eq!(summary.commands_accepted, 2);
    assert_eq!(summary.commands_refused, 2);
    drop(client);
    drop(service);
    drop(states);
    drop(node);
    instance.remove_leftover_files();
}
