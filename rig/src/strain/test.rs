//! A strain-controlled test as a user configures it (`[[rig.tests]] control = "strain"`,
//! `dicstream rig --control strain`): its kind, the larger measured stretch it goes to, the
//! ratio ρ = ln λy / ln λx it holds, its rate, and what the interlocks do. Checked here, with
//! the reasons a user reads; [`StrainTest::path`] is its strain program.

use crate::strain::control::OnRestore;
use crate::strain::interlock::{InterlockLimits, DEFAULT_MIN_VALID_NODES, DEFAULT_STALE_S};
use crate::strain::path::{StrainPath, StrainPathError};

/// The path a strain-controlled test holds on the cruciform specimen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrainKind {
    /// ρ = −1/2: the gauge zone stretched along x, contracting along y as in uniaxial tension.
    Uniaxial,
    /// ρ = 1.
    Equibiaxial,
    /// ρ = 0: ln λy held at 0.
    PureShear,
    /// Any ρ (`ratio`).
    Biaxial,
}

/// How a test drives the grips.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TestControl {
    /// The grips follow the program (centroid control).
    #[default]
    Displacement,
    /// The correlator's fields close the loop on the gauge zone's log strains.
    Strain,
}

wire::named!(TestControl, "control", { Displacement => "displacement", Strain => "strain" });

wire::named!(StrainKind, "kind", {
    Uniaxial => "uniaxial", Equibiaxial => "equibiaxial", PureShear => "pure_shear",
    Biaxial => "biaxial",
});

impl StrainKind {
    /// The kind's own ratio (None: biaxial, given by the user).
    pub fn fixed_ratio(self) -> Option<f64> {
        match self {
            StrainKind::Uniaxial => Some(-0.5),
            StrainKind::Equibiaxial => Some(1.0),
            StrainKind::PureShear => Some(0.0),
            StrainKind::Biaxial => None,
        }
    }
}

/// A checked strain-controlled test (one read from a settings file is checked again by
/// [`StrainTest::check`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrainTest {
    pub kind: StrainKind,
    /// ρ = ln λy / ln λx held along the path.
    pub ratio: f64,
    /// Target of the larger measured stretch.
    pub stretch: f64,
    /// Rate of the larger log strain component (/s; ≈ the stretch rate near λ = 1).
    pub rate_log_per_s: f64,
    pub limits: InterlockLimits,
    pub on_interlock: OnRestore,
}

/// Why a strain-controlled test was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StrainTestError {
    #[error("ratio {ratio} given with kind {kind}: only a biaxial test takes a ratio (uniaxial is −0.5, equibiaxial 1, pure_shear 0)")]
    RatioNotTaken { kind: &'static str, ratio: f64 },
    #[error("a biaxial test needs its ratio (ln λy / ln λx)")]
    RatioMissing,
    #[error("stale limit {stale_s} s: expected a positive number of seconds")]
    Stale { stale_s: f64 },
    #[error("jump limit {jump_log} (log strain): expected a positive number")]
    Jump { jump_log: f64 },
    #[error(transparent)]
    Path(#[from] StrainPathError),
}

impl StrainTest {
    /// `ratio` only for a biaxial test; `stretch` > 1; `rate_log_per_s` > 0.
    pub fn new(
        kind: StrainKind,
        ratio: Option<f64>,
        stretch: f64,
        rate_log_per_s: f64,
    ) -> Result<StrainTest, StrainTestError> {
        let ratio = match (kind.fixed_ratio(), ratio) {
            (Some(_), Some(ratio)) => {
                return Err(StrainTestError::RatioNotTaken {
                    kind: kind.name(),
                    ratio,
                })
            }
            (Some(fixed), None) => fixed,
            (None, Some(ratio)) => ratio,
            (None, None) => return Err(StrainTestError::RatioMissing),
        };
        let test = StrainTest {
            kind,
            ratio,
            stretch,
            rate_log_per_s,
            limits: InterlockLimits {
                stale_s: DEFAULT_STALE_S,
                min_valid_nodes: DEFAULT_MIN_VALID_NODES,
                ..InterlockLimits::default()
            },
            on_interlock: OnRestore::Resume,
        };
        test.path()?;
        Ok(test)
    }

    /// The interlocks: the stale limit (s), the fewest valid nodes, and what follows a hold.
    pub fn with_interlocks(
        mut self,
        stale_s: f64,
        min_valid_nodes: u32,
        on_interlock: OnRestore,
    ) -> Result<StrainTest, StrainTestError> {
        if !(stale_s.is_finite() && stale_s > 0.0) {
            return Err(StrainTestError::Stale { stale_s });
        }
        self.limits.stale_s = stale_s;
        self.limits.min_valid_nodes = min_valid_nodes;
        self.on_interlock = on_interlock;
        Ok(self)
    }

    /// The checks of [`StrainTest::new`] and [`StrainTest::with_interlocks`] again, on a test
    /// that did not come from them (a settings file).
    pub fn check(&self) -> Result<(), StrainTestError> {
        let ratio = (self.kind.fixed_ratio().is_none()).then_some(self.ratio);
        if let Some(fixed) = self.kind.fixed_ratio() {
            if fixed != self.ratio {
                return Err(StrainTestError::RatioNotTaken {
                    kind: self.kind.name(),
                    ratio: self.ratio,
                });
            }
        }
        StrainTest::new(self.kind, ratio, self.stretch, self.rate_log_per_s)?.with_interlocks(
            self.limits.stale_s,
            self.limits.min_valid_nodes,
            self.on_interlock,
        )?;
        let jump_log = self.limits.jump_log;
        if !(jump_log.is_finite() && jump_log > 0.0) {
            return Err(StrainTestError::Jump { jump_log });
        }
        Ok(())
    }

    /// Hold 1 s, the constant-ratio ramp to the stretch, hold 1 s.
    pub fn path(&self) -> Result<StrainPath, StrainPathError> {
        StrainPath::ratio_path(self.ratio, self.stretch, self.rate_log_per_s)
    }

    /// The target end point (ln λx, ln λy).
    pub fn target_log(&self) -> [f64; 2] {
        StrainPath::ratio_target(self.ratio, self.stretch).unwrap_or([0.0; 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_give_their_ratio_and_bad_combinations_are_refused_with_reasons() {
        let t = StrainTest::new(StrainKind::Equibiaxial, None, 1.8, 0.02).unwrap();
        assert_eq!(t.ratio, 1.0);
        assert_eq!(t.target_log(), [1.8f64.ln(); 2]);
        assert_eq!(
            StrainTest::new(StrainKind::PureShear, None, 1.5, 0.02)
                .unwrap()
                .target_log(),
            [1.5f64.ln(), 0.0]
        );
        assert_eq!(
            StrainTest::new(StrainKind::Uniaxial, None, 1.5, 0.02)
                .unwrap()
                .ratio,
            -0.5
        );
        let b = StrainTest::new(StrainKind::Biaxial, Some(0.5), 1.5, 0.02).unwrap();
        assert_eq!(b.target_log(), [1.5f64.ln(), 0.5 * 1.5f64.ln()]);
        let refused = |kind, ratio, stretch, rate| {
            StrainTest::new(kind, ratio, stretch, rate)
                .unwrap_err()
                .to_string()
        };
        assert!(refused(StrainKind::Uniaxial, Some(0.5), 1.5, 0.02).contains("only a biaxial"));
        assert!(refused(StrainKind::Biaxial, None, 1.5, 0.02).contains("needs its ratio"));
        assert!(refused(StrainKind::Biaxial, Some(f64::NAN), 1.5, 0.02).contains("ratio NaN"));
        assert!(refused(StrainKind::Equibiaxial, None, 1.0, 0.02).contains("stretch 1"));
        assert!(refused(StrainKind::Equibiaxial, None, 0.8, 0.02).contains("stretch"));
        assert!(refused(StrainKind::Equibiaxial, None, 1.5, 0.0).contains("rate"));
        assert!("shear"
            .parse::<StrainKind>()
            .unwrap_err()
            .to_string()
            .contains("pure_shear or biaxial"));
        let t = StrainTest::new(StrainKind::Equibiaxial, None, 1.8, 0.02).unwrap();
        assert!(t
            .with_interlocks(0.0, 16, OnRestore::Resume)
            .unwrap_err()
            .to_string()
            .contains("stale limit"));
        assert!("pause"
            .parse::<OnRestore>()
            .unwrap_err()
            .to_string()
            .contains("resume or stop"));
        let t = t.with_interlocks(1.5, 40, OnRestore::Stop).unwrap();
        assert_eq!(t.limits.stale_s, 1.5);
        assert_eq!(t.limits.min_valid_nodes, 40);
        assert_eq!(t.on_interlock, OnRestore::Stop);
    }
}
