//! `correlate(reference, deformed, ...)`: one field of `correlator::Correlator` between two
//! numpy images, with the settings of `dicstream correlate` (same names, same defaults: the
//! library's), the GIL released while it runs.

use crate::images::{pixels, Pixels};
use correlator::settings::{Method, ReferenceKind};
use correlator::{
    ControlGauge, Correlator, CorrelatorSettings, Gauge, GuessMode, Polygon, ReferenceMode,
    RoiChoice, StrainMeasure,
};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::str::FromStr;
use wire::names::Named;

/// A `ValueError` from any error's message.
pub(crate) fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A named choice (`method`, `strain`, `guess`) as the CLI reads it: `method: method "x":
/// expected correli, icgn1, icgn2 or icgn`.
fn named<T: Named>(flag: &str, text: Option<&str>, default: T) -> PyResult<T> {
    text.map_or(Ok(default), |t| {
        T::parse_name(t).map_err(|e| value_error(format!("{flag}: {e}")))
    })
}

/// A value given as text (`roi`, a polygon, a gauge), parsed by its own `FromStr`.
fn parsed<T: FromStr>(flag: &str, text: &str) -> PyResult<T>
where
    T::Err: std::fmt::Display,
{
    text.parse()
        .map_err(|e| value_error(format!("{flag} {text:?}: {e}")))
}

/// Every text of `texts` parsed, as [`parsed`].
fn parsed_all<T: FromStr>(flag: &str, texts: &[String]) -> PyResult<Vec<T>>
where
    T::Err: std::fmt::Display,
{
    texts.iter().map(|t| parsed(flag, t)).collect()
}

/// The region's rectangle: None (the margin), a name (`margin`, `centred-pow2`), "x,y,w,h" or a
/// tuple (x, y, w, h) in px.
fn roi_choice(roi: Option<&Bound<'_, PyAny>>) -> PyResult<RoiChoice> {
    let Some(roi) = roi else {
        return Ok(RoiChoice::Margin);
    };
    if let Ok(text) = roi.extract::<String>() {
        return parsed("roi", &text);
    }
    let (x, y, w, h): (usize, usize, usize, usize) = roi.extract().map_err(|_| {
        value_error("roi: give None, \"margin\", \"centred-pow2\", \"x,y,w,h\" or a tuple (x, y, w, h) of px")
    })?;
    parsed("roi", &format!("{x},{y},{w},{h}"))
}

/// One field between `reference` and `deformed` (2-D numpy arrays of one shape: uint8,
/// uint16, or float grey levels in [0, 1]). Returns a dict: the node arrays (`x`, `y`, `u`,
/// `v` in px, `exx`, `eyy`, `exy`, the gradient `du_dx`, `du_dy`, `dv_dx`, `dv_dy`, `score`,
/// `iterations`: (ny, nx) arrays, row-major as the field's CSV), `status` (one word a node)
/// `summary` (JSON text of the frame's summary, as in `summary.json`) and `elapsed_ms` (the
/// correlation's time, as the CLI's `elapsed_ms`).
#[pyfunction]
#[pyo3(signature = (
    reference, deformed, *, method=None, zoi=None, step=None, roi=None, polygons=vec![],
    mask=None, strain=None, guess=None, min_zncc=None, gradient_correction=None, threads=None,
    max_iterations=None, gauges=vec![], control_gauge=None
))]
#[allow(clippy::too_many_arguments)]
pub fn correlate<'py>(
    py: Python<'py>,
    reference: &Bound<'py, PyAny>,
    deformed: &Bound<'py, PyAny>,
    method: Option<&str>,
    zoi: Option<usize>,
    step: Option<usize>,
    roi: Option<&Bound<'py, PyAny>>,
    polygons: Vec<String>,
    mask: Option<PathBuf>,
    strain: Option<&str>,
    guess: Option<&str>,
    min_zncc: Option<f64>,
    gradient_correction: Option<bool>,
    threads: Option<usize>,
    max_iterations: Option<u32>,
    gauges: Vec<String>,
    control_gauge: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    // Settings from the keyword arguments, the library's defaults (the CLI's) for the others.
    let d = CorrelatorSettings::default();
    let method = named::<Method>("method", method, d.method)?;
    let mut settings = CorrelatorSettings {
        method,
        zoi_px: zoi.unwrap_or(d.zoi_px),
        step_px: step.unwrap_or(d.step_px),
        strain: named::<StrainMeasure>("strain", strain, d.strain)?,
        reference: ReferenceMode::of_kind(ReferenceKind::Fixed, method),
        guess: named::<GuessMode>("guess", guess, d.guess)?,
        min_zncc: min_zncc.unwrap_or(d.min_zncc),
        gradient_correction: gradient_correction.unwrap_or(d.gradient_correction),
        threads: threads.unwrap_or(d.threads),
        max_iterations: max_iterations.unwrap_or(d.max_iterations),
        control_gauge: match control_gauge {
            Some(text) => parsed::<ControlGauge>("control_gauge", text)?,
            None => d.control_gauge.clone(),
        },
        ..d
    };
    settings.region.roi = roi_choice(roi)?;
    settings.region.polygons = parsed_all::<Polygon>("polygon", &polygons)?;
    settings.region.mask = mask;
    settings.gauges = parsed_all::<Gauge>("gauge", &gauges)?;
    let reference = pixels("reference image", reference)?;
    let deformed = pixels("deformed image", deformed)?;
    if (deformed.width_px, deformed.height_px) != (reference.width_px, reference.height_px) {
        return Err(value_error(format!(
            "deformed image is {}x{} px, expected {}x{} px like the reference",
            deformed.width_px, deformed.height_px, reference.width_px, reference.height_px
        )));
    }
    let (correlator, elapsed_ms) = py.detach(|| run(settings, &reference, &deformed))?;
    let dict = field_dict(py, &correlator)?;
    dict.set_item("elapsed_ms", elapsed_ms)?;
    Ok(dict)
}

/// The correlator made for `reference`, having measured `deformed` (its field), and the time
/// of that measurement in ms (what `dicstream correlate` reports as a frame's `elapsed_ms`).
fn run(
    settings: CorrelatorSettings,
    reference: &Pixels,
    deformed: &Pixels,
) -> PyResult<(Correlator, f64)> {
    let (width, height) = (reference.width_px, reference.height_px);
    let mut correlator = Correlator::new(settings, width, height).map_err(|e| {
        value_error(format!(
            "settings refused for the {width}x{height} px reference: {e}"
        ))
    })?;
    correlator
        .set_reference(&reference.pixels)
        .map_err(value_error)?;
    let started = std::time::Instant::now();
    correlator
        .correlate(&deformed.pixels)
        .map_err(value_error)?;
    Ok((correlator, started.elapsed().as_secs_f64() * 1e3))
}

/// One value of every node.
type NodeValue = fn(&correlator::Field, usize) -> f64;

/// The arrays of [`correlate`]'s dict, by name.
const ARRAYS: [(&str, NodeValue); 13] = [
    ("x", |f, k| f.nodes[k].x_px),
    ("y", |f, k| f.nodes[k].y_px),
    ("u", |f, k| f.nodes[k].u_px),
    ("v", |f, k| f.nodes[k].v_px),
    ("exx", |f, k| f.nodes[k].exx),
    ("eyy", |f, k| f.nodes[k].eyy),
    ("exy", |f, k| f.nodes[k].exy),
    ("du_dx", |f, k| {
        correlator::output::node_gradient(f, k)[0][0]
    }),
    ("du_dy", |f, k| {
        correlator::output::node_gradient(f, k)[0][1]
    }),
    ("dv_dx", |f, k| {
        correlator::output::node_gradient(f, k)[1][0]
    }),
    ("dv_dy", |f, k| {
        correlator::output::node_gradient(f, k)[1][1]
    }),
    ("score", |f, k| f.nodes[k].score),
    ("iterations", |f, k| f64::from(f.nodes[k].iterations)),
];

fn field_dict<'py>(py: Python<'py>, correlator: &Correlator) -> PyResult<Bound<'py, PyDict>> {
    let field = correlator.field();
    let dict = PyDict::new(py);
    for (name, value) in ARRAYS {
        let values: Vec<f64> = (0..field.nodes.len()).map(|k| value(field, k)).collect();
        dict.set_item(
            name,
            PyArray1::from_vec(py, values).reshape([field.ny, field.nx])?,
        )?;
    }
    let status: Vec<&str> = field.nodes.iter().map(|n| n.status.name()).collect();
    dict.set_item("status", status)?;
    dict.set_item("shape", (field.ny, field.nx))?;
    let summary = correlator::summary::frame_summary(field, &correlator.settings().gauges);
    dict.set_item("summary", summary.to_string())?;
    Ok(dict)
}
