//! Real shared memory, one process: a frame published zero-copy arrives intact, a value arrives,
//! and the instance leaves no file behind once its nodes are gone.

use wire::frame::pixel_checksum;
use wire::pubsub::{SlicePublisher, SliceSubscriber, ValuePublisher, ValueSubscriber};
use wire::{services, FrameHeader, Instance, RigState};

fn unique_instance(tag: &str) -> Instance {
    Instance::new(&format!("wiretest_{tag}_{}", std::process::id())).unwrap()
}

#[test]
fn frame_and_value_round_trip_then_no_leftovers() {
    let instance = unique_instance("rt");
    {
        let (node, _) = instance.create_node("test").unwrap();
        let (width, height) = (64usize, 32usize);
        let publisher: SlicePublisher<u16, FrameHeader> =
            SlicePublisher::create(&node, &services::FRAMES, width * height).unwrap();
        let subscriber: SliceSubscriber<u16, FrameHeader> =
            SliceSubscriber::create(&node, &services::FRAMES).unwrap();
        let delivered = publisher
            .publish(width * height, |header, pixels| {
                for (i, p) in pixels.iter_mut().enumerate() {
                    *p = (i * 13 % 4096) as u16;
                }
                header.frame_id = 7;
                header.width_px = width as u32;
                header.height_px = height as u32;
                header.bit_depth = 12;
                header.pixel_checksum = pixel_checksum(pixels);
                Ok::<bool, ()>(true)
            })
            .unwrap()
            .unwrap();
        assert_eq!(delivered, Some(1));
        let sample = subscriber.receive().unwrap().expect("a frame");
        let header = *sample.user_header();
        header.validate(sample.payload().len()).unwrap();
        assert_eq!(header.frame_id, 7);
        assert_eq!(pixel_checksum(sample.payload()), header.pixel_checksum);
        assert_eq!(sample.payload()[1000], (1000 * 13 % 4096) as u16);
        drop(sample);
        assert!(subscriber.receive().unwrap().is_none());

        let state_publisher: ValuePublisher<RigState> =
            ValuePublisher::create(&node, &services::RIG_STATE).unwrap();
        let state_subscriber: ValueSubscriber<RigState> =
            ValueSubscriber::create(&node, &services::RIG_STATE).unwrap();
        let state = RigState {
            sample_id: 42,
            t_sim_s: 1.5,
            control_mode: wire::RigControl::Held as u32,
            target_log_exx: 0.3,
            target_log_eyy: -0.02,
            ..RigState::default()
        };
        state_publisher.publish(state).unwrap();
        let received = state_subscriber.receive().unwrap().unwrap();
        assert_eq!(received, state);
        assert_eq!(received.control(), wire::RigControl::Held);
        assert_eq!(received.strain_target(), Some([0.3, -0.02]));
        assert!(
            !instance.leftover_files().is_empty(),
            "a live instance has shared-memory files"
        );
    }
    // iceoryx2 keeps one global management segment per prefix after its last node is gone;
    // every port, service and node file must be gone, and the cleanup removes the rest.
    let left = instance.leftover_files();
    assert!(
        left.iter()
            .all(|p| p.to_string_lossy().ends_with("global_mgmt")),
        "port or service files left after every node was dropped: {left:?}"
    );
    instance.remove_leftover_files();
    assert!(instance.leftover_files().is_empty());
}
