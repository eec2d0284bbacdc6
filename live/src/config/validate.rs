//! The checks of a run's configuration across keys (a word or a type is checked when the TOML
//! is read): what a process would refuse later, refused before any starts, with the section
//! and key named.

use super::{CameraSource, RigSource, RunConfig};
use anyhow::{anyhow, bail, Context};

/// Largest stretch rate the live bench accepts (/s of simulated time): beyond it the camera
/// sees too much motion between frames at the default rate.
const MAX_SIMULATED_SPEED: f64 = 20.0;

impl RunConfig {
    /// Everything a process would refuse, refused now with the section and key named.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.validate_sources()?;
        self.validate_run()?;
        self.validate_camera()?;
        self.correlator_settings()?;
        self.validate_rig()?;
        self.validate_identifier()?;
        if let Some(link) = &self.link {
            link.plan()?;
        }
        Ok(())
    }

    /// The field route needs the specimen as a structure (a cruciform to cut across).
    fn validate_identifier(&self) -> anyhow::Result<()> {
        use wire::identification::ReportRoute;
        let routes = self.identifier_routes();
        if routes.runs(ReportRoute::Field) && self.specimen.model != rig::SpecimenModel::Structure {
            anyhow::bail!(
                "[identifier] route = \"{routes}\" runs the field route, which needs [specimen] \
                 model = \"structure\" (the cruciform whose arms its cuts cross), not \"{}\"",
                self.specimen.model
            );
        }
        Ok(())
    }

    fn validate_run(&self) -> anyhow::Result<()> {
        let r = &self.run;
        if r.results_dir.as_os_str().is_empty() {
            bail!("[run] results_dir is empty");
        }
        if r.fields_every == 0 {
            bail!("[run] fields_every = 0: expected 1 or more (1 = every field)");
        }
        if r.processes.is_empty() {
            bail!(
                "[run] processes is empty: name what this host runs ({})",
                wire::names::expected_list(super::BenchProcess::ALL.iter().map(|p| p.name()))
            );
        }
        if let Some(twice) = r
            .processes
            .iter()
            .enumerate()
            .find(|&(k, p)| r.processes[..k].contains(p))
        {
            bail!("[run] processes: {} is named twice", twice.1);
        }
        for (name, v) in [
            ("status_interval_s", r.status_interval_s),
            ("stop_timeout_s", r.stop_timeout_s),
            ("stale_after_s", r.stale_after_s),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= 3600.0) {
                bail!("[run] {name} = {v}: expected (0, 3600] s");
            }
        }
        Ok(())
    }

    fn validate_camera(&self) -> anyhow::Result<()> {
        let c = &self.camera;
        for (name, side) in [("width_px", c.width_px), ("height_px", c.height_px)] {
            if !(64..=producer::MAX_SIDE_PX).contains(&side) {
                bail!(
                    "[camera] {name} = {side}: expected 64 to {} px",
                    producer::MAX_SIDE_PX
                );
            }
        }
        if !(c.fps.is_finite() && c.fps > 0.0 && c.fps <= 1000.0) {
            bail!("[camera] fps = {}: expected (0, 1000]", c.fps);
        }
        if !producer::BIT_DEPTHS.contains(&c.bit_depth) {
            bail!(
                "[camera] bit_depth = {}: expected one of {:?}",
                c.bit_depth,
                producer::BIT_DEPTHS
            );
        }
        for (key, scale) in [
            ("mm_per_px", c.mm_per_px),
            ("strip_mm_per_px", c.strip_mm_per_px),
        ] {
            if !(scale.is_finite() && scale > 0.0) {
                bail!("[camera] {key} = {scale}: expected a positive scale");
            }
        }
        if c.scale_mm_per_px != 0.0 {
            wire::scale::MmPerPx::new(c.scale_mm_per_px)
                .map_err(|e| anyhow!("[camera] scale_mm_per_px = {}: {e}", c.scale_mm_per_px))?;
            if c.scale_known_length.is_some() {
                bail!(
                    "[camera] scale_mm_per_px and scale_known_length: give one of them, not both"
                );
            }
        }
        producer::SpeckleParams {
            size_px: c.speckle_size_px,
            ..producer::SpeckleParams::default()
        }
        .validate()
        .map_err(|e| anyhow!("[camera] {e}"))?;
        if !(1..=64).contains(&c.threads) {
            bail!("[camera] threads = {}: expected 1 to 64", c.threads);
        }
        Ok(())
    }

    fn validate_rig(&self) -> anyhow::Result<()> {
        let g = &self.rig;
        if !(g.speed.is_finite() && g.speed > 0.0 && g.speed <= MAX_SIMULATED_SPEED) {
            bail!(
                "[rig] speed = {}: expected (0, {MAX_SIMULATED_SPEED}] times real time",
                g.speed
            );
        }
        let rig_config = rig::RigConfig::default();
        for (name, hz) in [("publish_hz", g.publish_hz), ("log_hz", g.log_hz)] {
            if !(hz.is_finite() && hz > 0.0 && hz <= rig_config.control_hz) {
                bail!(
                    "[rig] {name} = {hz}: expected (0, {}] Hz",
                    rig_config.control_hz
                );
            }
        }
        if self.strain_test()?.is_none() {
            let campaign = self.campaign()?;
            campaign
                .check_against(&rig_config)
                .map_err(|e| anyhow!("[rig] {e}"))?;
        }
        Ok(())
    }

    fn validate_sources(&self) -> anyhow::Result<()> {
        let c = &self.camera;
        match c.source {
            CameraSource::Watch if c.watch_dir.as_os_str().is_empty() => {
                bail!("[camera] source = \"watch\" needs watch_dir = \"FOLDER\"")
            }
            CameraSource::Replay if c.replay_files.trim().is_empty() => {
                bail!("[camera] source = \"replay\" needs replay_files = \"FOLDER or GLOB\"")
            }
            _ => {}
        }
        if !(c.watch_idle_timeout_s.is_finite() && c.watch_idle_timeout_s >= 0.0) {
            bail!(
                "[camera] watch_idle_timeout_s = {}: expected 0 (never) or more s",
                c.watch_idle_timeout_s
            );
        }
        if self.rig.source == RigSource::CsvFollow {
            if c.source == CameraSource::Simulated {
                bail!(
                    "[rig] source = \"csv-follow\" with [camera] source = \"simulated\": the \
                     simulated camera renders the simulated rig's motion; choose watch, replay \
                     or genicam for a real test"
                );
            }
            self.validate_csv_follow()?;
        }
        Ok(())
    }

    fn validate_csv_follow(&self) -> anyhow::Result<()> {
        let v = &self.rig.csv;
        if v.file.as_os_str().is_empty() {
            bail!("[rig.csv] file is empty: the machine's CSV log to follow");
        }
        if v.time_column.trim().is_empty() {
            bail!("[rig.csv] time_column is empty: the name of the time column");
        }
        if [&v.force_x_column, &v.force_y_column, &v.force_z_column]
            .iter()
            .all(|c| c.trim().is_empty())
        {
            bail!("[rig.csv] no force column: set force_x_column (and force_y_column, ...)");
        }
        if !v.offset_s.is_finite() {
            bail!("[rig.csv] offset_s = {}: expected seconds", v.offset_s);
        }
        for (key, a) in [
            ("section_x_mm2", v.section_x_mm2),
            ("section_y_mm2", v.section_y_mm2),
        ] {
            if !(a.is_finite() && a >= 0.0) {
                bail!("[rig.csv] {key} = {a}: expected a section in mm² (0: unknown)");
            }
        }
        if !(v.idle_timeout_s.is_finite() && v.idle_timeout_s > 0.0) {
            bail!(
                "[rig.csv] idle_timeout_s = {}: expected a positive number of seconds",
                v.idle_timeout_s
            );
        }
        Ok(())
    }

    /// The correlator settings the live correlator will run with.
    pub fn correlator_settings(&self) -> anyhow::Result<correlator::CorrelatorSettings> {
        let c = &self.correlator;
        let settings = correlator::CorrelatorSettings {
            method: c.method,
            zoi_px: c.zoi_px,
            step_px: c.step_px,
            threads: c.threads,
            strain: c.strain,
            reference: correlator::ReferenceMode::of_kind(c.reference, c.method),
            guess: c.guess,
            min_zncc: c.min_zncc,
            gradient_correction: c.gradient_correction,
            gauges: c.gauges.clone(),
            control_gauge: c.control_gauge.clone(),
            region: correlator::Region {
                // The correlator process reads the mask: from wherever it runs.
                mask: c
                    .region
                    .mask
                    .as_deref()
                    .map(std::path::absolute)
                    .transpose()
                    .with_context(|| format!("[correlator.region] mask {:?}", c.region.mask))?,
                ..c.region.clone()
            },
            ..correlator::CorrelatorSettings::default()
        };
        settings
            .validate()
            .map_err(|e| anyhow!("[correlator] {e}"))?;
        for gauge in &settings.gauges {
            gauge
                .check_inside(
                    self.camera.width_px as usize,
                    self.camera.height_px as usize,
                )
                .map_err(|e| anyhow!("[correlator] gauges: {e}"))?;
        }
        settings
            .resolve_region(
                self.camera.width_px as usize,
                self.camera.height_px as usize,
            )
            .with_context(|| {
                format!(
                    "[correlator] with the {}x{} px camera",
                    self.camera.width_px, self.camera.height_px
                )
            })?;
        Ok(settings)
    }
}
