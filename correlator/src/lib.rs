//! CORRELI-GD digital image correlation on a parallel mesh of zones of interest, and strains.
//!
//! Chevalier, Calloch, Hild, Marco, section 3.b: a centred 2^p ROI (here by default the whole
//! image less half a ZOI, or the user's rectangle, polygons or mask: [`region`]), one global
//! FFT correlation for the mean integer displacement (U0, V0), then per ZOI of 2^s px every
//! δx px: integer FFT correlation and move, modified Hanning window (eq. 9), 3x3 quadratic
//! sub-pixel peak, Fourier-shift iterations (eqs. 5-7) while the interpolated maximum increases.
//! Each ZOI is zero-mean and unit-norm (insensitive to brightness and contrast changes).
//!
//! ```no_run
//! use correlator::{Correlator, CorrelatorSettings};
//! let (w, h) = (512, 512);
//! let reference = vec![0u16; w * h];
//! let deformed = vec![0u16; w * h];
//! let mut c = Correlator::new(CorrelatorSettings::default(), w, h).unwrap();
//! c.set_reference(&reference).unwrap();
//! let field = c.correlate(&deformed).unwrap();
//! println!("{} of {} nodes valid, log gauge exx {}", field.valid, field.nodes.len(), field.gauge.log.exx);
//! ```
//!
//! No allocation per ZOI or per frame after `Correlator::new` (the first `set_reference` fills
//! preallocated caches); worker threads are spawned once and own their FFT plans and buffers.
//!
//! The live process shell is [`process`] (the only module that knows iceoryx2: `frames` in,
//! `fields` out); [`state`] saves and restores the reference so that a restarted process
//! resumes measuring the same total displacement.

// First: its macro is used by the modules below.
#[macro_use]
mod text_serde;

mod correlator;
pub mod field;
pub mod gauges;
mod global;
mod icgn;
mod image;
mod interpolate;
pub mod keypoints;
mod mesh;
pub mod output;
mod peak;
mod pool;
#[cfg(feature = "process")]
pub mod process;
pub mod pvd;
pub mod region;
pub mod settings;
mod simd;
#[cfg(target_arch = "x86_64")]
mod simd_avx2;
pub mod state;
pub mod strain;
pub mod summary;
pub mod timing;
mod verify;
pub mod vts;
mod window;
mod zoi;

pub use correlator::{Correlator, ORIGIN_PASS_FRAMES};
pub use field::{Field, GaugeStrains, Node, NodeStatus, Strain2};
pub use gauges::{ControlGauge, Gauge, GaugeReading, GaugeShape, GaugeValue};
pub use region::{Polygon, Region, RoiChoice};
pub use settings::{
    CorrelatorSettings, GuessMode, Method, ReferenceMode, Roi, SettingsError, StrainMeasure,
    DEFAULT_MIN_ZNCC,
};
pub use zoi::{Image, TimeSplit};
