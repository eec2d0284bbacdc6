//! `dicstream._dicstream`, the extension module behind the Python package `dicstream`
//! (`python/dicstream/`): the workspace's own code on numpy arrays, nothing of it rewritten.
//!
//! - [`correlate`]: `correlator::Correlator` on two images, the field as numpy arrays and the
//!   frame's summary (`correlator::summary`, as `dicstream correlate` writes it).
//! - [`identify`]: `identifier::ranking::identify` on stretch-stress arrays, the JSON of
//!   `dicstream identify --json`.
//! - [`images`]: numpy images (8/16-bit, float in [0, 1]) to the correlator's 16-bit pixels,
//!   and `read_image`, the CLI's image reader.
//! - [`subscribe`]: a live service's samples, frames' pixels and fields' nodes as numpy views
//!   of the iceoryx2 samples' shared memory (zero copy).
//! - [`layout_dtype`]: the numpy dtypes of the wire layouts, from `wire::layouts`.
//!
//! Every refusal of bad input is a `ValueError` with the library's own message.

mod correlate;
mod identify;
mod images;
mod layout_dtype;
mod subscribe;

use pyo3::prelude::*;
use std::collections::HashMap;
use wire::{NodeStatus, StrainMeasure};

#[pymodule]
fn _dicstream(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(correlate::correlate, m)?)?;
    m.add_function(wrap_pyfunction!(identify::identify_json, m)?)?;
    m.add_function(wrap_pyfunction!(images::read_image, m)?)?;
    m.add_function(wrap_pyfunction!(subscribe::subscribe, m)?)?;
    m.add_function(wrap_pyfunction!(layout_dtype::layouts, m)?)?;
    m.add_class::<subscribe::Subscription>()?;
    m.add_class::<subscribe::Sample>()?;
    m.add("LAYOUT_VERSION", wire::LAYOUT_VERSION)?;
    // The codes of a node's `status` and a field's `strain_measure`, by name (wire's names).
    let codes = |pairs: Vec<(&'static str, u32)>| pairs.into_iter().collect::<HashMap<_, _>>();
    m.add(
        "NODE_STATUS",
        codes(NodeStatus::ALL.map(|s| (s.name(), s as u32)).to_vec()),
    )?;
    m.add(
        "STRAIN_MEASURES",
        codes(StrainMeasure::ALL.map(|s| (s.name(), s as u32)).to_vec()),
    )?;
    Ok(())
}
