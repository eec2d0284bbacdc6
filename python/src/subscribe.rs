//! `subscribe(service, instance=None, timeout=None)`: an iterator of a live service's samples
//! (`frames`, `fields`, `rig/state`, `identification`), through the subscriber `dicstream tap`
//! opens (`wire::pubsub::TappedSubscriber`) on a node of the instance (`wire::Instance`).
//!
//! A frame's pixels and a field's nodes are numpy views of the iceoryx2 sample's shared memory
//! (no copy): a read-only uint8 array over the sample's bytes whose base is the [`Sample`]
//! object, viewed with the dtype of `wire::layouts`. The sample goes back to the publisher when
//! the last view of it and the `Sample` are gone. Rig states and identification reports are
//! single values that `ValueSubscriber` copies out (a few hundred bytes).

use crate::correlate::value_error;
use crate::layout_dtype::dtype;
use numpy::ndarray::ArrayView1;
use numpy::PyArray1;
use pyo3::exceptions::{PyAttributeError, PyTimeoutError};
use pyo3::prelude::*;
use std::time::{Duration, Instant};
use wire::layouts::{self, Layout};
use wire::pubsub::TappedSubscriber;
use wire::{FieldHeader, FieldNode, FrameHeader, IdentificationReport, Instance, RigState};

type Ipc = iceoryx2::prelude::ipc::Service;
type IoxSample<T, H> = iceoryx2::sample::Sample<Ipc, [T], H>;

/// The longest wait without looking at Python's signals (Ctrl-C).
const SIGNAL_CHECK: Duration = Duration::from_millis(100);

/// What a [`Sample`] holds: the iceoryx2 sample itself (frames, fields) or the copied value.
enum Held {
    Frame(IoxSample<u16, FrameHeader>),
    Field(IoxSample<FieldNode, FieldHeader>),
    Rig(Box<RigState>),
    Identification(Box<IdentificationReport>),
}

impl Held {
    /// The header's (the value's) bytes: address and length.
    fn header_bytes(&self) -> (*const u8, usize) {
        fn bytes<H>(header: &H) -> (*const u8, usize) {
            ((header as *const H).cast(), std::mem::size_of::<H>())
        }
        match self {
            Held::Frame(s) => bytes(s.user_header()),
            Held::Field(s) => bytes(s.user_header()),
            Held::Rig(v) => bytes(&**v),
            Held::Identification(v) => bytes(&**v),
        }
    }

    /// The payload's bytes (frames, fields), or None.
    fn payload_bytes(&self) -> Option<(*const u8, usize)> {
        fn bytes<T>(payload: &[T]) -> (*const u8, usize) {
            (payload.as_ptr().cast(), std::mem::size_of_val(payload))
        }
        match self {
            Held::Frame(s) => Some(bytes(s.payload())),
            Held::Field(s) => Some(bytes(s.payload())),
            Held::Rig(_) | Held::Identification(_) => None,
        }
    }
}

/// One received sample: `header` (a 0-d structured array over the header), the header's
/// fields as attributes, and `pixels` (frames: uint16, (height, width)) or `nodes` (fields:
/// structured, (mesh_rows, mesh_cols)), views of the shared memory.
#[pyclass(unsendable, module = "dicstream._dicstream")]
pub struct Sample {
    held: Held,
    service: &'static str,
    header_dtype: Py<PyAny>,
    payload_dtype: Option<Py<PyAny>>,
}

/// A read-only uint8 array over `len` bytes at `ptr`, owned by `owner` (its numpy base).
///
/// # Safety
/// The bytes must stay valid and unchanged for as long as `owner` lives.
unsafe fn bytes_view<'py>(
    owner: &Bound<'py, Sample>,
    ptr: *const u8,
    len: usize,
) -> PyResult<Bound<'py, PyAny>> {
    // SAFETY: the caller's promise; ndarray only records the pointer and the length.
    let view = unsafe { ArrayView1::from_shape_ptr(len, ptr) };
    // SAFETY: `owner` becomes the array's base, so the bytes outlive the array.
    let array = unsafe { PyArray1::borrow_from_array(&view, owner.clone().into_any()) };
    // The subscriber's mapping is read-only: a write would fault, so numpy refuses it.
    array.call_method1("setflags", (false,))?;
    Ok(array.into_any())
}

#[pymethods]
impl Sample {
    /// The service the sample came from.
    #[getter]
    fn service(&self) -> &'static str {
        self.service
    }

    /// The header (or the whole value): a 0-d structured array over its memory.
    #[getter]
    fn header<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let this = slf.borrow();
        let (ptr, len) = this.held.header_bytes();
        // SAFETY: the header lies in the held sample (or box), alive as long as `slf`.
        let bytes = unsafe { bytes_view(slf, ptr, len)? };
        let dtype = this.header_dtype.bind(slf.py());
        bytes
            .call_method1("view", (dtype,))?
            .call_method1("reshape", ((),))
    }

    /// A frame's pixels, uint16 of shape (height_px, width_px): a view of the shared memory.
    #[getter]
    fn pixels<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let shape = match &slf.borrow().held {
            Held::Frame(s) => (s.user_header().height_px, s.user_header().width_px),
            _ => return Err(PyAttributeError::new_err("only a frame has pixels")),
        };
        Self::payload(slf, shape)
    }

    /// A field's nodes, structured (x_px, y_px, u_px, v_px, exx, ...) of shape (mesh_rows,
    /// mesh_cols), row-major as published: a view of the shared memory.
    #[getter]
    fn nodes<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let shape = match &slf.borrow().held {
            Held::Field(s) => (s.user_header().mesh_rows, s.user_header().mesh_cols),
            _ => return Err(PyAttributeError::new_err("only a field has nodes")),
        };
        Self::payload(slf, shape)
    }

    /// The address of the payload (pixels, nodes) in this process, as iceoryx2 gives it: where
    /// a view of it must point.
    #[getter]
    fn payload_address(&self) -> PyResult<usize> {
        match self.held.payload_bytes() {
            Some((ptr, _)) => Ok(ptr as usize),
            None => Err(PyAttributeError::new_err(format!(
                "a {} sample has no payload",
                self.service
            ))),
        }
    }

    /// A field's `wire::field::nodes_checksum` (what `dicstream tap --json` prints as
    /// `nodes_checksum`), as text.
    fn nodes_checksum(&self) -> PyResult<String> {
        match &self.held {
            Held::Field(s) => Ok(wire::field::nodes_checksum(s.payload()).to_string()),
            _ => Err(PyAttributeError::new_err("only a field has nodes")),
        }
    }

    /// The header's field `name`: a number, or an array (view) for an array or nested field.
    fn __getattr__<'py>(slf: &Bound<'py, Self>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        let known = {
            let this = slf.borrow();
            let names = this.header_dtype.bind(slf.py()).getattr("names")?;
            names.contains(name)?
        };
        if !known {
            return Err(PyAttributeError::new_err(format!(
                "a {} sample has no attribute {name:?}",
                slf.borrow().service
            )));
        }
        let value = Self::header(slf)?.get_item(name)?;
        let scalar = value.getattr("ndim")?.extract::<usize>()? == 0
            && value.getattr("dtype")?.getattr("names")?.is_none();
        match scalar {
            true => value.call_method0("item"),
            false => Ok(value),
        }
    }

    fn __repr__(slf: &Bound<'_, Self>) -> String {
        let this = slf.borrow();
        match &this.held {
            Held::Frame(s) => {
                let h = s.user_header();
                format!(
                    "<frames sample: frame {} {}x{}>",
                    h.frame_id, h.width_px, h.height_px
                )
            }
            Held::Field(s) => {
                let h = s.user_header();
                format!(
                    "<fields sample: frame {} {}x{} nodes, {} valid>",
                    h.frame_id, h.mesh_cols, h.mesh_rows, h.valid_nodes
                )
            }
            Held::Rig(v) => format!("<rig/state sample {}>", v.sample_id),
            Held::Identification(v) => format!("<identification at frame {}>", v.frame_id),
        }
    }
}

impl Sample {
    /// The payload viewed with its dtype, of `shape`.
    fn payload<'py>(slf: &Bound<'py, Self>, shape: (u32, u32)) -> PyResult<Bound<'py, PyAny>> {
        let this = slf.borrow();
        let (ptr, len) = this
            .held
            .payload_bytes()
            .expect("frames and fields have one");
        let dtype = this
            .payload_dtype
            .as_ref()
            .expect("frames and fields have one")
            .bind(slf.py());
        // SAFETY: the payload lies in the held iceoryx2 sample, alive as long as `slf`.
        let bytes = unsafe { bytes_view(slf, ptr, len)? };
        bytes
            .call_method1("view", (dtype,))?
            .call_method1("reshape", (shape,))
    }
}

/// Asserts `Send` for a value used only on the thread that made it: `Python::detach` runs its
/// closure on the calling thread, and asks `Send` only to keep Python objects out of it.
struct SameThread<T>(T);
// SAFETY: see above; the value never leaves the thread that owns it.
unsafe impl<T> Send for SameThread<T> {}

/// The iterator `subscribe` returns. Fields drop in order: the subscriber, then its node,
/// then the instance (whose drop removes the instance's node counter when no node is left).
#[pyclass(unsendable, module = "dicstream._dicstream")]
pub struct Subscription {
    subscriber: TappedSubscriber,
    _node: iceoryx2::node::Node<Ipc>,
    instance: Instance,
    service: &'static str,
    spec: &'static wire::services::ServiceSpec,
    timeout: Option<Duration>,
    header_dtype: Py<PyAny>,
    payload_dtype: Option<Py<PyAny>>,
}

/// Subscribes to `service` of `instance` (None: the default instance, as the CLI's); each
/// `next()` waits at most `timeout` seconds (None: until a sample comes), then raises
/// `TimeoutError`. A sample of another layout version raises `ValueError` (the Rust readers'
/// message).
#[pyfunction]
#[pyo3(signature = (service, instance=None, timeout=None))]
pub fn subscribe(
    py: Python<'_>,
    service: &str,
    instance: Option<&str>,
    timeout: Option<f64>,
) -> PyResult<Subscription> {
    let timeout = timeout
        .map(|s| {
            Duration::try_from_secs_f64(s)
                .map_err(|_| value_error(format!("timeout {s}: expected seconds >= 0")))
        })
        .transpose()?;
    let name = instance.map_or_else(Instance::default_name, str::to_string);
    let instance = Instance::new(&name).map_err(value_error)?;
    let (node, _dead_nodes_cleaned) = instance.create_node("python").map_err(value_error)?;
    let subscriber = TappedSubscriber::open(&node, service)
        .ok_or_else(|| value_error(TappedSubscriber::unknown_text(service)))?
        .map_err(value_error)?;
    let (header, payload): (Layout, Option<Layout>) = match &subscriber {
        TappedSubscriber::Frames(_) => (layouts::frame_header(), None),
        TappedSubscriber::Fields(_) => (layouts::field_header(), Some(layouts::field_node())),
        TappedSubscriber::RigState(_) => (layouts::rig_state(), None),
        TappedSubscriber::Identification(_) => (layouts::identification_report(), None),
    };
    let payload_dtype = match (&subscriber, payload) {
        (TappedSubscriber::Frames(_), _) => Some(py.import("numpy")?.getattr("uint16")?.unbind()),
        (_, Some(layout)) => Some(dtype(py, &layout)?.unbind()),
        (_, None) => None,
    };
    let spec = wire::services::by_name(service).expect("a service TappedSubscriber opened");
    Ok(Subscription {
        subscriber,
        _node: node,
        instance,
        service: spec.name,
        spec,
        timeout,
        header_dtype: dtype(py, &header)?.unbind(),
        payload_dtype,
    })
}

#[pymethods]
impl Subscription {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    /// The next sample: one queued, or the first to come within the timeout.
    fn __next__(&self, py: Python<'_>) -> PyResult<Sample> {
        let deadline = self.timeout.map(|t| Instant::now() + t);
        loop {
            if let Some(held) = self.receive()? {
                return Ok(Sample {
                    held,
                    service: self.service,
                    header_dtype: self.header_dtype.clone_ref(py),
                    payload_dtype: self.payload_dtype.as_ref().map(|d| d.clone_ref(py)),
                });
            }
            let left = match deadline {
                Some(deadline) => deadline.saturating_duration_since(Instant::now()),
                None => SIGNAL_CHECK,
            };
            if left.is_zero() {
                return Err(PyTimeoutError::new_err(format!(
                    "no {} sample on instance {} in {} s",
                    self.service,
                    self.instance.name(),
                    self.timeout.unwrap_or_default().as_secs_f64()
                )));
            }
            let listener = SameThread(self.subscriber.listener());
            let wait = left.min(SIGNAL_CHECK);
            // The GIL is released while waiting; a wake-up or the slice's end comes back here.
            py.detach(move || {
                let listener = listener;
                let _ = listener.0.timed_wait(|_| {}, wait);
            });
            py.check_signals()?;
        }
    }

    /// The instance's name.
    #[getter]
    fn instance(&self) -> &str {
        self.instance.name()
    }

    /// The service's name.
    #[getter]
    fn service(&self) -> &'static str {
        self.service
    }

    /// How many samples (with views of them) this subscriber may hold at once: one more
    /// makes `next()` fail until one is released.
    #[getter]
    fn max_borrowed(&self) -> usize {
        self.spec.subscriber_borrowed
    }

    /// How many samples wait in this subscriber's queue before the oldest is dropped.
    #[getter]
    fn queue_size(&self) -> usize {
        self.spec.subscriber_buffer
    }
}

impl Subscription {
    /// A failed receive as a `ValueError`; holding too many samples says what to do.
    fn receive_error(&self, e: wire::InstanceError) -> PyErr {
        // iceoryx2's ReceiveError::ExceedsMaxBorrows, told by its name (as `pubsub/connect.rs`).
        match e.to_string().contains("ExceedsMaxBorrows") {
            true => value_error(format!(
                "{}: {} samples are held already (max_borrowed): drop a sample and its views \
                 (keep copies, e.g. nodes.copy()) before taking another ({e})",
                self.service, self.spec.subscriber_borrowed
            )),
            false => value_error(e),
        }
    }

    /// One queued sample, checked as the Rust readers check it (None: none queued).
    fn receive(&self) -> PyResult<Option<Held>> {
        let error = |e| self.receive_error(e);
        let held = match &self.subscriber {
            TappedSubscriber::Frames(s) => s.receive().map_err(error)?.map(Held::Frame),
            TappedSubscriber::Fields(s) => s.receive().map_err(error)?.map(Held::Field),
            TappedSubscriber::RigState(s) => {
                s.receive().map_err(error)?.map(|v| Held::Rig(Box::new(v)))
            }
            TappedSubscriber::Identification(s) => s
                .receive()
                .map_err(error)?
                .map(|v| Held::Identification(Box::new(v))),
        };
        match &held {
            Some(Held::Frame(s)) => s
                .user_header()
                .validate(s.payload().len())
                .map_err(value_error)?,
            Some(Held::Field(s)) => s
                .user_header()
                .validate(s.payload().len())
                .map_err(value_error)?,
            Some(Held::Rig(v)) => {
                layouts::check_version("rig state", v.layout_version).map_err(value_error)?
            }
            Some(Held::Identification(v)) => {
                layouts::check_version("identification report", v.layout_version)
                    .map_err(value_error)?
            }
            None => {}
        }
        Ok(held)
    }
}
