//! Images from Python: numpy arrays to the correlator's 16-bit pixels, with the CLI's rules
//! (8-bit grey levels kept as they are, as the image reader keeps an 8-bit file's), and the
//! CLI's reader.

use numpy::{PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// An image as the correlator takes it: width, height and row-major 16-bit pixels.
pub struct Pixels {
    pub width_px: usize,
    pub height_px: usize,
    pub pixels: Vec<u16>,
}

/// `what` (e.g. "reference image") as 16-bit pixels: a 2-D numpy array of uint16 (as is),
/// uint8 (as they are, as `producer::read_image` reads an 8-bit file) or float32/float64 grey
/// levels in [0, 1] (× 65535, rounded; NaN or out of range is refused, naming the pixel).
pub fn pixels(what: &str, image: &Bound<'_, PyAny>) -> PyResult<Pixels> {
    if let Ok(a) = image.extract::<PyReadonlyArray2<'_, u16>>() {
        return Ok(collect(&a, |&v| v));
    }
    if let Ok(a) = image.extract::<PyReadonlyArray2<'_, u8>>() {
        return Ok(collect(&a, |&v| u16::from(v)));
    }
    if let Ok(a) = image.extract::<PyReadonlyArray2<'_, f32>>() {
        return from_float(what, &a, |&v| f64::from(v));
    }
    if let Ok(a) = image.extract::<PyReadonlyArray2<'_, f64>>() {
        return from_float(what, &a, |&v| v);
    }
    let dtype = image.getattr("dtype").map_or_else(
        |_| {
            image
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_default()
        },
        |d| d.to_string(),
    );
    let ndim = image
        .getattr("ndim")
        .and_then(|n| n.extract::<usize>())
        .ok();
    Err(PyValueError::new_err(match ndim {
        Some(n) if n != 2 => format!("{what}: a 2-D array (height, width) is needed, not {n}-D"),
        _ => format!("{what}: dtype {dtype} is not an image: give uint8, uint16, float32 or float64 (grey levels in [0, 1])"),
    }))
}

fn collect<T: numpy::Element>(a: &PyReadonlyArray2<'_, T>, to_u16: impl Fn(&T) -> u16) -> Pixels {
    let shape = a.shape();
    let view = a.as_array();
    Pixels {
        width_px: shape[1],
        height_px: shape[0],
        pixels: view.iter().map(to_u16).collect(),
    }
}

fn from_float<T: numpy::Element>(
    what: &str,
    a: &PyReadonlyArray2<'_, T>,
    to_f64: impl Fn(&T) -> f64,
) -> PyResult<Pixels> {
    let width_px = a.shape()[1];
    let view = a.as_array();
    let mut pixels = Vec::with_capacity(view.len());
    for (k, v) in view.iter().enumerate() {
        let v = to_f64(v);
        if !(0.0..=1.0).contains(&v) {
            return Err(PyValueError::new_err(format!(
                "{what}: pixel (x {}, y {}) is {v}: a float image holds grey levels in [0, 1]",
                k % width_px.max(1),
                k / width_px.max(1)
            )));
        }
        pixels.push((v * 65535.0).round() as u16);
    }
    Ok(Pixels {
        width_px,
        height_px: a.shape()[0],
        pixels,
    })
}

/// `read_image(path)`: a PNG, TIFF or BMP file (8 or 16 bit) as a uint16 array (height,
/// width), read by the CLI's own reader (`producer::read_image`; an 8-bit file's levels as
/// they are, 0-255).
#[pyfunction]
pub fn read_image<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
) -> PyResult<Bound<'py, PyArray2<u16>>> {
    let image = producer::read_image(&path).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let (w, h) = (image.width as usize, image.height as usize);
    numpy::PyArray1::from_vec(py, image.pixels).reshape([h, w])
}
