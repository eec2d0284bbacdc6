//! Hyperelastic identification of rubber-like materials (paper section 4). Everything but
//! [`process`] is pure (no IPC) and tested without shared memory.
//!
//! - [`law`]: the invariant-based law W(I1, I2) with f(I1), g(I2) (eqs 18-25), Smactane™ default.
//! - [`data`]: load cases, kinematics, stresses from forces, the CSV reader.
//! - [`models`]: the catalogue of potentials (Table 2 and the usual others).
//! - [`gradient`]: analytic gradients of the nominal stress with respect to the parameters.
//! - [`lsq`]: linear least squares and a bounded Levenberg-Marquardt (nalgebra).
//! - [`residuals`]: the fit's residuals, cost and normal equations in one pass (blocked, threaded).
//! - [`fit`]: fitting a model to any combination of load cases, statistics, ranking by AIC.
//! - [`stability`]: Drucker stability along the load paths.
//! - [`field_stress`]: a measured node's stress from its in-plane F and a law (section 4.c).
//! - [`section_cut`]: the force through a band across an arm, the paper's section cut as a
//!   virtual field.
//! - [`vfm`]: the virtual fields method over the cuts of all frames of a test.
//! - [`virtual_work`]: a virtual field's work as weighted nodes; a fit's equations compiled
//!   once for every trial law.
//! - [`field_layout`]: where the cuts and ramps go, from the cruciform and the view.
//! - [`grip_forces`]: the grips' forces of recent rig samples, by id or by time.
//! - [`field_route`]: the frames of a test kept for the field route, fitted together.
//! - [`model_window`]: the models the forces do not tell apart, the fewest parameters first.
//! - [`state_contributions`]: each state's (node and frame) share of a field fit's
//!   sensitivity to its parameters, and `states.csv`.
//! - [`femu`]: finite-element model updating, the field route's reference (offline): the
//!   view's finite-element model under the measured edge displacements against the grips'
//!   forces and the interior displacements ([`measured_displacement`]: the edges' values).
//! - [`saved_fields`]: a run's saved fields, frames and rig log read for the field route
//!   offline (`identify --fields`).
//! - [`route`]: the paper's f-then-g route (eqs 20-25) feeding the LM refinement.
//! - [`plot`]: PNG plots of the data, fits, f(I1) and g(I2) (plotters, bitmap backend).
//! - [`online`]: pairing strains with rig forces, accumulating the load path, refitting (no IPC).
//! - [`process`]: the live `identifier` process shell over iceoryx2 (`wire` services).
//! - [`ranking`]: the offline identification on data in memory (`identify`, Python) and its JSON.
//! - [`report`]: JSON of fits, atomic file writes.
//! - [`subsample`]: the documented limit on fitted points and the load-path-preserving subsample.

#![forbid(unsafe_code)]

pub mod columns;
pub mod data;
pub mod fe_cards;
pub mod femu;
pub mod field_layout;
pub mod field_route;
pub mod field_stress;
pub mod fit;
pub mod gradient;
pub mod grip_forces;
pub mod identifiability;
pub mod initial_modulus;
pub mod journal;
pub mod kinematics;
/// The law lives in its own crate (`material`), shared with the rig; re-exported here.
pub use material as law;
pub mod lsq;
pub mod map_figure;
pub mod measured_displacement;
pub mod model_window;
pub mod models;
pub mod online;
pub mod plot;
#[cfg(feature = "process")]
pub mod process;
pub mod ranking;
pub mod reach;
pub mod report;
pub mod residual_plot;
pub mod residuals;
pub mod route;
pub mod saved_fields;
pub mod section_cut;
pub mod stability;
pub mod state_contributions;
pub mod subsample;
pub mod table;
pub mod tapered_ramp;
pub mod vfm;
pub mod virtual_work;
