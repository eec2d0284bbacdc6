//! The rig's side of a run's configuration: the campaign of `[[rig.tests]]`, the
//! strain-controlled test when there is one, the specimen's law, and how long it all takes.

use super::{RigSource, RunConfig};
use anyhow::{anyhow, bail, Context};
use rig::builtin::BuiltinTest;
use rig::strain::{StrainKind, TestControl};

/// The kind of a built-in displacement-controlled test.
pub(super) fn kind_of(test: BuiltinTest) -> StrainKind {
    match test {
        BuiltinTest::Uniaxial => StrainKind::Uniaxial,
        BuiltinTest::Equibiaxial => StrainKind::Equibiaxial,
    }
}

impl RunConfig {
    /// The campaign the rig runs.
    pub fn campaign(&self) -> anyhow::Result<rig::Campaign> {
        let spec = self.campaign_spec();
        let campaign = rig::Campaign::parse(&spec).context("[rig] tests")?;
        Ok(campaign.with_law(self.law()?))
    }

    /// `uniaxial:3@0.08,...`, the rig's `--campaign` argument (a strain-controlled test is
    /// described as `strain:KIND:STRETCH@RATE`, for messages).
    pub fn campaign_spec(&self) -> String {
        self.rig
            .tests
            .iter()
            .map(|t| match t.control {
                TestControl::Strain => format!("strain:{}:{}@{}", t.kind, t.stretch, t.rate_per_s),
                TestControl::Displacement => format!("{}:{}@{}", t.kind, t.stretch, t.rate_per_s),
            })
            .collect::<Vec<_>>()
            .join(",")
    }

    /// The specimen material.
    pub fn law(&self) -> anyhow::Result<identifier::law::InvariantLaw> {
        use identifier::law::{InvariantLaw, LawError};
        InvariantLaw::exp_poly(&self.specimen.law_f, &self.specimen.law_g).map_err(|e| match e {
            LawError::Coefficients {
                which,
                coefficients,
            } => anyhow!(
                "[specimen] law_{which} = {coefficients:?}: expected one or more finite numbers"
            ),
            LawError::Stiffness { .. } => anyhow!("[specimen] {e}"),
        })
    }

    /// Wall-clock length of the campaign (s).
    pub fn campaign_wall_s(&self) -> anyhow::Result<f64> {
        if let Some(test) = self.strain_test()? {
            // Hold 1 s, ramp, hold 1 s, unload at 5x the rate, hold 0.5 s (rig::strain::run).
            let e = test
                .target_log()
                .map(f64::abs)
                .into_iter()
                .fold(0.0, f64::max);
            let ramp_s = e / test.rate_log_per_s;
            let unload_s =
                (test.stretch - 1.0) / (rig::campaign::UNLOAD_RATE_FACTOR * test.rate_log_per_s);
            return Ok((2.5 + ramp_s + unload_s) / self.rig.speed);
        }
        Ok(self.campaign()?.duration_s() / self.rig.speed)
    }

    /// The strain-controlled test of `[[rig.tests]]` (control = "strain"), None when every test
    /// is under displacement control; refused with the reason when the combination is not one
    /// a strain-controlled run can do.
    pub fn strain_test(&self) -> anyhow::Result<Option<rig::strain::StrainTest>> {
        let tests = &self.rig.tests;
        for (k, t) in tests.iter().enumerate() {
            let at = format!("[[rig.tests]] {} (kind {:?})", k + 1, t.kind.name());
            if t.control == TestControl::Strain {
                continue;
            }
            for (key, given) in [
                ("ratio", t.ratio.is_some()),
                ("stale_s", t.stale_s.is_some()),
                ("min_valid_nodes", t.min_valid_nodes.is_some()),
                ("on_interlock", t.on_interlock.is_some()),
            ] {
                if given {
                    bail!("{at}: {key} applies to control = \"strain\" only");
                }
            }
            if matches!(t.kind, StrainKind::PureShear | StrainKind::Biaxial) {
                bail!(
                    "{at}: a {} path is held on the measured strains: set control = \"strain\"",
                    t.kind
                );
            }
        }
        let Some(t) = tests.iter().find(|t| t.control == TestControl::Strain) else {
            return Ok(None);
        };
        if tests.len() > 1 {
            bail!(
                "[[rig.tests]]: a strain-controlled test runs alone in its run ({} tests given); \
                 run one config per strain path",
                tests.len()
            );
        }
        if self.rig.source == RigSource::CsvFollow {
            bail!(
                "[[rig.tests]] control = \"strain\" with [rig] source = \"csv-follow\": strain \
                 control drives the simulated rig; a followed machine's log cannot be steered"
            );
        }
        let test = rig::strain::StrainTest::new(t.kind, t.ratio, t.stretch, t.rate_per_s)
            .and_then(|test| {
                test.with_interlocks(
                    t.stale_s.unwrap_or(rig::strain::interlock::DEFAULT_STALE_S),
                    t.min_valid_nodes
                        .unwrap_or(rig::strain::interlock::DEFAULT_MIN_VALID_NODES),
                    t.on_interlock.unwrap_or_default(),
                )
            })
            .map_err(|e| anyhow!("[[rig.tests]] 1 (control = \"strain\"): {e}"))?;
        Ok(Some(test))
    }
}
