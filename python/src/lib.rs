//! `dicstream._dicstream`, the extension module behind the Python package `dicstream`
//! (`python/dicstream/`): the workspace's own code on numpy arrays, nothing of it rewritten.
//!
//! - [`correlate`]: `correlator::Correlator` on two images, the field as numpy arrays and the
//!   frame's summary (`correlator::summary`, as `dicstream correlate` writes it).
//! - [`identify`]: `identifier::ranking::identify` on stretch-stress arrays, the JSON of
//!   `dicstream identify --json`.
//! - [`images`]: numpy images (8/16-bit, float in [0, 1]) to the correlator's 16-bit pixels,
//!   and `read_image`, the CLI's image reader.
//!
//! Every refusal of bad input is a `ValueError` with the library's own message.

mod correlate;
mod identify;
mod images;

use pyo3::prelude::*;

#[pymodule]
fn _dicstream(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(correlate::correlate, m)?)?;
    m.add_function(wrap_pyfunction!(identify::identify_json, m)?)?;
    m.add_function(wrap_pyfunction!(images::read_image, m)?)?;
    m.add("LAYOUT_VERSION", wire::LAYOUT_VERSION)?;
    Ok(())
}
