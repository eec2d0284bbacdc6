//! Correlate two images with the correlator library alone: no process, no shared memory.
//!
//! ```text
//! cargo run --release --example correlate_two_images -- REFERENCE DEFORMED
//! ```
//! Without arguments it reads the DIC Challenge sample 14 (reference and L1) from
//! `testdata/`. Prints the mean displacement, the valid nodes and the gauge strain.

use anyhow::Context;
use correlator::{Correlator, CorrelatorSettings};

fn read_gray16(path: &str) -> anyhow::Result<(Vec<u16>, usize, usize)> {
    let image = image::open(path).with_context(|| format!("reading {path}"))?;
    let gray = image.to_luma16();
    let (width, height) = (gray.width() as usize, gray.height() as usize);
    Ok((gray.into_raw(), width, height))
}

fn main() -> anyhow::Result<()> {
    let sample = "testdata/dic-challenge/sample14";
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (reference_path, deformed_path) = match args.as_slice() {
        [r, d] => (r.clone(), d.clone()),
        [] => (
            format!("{sample}/Sample14 Reference.tif"),
            format!("{sample}/Sample14 L1 Amp0.1b.tif"),
        ),
        _ => anyhow::bail!("usage: correlate_two_images [REFERENCE DEFORMED]"),
    };
    let (reference, width, height) = read_gray16(&reference_path)?;
    let (deformed, w, h) = read_gray16(&deformed_path)?;
    anyhow::ensure!(
        (w, h) == (width, height),
        "{deformed_path} is {w}x{h} px, the reference {width}x{height} px"
    );

    let mut correlator = Correlator::new(CorrelatorSettings::default(), width, height)?;
    correlator.set_reference(&reference)?;
    let field = correlator.correlate(&deformed)?;
    anyhow::ensure!(
        field.valid > 0,
        "no node was measured: is the image textured?"
    );
    println!("{} of {} nodes measured", field.valid, field.nodes.len());
    println!(
        "mean displacement u {:.4} px, v {:.4} px",
        field.u_mean_px, field.v_mean_px
    );
    let gauge = field.gauge.log;
    println!(
        "gauge log strain exx {:.2e}, eyy {:.2e}, exy {:.2e}",
        gauge.exx, gauge.eyy, gauge.exy
    );
    Ok(())
}
