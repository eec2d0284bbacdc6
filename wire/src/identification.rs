//! `identification`: the current state of the on-line hyperelastic identification.

#[cfg(feature = "ipc")]
use iceoryx2::prelude::ZeroCopySend;

/// Most coefficients one reported model may carry.
pub const MAX_COEFFICIENTS: usize = 8;
/// How many ranked models a report lists.
pub const MAX_RANKED: usize = 8;

/// Which route a report comes from ([`IdentificationReport::route`]): the gauge's averages of
/// canonical tests, or the whole field by the virtual fields method (paper section 4.c).
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReportRoute {
    #[default]
    Gauge = 0,
    Field = 1,
}

crate::named!(ReportRoute, "identification route", { Gauge => "gauge", Field => "field" });

impl ReportRoute {
    pub fn from_code(code: u32) -> Option<ReportRoute> {
        ReportRoute::ALL.into_iter().find(|r| *r as u32 == code)
    }
}

/// The routes an identifier runs (`[identifier] route`, `identifier --route`): both publish
/// on `identification`, each report naming its own. `auto` is the run's default: both when the
/// specimen is a structure (a cruciform's field holds what the field route needs), the gauge
/// otherwise ([`IdentifierRoutes::resolved`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IdentifierRoutes {
    #[default]
    Auto,
    Gauge,
    Field,
    Both,
}

crate::named!(IdentifierRoutes, "identifier route", {
    Auto => "auto", Gauge => "gauge", Field => "field", Both => "both",
});

impl IdentifierRoutes {
    /// `auto` made concrete for a run whose specimen is (or is not) a structure.
    pub fn resolved(self, structure: bool) -> IdentifierRoutes {
        match (self, structure) {
            (IdentifierRoutes::Auto, true) => IdentifierRoutes::Both,
            (IdentifierRoutes::Auto, false) => IdentifierRoutes::Gauge,
            (other, _) => other,
        }
    }

    /// Whether `route` runs (`auto` unresolved runs the gauge's only).
    pub fn runs(self, route: ReportRoute) -> bool {
        matches!(
            (self, route),
            (IdentifierRoutes::Both, _)
                | (
                    IdentifierRoutes::Auto | IdentifierRoutes::Gauge,
                    ReportRoute::Gauge
                )
                | (IdentifierRoutes::Field, ReportRoute::Field)
        )
    }
}

/// One fitted model in the ranking.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.RankedModel.v6")
)]
pub struct RankedModel {
    /// NUL-padded model name (identifier crate names), see [`crate::text`].
    pub name: [u8; 24],
    pub aic: f64,
    pub rms_mpa: f64,
}

/// Header-only sample on `identification` (no payload slice).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.IdentificationReport.v6")
)]
pub struct IdentificationReport {
    pub layout_version: u32,
    /// Points of the load path used, per load case: uniaxial, equibiaxial, pure shear.
    pub points: [u32; 3],
    /// The field (frame) that triggered this refit and its capture time (monotonic ns).
    pub frame_id: u64,
    pub t_capture_ns: u64,
    pub t_published_ns: u64,
    /// Coefficients of f: ln f = Σ a_i (I1 − 3)^i (MPa), `a_count` of them; and of g:
    /// ln g = Σ b_i (I2 − 3)^i (MPa), `b_count` of them (the paper's eqs. 22 and 25).
    pub a: [f64; MAX_COEFFICIENTS],
    pub a_stderr: [f64; MAX_COEFFICIENTS],
    pub b: [f64; MAX_COEFFICIENTS],
    pub b_stderr: [f64; MAX_COEFFICIENTS],
    pub a_count: u32,
    pub b_count: u32,
    pub rms_mpa: f64,
    pub ranked_count: u32,
    /// A [`ReportRoute`] code: the gauge route's report, or the field route's (whose `points`
    /// are zero, `rms_mpa` NaN: its residuals are forces, in `identification.json`).
    pub route: u32,
    pub ranking: [RankedModel; MAX_RANKED],
}

impl IdentificationReport {
    /// The route this report comes from (None: an unknown code).
    pub fn route(&self) -> Option<ReportRoute> {
        ReportRoute::from_code(self.route)
    }
}

impl Default for IdentificationReport {
    fn default() -> Self {
        IdentificationReport {
            layout_version: crate::LAYOUT_VERSION,
            points: [0; 3],
            frame_id: 0,
            t_capture_ns: 0,
            t_published_ns: 0,
            a: [0.0; MAX_COEFFICIENTS],
            a_stderr: [0.0; MAX_COEFFICIENTS],
            b: [0.0; MAX_COEFFICIENTS],
            b_stderr: [0.0; MAX_COEFFICIENTS],
            a_count: 0,
            b_count: 0,
            rms_mpa: 0.0,
            ranked_count: 0,
            route: ReportRoute::Gauge as u32,
            ranking: [RankedModel {
                name: [0; 24],
                aic: 0.0,
                rms_mpa: 0.0,
            }; MAX_RANKED],
        }
    }
}
