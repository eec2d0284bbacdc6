//! A subscriber of the `fields` service in about 30 lines: prints each measured field's frame,
//! valid nodes, mean displacement and gauge strain as the correlator publishes it.
//!
//! ```text
//! cargo run --release -- run --instance demo &        # or any correlator on instance demo
//! cargo run --release --example fields_subscriber -- demo
//! ```

use std::time::Duration;

use wire::pubsub::SliceSubscriber;
use wire::{services, FieldHeader, FieldNode, Instance, StrainMeasure};

fn main() -> anyhow::Result<()> {
    wire::signals::install()?; // Ctrl-C ends the loop below, so the node is dropped cleanly
    let name = std::env::args()
        .nth(1)
        .unwrap_or_else(Instance::default_name);
    let instance = Instance::new(&name)?;
    let (node, _dead_nodes_cleaned) = instance.create_node("example-fields")?;
    let fields = SliceSubscriber::<FieldNode, FieldHeader>::create(&node, &services::FIELDS)?;
    println!("listening to the fields of instance {name} (Ctrl-C to stop)");
    while wire::signals::requested().is_none() {
        while let Some(sample) = fields.receive()? {
            let h = sample.user_header();
            let gauge = h.gauge_of(StrainMeasure::Log);
            println!(
                "frame {:6}  {:4}/{:4} nodes  u {:8.3} px  v {:8.3} px  exx {:.2e}",
                h.frame_id,
                h.valid_nodes,
                sample.payload().len(),
                h.u_mean_px,
                h.v_mean_px,
                gauge.exx
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    Ok(())
}
