//! numpy structured dtypes of the wire layouts, built at run time from `wire::layouts` (the
//! Rust definitions' own offsets, sizes and types): a layout change reaches Python with the
//! next build, never a hand-written copy of it.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use wire::layouts::{Element, Layout};

/// The dtype of `layout`: its fields by name at their offsets, arrays as sub-arrays, nested
/// layouts as nested dtypes, the itemsize the Rust type's size.
pub fn dtype<'py>(py: Python<'py>, layout: &Layout) -> PyResult<Bound<'py, PyAny>> {
    let numpy = py.import("numpy")?;
    let (names, formats, offsets) = (PyList::empty(py), PyList::empty(py), PyList::empty(py));
    for field in &layout.fields {
        let element = match field.element {
            Element::Scalar(scalar) => numpy.call_method1("dtype", (scalar.numpy(),))?,
            Element::Layout(nested) => dtype(py, &nested())?,
        };
        let format = match field.count {
            1 => element,
            n => PyTuple::new(py, [element, PyTuple::new(py, [n])?.into_any()])?.into_any(),
        };
        names.append(field.name)?;
        formats.append(format)?;
        offsets.append(field.offset_bytes)?;
    }
    let spec = PyDict::new(py);
    spec.set_item("names", names)?;
    spec.set_item("formats", formats)?;
    spec.set_item("offsets", offsets)?;
    spec.set_item("itemsize", layout.size_bytes)?;
    numpy.call_method1("dtype", (spec,))
}

/// `dicstream.layouts()`: every described layout's dtype by its Rust name.
#[pyfunction]
pub fn layouts(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let all = PyDict::new(py);
    for layout in wire::layouts::all() {
        all.set_item(layout.name, dtype(py, &layout)?)?;
    }
    Ok(all)
}
