//! The configuration of a live bench run (`dicstream run --config FILE.toml`): every knob of
//! the camera, correlator, rig campaign, specimen and identifier, with defaults that run the
//! paper's campaign in about a minute. Unknown keys are refused (a typo must not silently
//! fall back to a default), and [`RunConfig::validate`] refuses, before any process starts,
//! what the processes would refuse later: a ZOI larger than the image, a campaign beyond the
//! rig's stroke or rate limits, a frame the shared memory cannot hold.

use anyhow::{anyhow, bail, Context};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    pub run: RunSection,
    pub camera: CameraSection,
    pub correlator: CorrelatorSection,
    pub rig: RigSection,
    pub specimen: SpecimenSection,
    pub identifier: IdentifierSection,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunSection {
    /// Parent folder of the per-run results folders (`<results_dir>/<date-time>/`).
    pub results_dir: String,
    /// Restart a process that dies, at most `max_restarts` times per process.
    pub restart: bool,
    pub max_restarts: u32,
    /// Write the field of every Nth correlated frame (CSV, and VTK with `vtk`).
    pub fields_every: u32,
    pub vtk: bool,
    /// Seconds between two status lines.
    pub status_interval_s: f64,
    /// Seconds a process gets to stop after SIGTERM before SIGKILL.
    pub stop_timeout_s: f64,
    /// Seconds after which a process that is stopped (SIGSTOP) or publishes nothing while its
    /// input comes is stale: reported, killed and handled like a death.
    pub stale_after_s: f64,
    /// Address of the live dashboard (ADDR:PORT), or "off".
    pub dashboard: String,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraSection {
    pub width_px: u32,
    pub height_px: u32,
    pub fps: f64,
    pub bit_depth: u8,
    /// Scale of the image of the specimen (mm per px).
    pub mm_per_px: f64,
    pub speckle_size_px: f64,
    pub seed: u64,
    /// Rendering threads of the simulated camera.
    pub threads: usize,
    /// Where frames come from: simulated, watch, replay or genicam (see [`CameraSource`]).
    pub source: String,
    /// watch: the folder another program writes images into, and its options.
    pub watch_dir: String,
    pub watch_from_start: bool,
    /// watch: the camera ends after this long without a new image (0: never).
    pub watch_idle_timeout_s: f64,
    pub watch_settle_ms: u64,
    /// replay: a folder or a glob of images, sent at `fps`.
    pub replay_files: String,
    /// genicam: the camera's id ("" = the first found), and what is set on it ("" or absent:
    /// left as the camera has it).
    pub genicam_id: String,
    pub genicam_exposure_us: Option<f64>,
    pub genicam_gain_db: Option<f64>,
    pub genicam_pixel_format: String,
    /// x,y,w,h px.
    pub genicam_roi: String,
    /// software, hardware or free.
    pub genicam_trigger: String,
}

/// Where a run's frames come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraSource {
    /// Rendered from the simulated rig's motion: ground truth in every frame.
    Simulated,
    /// Images another program writes into a folder.
    Watch,
    /// Image files sent at a fixed rate.
    Replay,
    /// A GenICam camera (a build with the `genicam` feature).
    Genicam,
}

impl CameraSource {
    pub fn parse(text: &str) -> Option<CameraSource> {
        match text {
            "simulated" => Some(CameraSource::Simulated),
            "watch" => Some(CameraSource::Watch),
            "replay" => Some(CameraSource::Replay),
            "genicam" => Some(CameraSource::Genicam),
            _ => None,
        }
    }

    /// Only the simulated camera's frames carry the exact motion (truth columns, acceptance).
    pub fn has_truth(self) -> bool {
        self == CameraSource::Simulated
    }
}

/// Where a run's rig samples come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigSource {
    /// The simulated machine runs the campaign of `[[rig.tests]]`.
    Simulated,
    /// A test machine's CSV log, followed as it grows (`[rig.csv]`).
    CsvFollow,
}

/// `[rig.csv]`: the test machine's CSV log a `csv-follow` rig follows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CsvFollowSection {
    pub file: String,
    /// Column names as in the header, without their unit ("" = not logged).
    pub time_column: String,
    pub force_x_column: String,
    pub force_y_column: String,
    pub force_z_column: String,
    pub displacement_x_column: String,
    pub displacement_y_column: String,
    pub displacement_z_column: String,
    /// s, ms or min; N or kN; mm, um or m ("" = as the header says: `Fx (kN)`).
    pub time_unit: String,
    pub force_unit: String,
    pub displacement_unit: String,
    /// ",", ";" or "tab".
    pub delimiter: String,
    /// Seconds added to the machine's time to put it on the camera's (camera − machine).
    pub offset_s: f64,
    /// Initial specimen sections normal to X and Y, mm² (0: unknown, no stress).
    pub section_x_mm2: f64,
    pub section_y_mm2: f64,
    /// The test is over after this long without a new row.
    pub idle_timeout_s: f64,
}

impl Default for CsvFollowSection {
    fn default() -> Self {
        CsvFollowSection {
            file: String::new(),
            time_column: String::new(),
            force_x_column: String::new(),
            force_y_column: String::new(),
            force_z_column: String::new(),
            displacement_x_column: String::new(),
            displacement_y_column: String::new(),
            displacement_z_column: String::new(),
            time_unit: String::new(),
            force_unit: String::new(),
            displacement_unit: String::new(),
            delimiter: ",".into(),
            offset_s: 0.0,
            section_x_mm2: 0.0,
            section_y_mm2: 0.0,
            idle_timeout_s: 10.0,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CorrelatorSection {
    /// Sub-pixel method: icgn1, icgn2 or correli.
    pub method: String,
    pub zoi_px: usize,
    pub step_px: usize,
    pub threads: usize,
    /// Strain measure of the node strains: log, green, nominal or small.
    pub strain: String,
    /// Reference: fixed, incremental or auto.
    pub reference: String,
    /// Initial guess: auto, predict or correli.
    pub guess: String,
    /// A node is ok only when its final ZNCC check reaches this.
    pub min_zncc: f64,
    /// First-order correction of the rigid ZOI's bias under a displacement gradient.
    pub gradient_correction: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RigSection {
    /// Simulated time per wall time (1 = real time).
    pub speed: f64,
    /// Rate of `rig/state` and of `rig.csv` (Hz of simulated time).
    pub publish_hz: f64,
    pub log_hz: f64,
    pub seed: u64,
    /// The tests, in order; each mounts its own specimen and unloads at the end.
    pub tests: Vec<TestSection>,
    /// simulated or csv-follow.
    pub source: String,
    pub csv: CsvFollowSection,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TestSection {
    /// uniaxial or equibiaxial; under strain control also pure_shear or biaxial.
    pub kind: String,
    /// Displacement: the final grip stretch; strain: the target of the larger measured stretch.
    pub stretch: f64,
    /// Displacement: the stretch rate; strain: the rate of the larger log strain (/s).
    pub rate_per_s: f64,
    /// displacement (the grips follow the program; the default) or strain (the correlator's
    /// fields close the loop on the gauge zone's log strains; a test alone in its run).
    #[serde(
        default = "TestSection::displacement",
        skip_serializing_if = "TestSection::is_displacement"
    )]
    pub control: String,
    /// Strain control, biaxial: ρ = ln λy / ln λx held along the path.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ratio: Option<f64>,
    /// Strain control: hold the grips when the newest field is older than this (s) [0.5].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stale_s: Option<f64>,
    /// Strain control: hold on a field with fewer converged nodes [16].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_valid_nodes: Option<u32>,
    /// Strain control, once fields are usable again after a hold: resume or stop [resume].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on_interlock: Option<String>,
}

impl TestSection {
    /// A test under displacement control (today's tests).
    pub fn new(kind: &str, stretch: f64, rate_per_s: f64) -> TestSection {
        TestSection {
            kind: kind.into(),
            stretch,
            rate_per_s,
            control: TestSection::displacement(),
            ratio: None,
            stale_s: None,
            min_valid_nodes: None,
            on_interlock: None,
        }
    }

    fn displacement() -> String {
        "displacement".into()
    }

    fn is_displacement(control: &String) -> bool {
        control == "displacement"
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpecimenSection {
    /// ln f(I1) = Σ a_i (I1 − 3)^i (eq. 22), f in MPa.
    pub law_f: Vec<f64>,
    /// ln g(I2) = Σ b_i (I2 − 3)^i (eq. 25), g in MPa.
    pub law_g: Vec<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IdentifierSection {
    /// Models ranked at each refit, NAME[,NAME...] or all.
    pub models: String,
}

impl Default for RunSection {
    fn default() -> Self {
        RunSection {
            results_dir: "results".into(),
            restart: true,
            max_restarts: 3,
            fields_every: 10,
            vtk: false,
            status_interval_s: 1.0,
            stop_timeout_s: 5.0,
            stale_after_s: 5.0,
            dashboard: dashboard::address::DEFAULT.into(),
        }
    }
}

impl Default for CameraSection {
    fn default() -> Self {
        CameraSection {
            width_px: 1024,
            height_px: 1024,
            fps: 10.0,
            bit_depth: 8,
            mm_per_px: 0.015,
            speckle_size_px: 4.0,
            seed: 1,
            threads: 1,
            source: "simulated".into(),
            watch_dir: String::new(),
            watch_from_start: false,
            watch_idle_timeout_s: 0.0,
            watch_settle_ms: producer::DEFAULT_SETTLE_MS,
            replay_files: String::new(),
            genicam_id: String::new(),
            genicam_exposure_us: None,
            genicam_gain_db: None,
            genicam_pixel_format: String::new(),
            genicam_roi: String::new(),
            genicam_trigger: String::new(),
        }
    }
}

impl Default for CorrelatorSection {
    fn default() -> Self {
        CorrelatorSection {
            method: correlator::settings::Method::default().name().into(),
            zoi_px: 32,
            step_px: 16,
            threads: 2,
            strain: "log".into(),
            reference: "auto".into(),
            guess: "auto".into(),
            min_zncc: correlator::DEFAULT_MIN_ZNCC,
            gradient_correction: true,
        }
    }
}

impl Default for RigSection {
    fn default() -> Self {
        let tests = rig::Campaign::paper()
            .tests()
            .iter()
            .map(|t| TestSection::new(test_kind_name(t.test), t.stretch, t.rate_per_s))
            .collect();
        RigSection {
            speed: 1.0,
            publish_hz: 200.0,
            log_hz: 50.0,
            seed: 1,
            tests,
            source: "simulated".into(),
            csv: CsvFollowSection::default(),
        }
    }
}

impl Default for SpecimenSection {
    fn default() -> Self {
        let law = identifier::law::InvariantLaw::smactane();
        SpecimenSection {
            law_f: law.f.coefficients().to_vec(),
            law_g: law.g.coefficients().to_vec(),
        }
    }
}

impl Default for IdentifierSection {
    fn default() -> Self {
        IdentifierSection {
            models: "lambert-diani-rey,neo-hookean,mooney,yeoh,gent,hart-smith".into(),
        }
    }
}

fn test_kind_name(test: rig::builtin::BuiltinTest) -> &'static str {
    match test {
        rig::builtin::BuiltinTest::Uniaxial => "uniaxial",
        rig::builtin::BuiltinTest::Equibiaxial => "equibiaxial",
    }
}

/// Largest stretch rate the live bench accepts (/s of simulated time): beyond it the camera
/// sees too much motion between frames at the default rate.
const MAX_SIMULATED_SPEED: f64 = 20.0;

impl RunConfig {
    /// Parses a TOML file's text; errors name the file and the offending key or line.
    pub fn from_toml(text: &str, source: &str) -> anyhow::Result<RunConfig> {
        toml::from_str(text).with_context(|| source.to_string())
    }

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("the run configuration serialises")
    }

    /// Where frames come from (validated: an unknown name is refused by [`Self::validate`]).
    pub fn camera_source(&self) -> CameraSource {
        CameraSource::parse(&self.camera.source).unwrap_or(CameraSource::Simulated)
    }

    /// Where rig samples come from.
    pub fn rig_source(&self) -> RigSource {
        match self.rig.source.as_str() {
            "csv-follow" => RigSource::CsvFollow,
            _ => RigSource::Simulated,
        }
    }

    fn validate_sources(&self) -> anyhow::Result<()> {
        let c = &self.camera;
        let camera = CameraSource::parse(&c.source).ok_or_else(|| {
            anyhow!(
                "[camera] source = {:?}: expected simulated, watch, replay or genicam",
                c.source
            )
        })?;
        match camera {
            CameraSource::Watch if c.watch_dir.trim().is_empty() => {
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
        if !c.genicam_pixel_format.is_empty()
            && !["Mono8", "Mono10", "Mono12", "Mono16"].contains(&c.genicam_pixel_format.as_str())
        {
            bail!(
                "[camera] genicam_pixel_format = {:?}: expected Mono8, Mono10, Mono12 or Mono16",
                c.genicam_pixel_format
            );
        }
        if !c.genicam_trigger.is_empty()
            && !["software", "hardware", "free"].contains(&c.genicam_trigger.as_str())
        {
            bail!(
                "[camera] genicam_trigger = {:?}: expected software, hardware or free",
                c.genicam_trigger
            );
        }
        if !c.genicam_roi.is_empty() {
            let parts: Vec<Option<u32>> = c
                .genicam_roi
                .split(',')
                .map(|p| p.trim().parse().ok())
                .collect();
            if parts.len() != 4 || parts.iter().any(Option::is_none) {
                bail!(
                    "[camera] genicam_roi = {:?}: expected \"x,y,w,h\" in px",
                    c.genicam_roi
                );
            }
        }
        let rig = match self.rig.source.as_str() {
            "simulated" => RigSource::Simulated,
            "csv-follow" => RigSource::CsvFollow,
            other => bail!("[rig] source = {other:?}: expected simulated or csv-follow"),
        };
        if rig == RigSource::CsvFollow {
            if camera == CameraSource::Simulated {
                bail!(
                    "[rig] source = \"csv-follow\" with [camera] source = \"simulated\": the \
                     simulated camera renders the simulated rig's motion; choose watch, replay \
                     or genicam for a real test"
                );
            }
            let v = &self.rig.csv;
            if v.file.trim().is_empty() {
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
            use rig::csv_follow::columns as units;
            for (key, unit, ok, expected) in [
                (
                    "time_unit",
                    &v.time_unit,
                    units::TimeUnit::parse(&v.time_unit).is_some(),
                    units::TIME_UNITS,
                ),
                (
                    "force_unit",
                    &v.force_unit,
                    units::ForceUnit::parse(&v.force_unit).is_some(),
                    units::FORCE_UNITS,
                ),
                (
                    "displacement_unit",
                    &v.displacement_unit,
                    units::LengthUnit::parse(&v.displacement_unit).is_some(),
                    units::LENGTH_UNITS,
                ),
            ] {
                if !unit.is_empty() && !ok {
                    bail!(
                        "[rig.csv] {key} = {unit:?}: expected {expected}, or \"\" (the header's)"
                    );
                }
            }
            if ![",", ";", "tab"].contains(&v.delimiter.as_str()) {
                bail!(
                    "[rig.csv] delimiter = {:?}: expected \",\", \";\" or \"tab\"",
                    v.delimiter
                );
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
        }
        Ok(())
    }

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
            .map(|t| match t.control.as_str() {
                "strain" => format!("strain:{}:{}@{}", t.kind, t.stretch, t.rate_per_s),
                _ => format!("{}:{}@{}", t.kind, t.stretch, t.rate_per_s),
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

    /// Largest stretch any test reaches: the camera's pattern must cover it.
    pub fn max_stretch(&self) -> f64 {
        self.rig.tests.iter().map(|t| t.stretch).fold(1.0, f64::max)
    }

    /// The correlator settings the live correlator will run with.
    pub fn correlator_settings(&self) -> anyhow::Result<correlator::CorrelatorSettings> {
        use correlator::{GuessMode, ReferenceMode, StrainMeasure};
        let c = &self.correlator;
        let strain = StrainMeasure::from_name(&c.strain).ok_or_else(|| {
            anyhow!(
                "[correlator] strain = {:?}: expected log, green, nominal or small",
                c.strain
            )
        })?;
        let reference = ReferenceMode::from_name(&c.reference).ok_or_else(|| {
            anyhow!(
                "[correlator] reference = {:?}: expected fixed, incremental or auto",
                c.reference
            )
        })?;
        let method = correlator::settings::Method::from_name(&c.method).ok_or_else(|| {
            anyhow!(
                "[correlator] method = {:?}: expected icgn1, icgn2 or correli",
                c.method
            )
        })?;
        let guess = GuessMode::from_name(&c.guess).ok_or_else(|| {
            anyhow!(
                "[correlator] guess = {:?}: expected auto, predict or correli",
                c.guess
            )
        })?;
        let settings = correlator::CorrelatorSettings {
            method,
            zoi_px: c.zoi_px,
            step_px: c.step_px,
            threads: c.threads,
            strain,
            reference,
            guess,
            min_zncc: c.min_zncc,
            gradient_correction: c.gradient_correction,
            ..correlator::CorrelatorSettings::default()
        };
        settings
            .validate()
            .map_err(|e| anyhow!("[correlator] {e}"))?;
        settings
            .resolve_roi(
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

    /// Everything a process would refuse, refused now with the section and key named.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.validate_sources()?;
        let r = &self.run;
        if r.results_dir.trim().is_empty() {
            bail!("[run] results_dir is empty");
        }
        if r.fields_every == 0 {
            bail!("[run] fields_every = 0: expected 1 or more (1 = every field)");
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
        if r.dashboard != "off" {
            dashboard::address::parse(&r.dashboard).context("[run]")?;
        }
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
        if !(c.mm_per_px.is_finite() && c.mm_per_px > 0.0) {
            bail!(
                "[camera] mm_per_px = {}: expected a positive scale",
                c.mm_per_px
            );
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
        self.correlator_settings()?;
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
        identifier::models::parse_model_list(&self.identifier.models)
            .context("[identifier] models")?;
        Ok(())
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
            let at = format!("[[rig.tests]] {} (kind {:?})", k + 1, t.kind);
            match t.control.as_str() {
                "displacement" => {
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
                    if ["pure_shear", "biaxial"].contains(&t.kind.as_str()) {
                        bail!(
                            "{at}: a {} path is held on the measured strains: set control = \"strain\"",
                            t.kind
                        );
                    }
                }
                "strain" => {}
                other => bail!("{at}: control = {other:?}: expected displacement or strain"),
            }
        }
        let Some(t) = tests.iter().find(|t| t.control == "strain") else {
            return Ok(None);
        };
        if tests.len() > 1 {
            bail!(
                "[[rig.tests]]: a strain-controlled test runs alone in its run ({} tests given); \
                 run one config per strain path",
                tests.len()
            );
        }
        if self.rig.source == "csv-follow" {
            bail!(
                "[[rig.tests]] control = \"strain\" with [rig] source = \"csv-follow\": strain \
                 control drives the simulated rig; a followed machine's log cannot be steered"
            );
        }
        let test = rig::strain::StrainTest::new(&t.kind, t.ratio, t.stretch, t.rate_per_s)
            .and_then(|test| {
                test.with_interlocks(
                    t.stale_s.unwrap_or(rig::strain::test::DEFAULT_STALE_S),
                    t.min_valid_nodes
                        .unwrap_or(rig::strain::test::DEFAULT_MIN_VALID_NODES),
                    t.on_interlock.as_deref().unwrap_or("resume"),
                )
            })
            .map_err(|e| anyhow!("[[rig.tests]] 1 (control = \"strain\"): {e}"))?;
        Ok(Some(test))
    }

    /// The defaults as a commented TOML file to start from (`dicstream run --print-config`).
    pub fn commented_defaults() -> String {
        let d = RunConfig::default();
        let mut t = String::new();
        let _ = writeln!(
            t,
            "# dicstream run configuration. Every key is optional: a missing key takes the value\n\
             # shown here. Unknown keys are refused.\n"
        );
        let _ = writeln!(t, "[run]");
        let _ = writeln!(
            t,
            "# Parent folder of the per-run results folders (<results_dir>/<date-time>/).\n\
             results_dir = {:?}\n\
             # Restart a process that dies (at most max_restarts times each).\n\
             restart = {}\nmax_restarts = {}\n\
             # Keep the field of every Nth correlated frame (fields/field_<frame>.csv, and .vtk).\n\
             fields_every = {}\nvtk = {}\n\
             # Seconds between two status lines, and given to a process to stop before SIGKILL.\n\
             status_interval_s = {:?}\nstop_timeout_s = {:?}\n\
             # Seconds after which a stopped (SIGSTOP) or silent process is killed as hung.\n\
             stale_after_s = {:?}\n",
            d.run.results_dir,
            d.run.restart,
            d.run.max_restarts,
            d.run.fields_every,
            d.run.vtk,
            d.run.status_interval_s,
            d.run.stop_timeout_s,
            d.run.stale_after_s
        );
        let _ = writeln!(
            t,
            "# The live dashboard (ADDR:PORT, or \"off\"); a non-loopback address serves other\n\
             # machines too.\ndashboard = {:?}\n",
            d.run.dashboard
        );
        let c = &d.camera;
        let _ = writeln!(
            t,
            "[camera]\n\
             # The simulated camera renders the specimen as the rig deforms it.\n\
             width_px = {}\nheight_px = {}\nfps = {:?}\n\
             # 8, 10, 12 or 16 bit.\n\
             bit_depth = {}\n\
             # Image scale of the specimen, mm per px.\n\
             mm_per_px = {:?}\n\
             # Speckle spot size (FWHM), px; seed of the pattern and the noise.\n\
             speckle_size_px = {:?}\nseed = {}\n\
             # Rendering threads (the correlator wants the cores more).\n\
             threads = {}\n\
             # Where frames come from: simulated (rendered from the simulated rig, with ground\n\
             # truth), watch (images another program writes into watch_dir), replay (the\n\
             # images of replay_files at fps) or genicam (a GenICam camera: a build with the\n\
             # genicam feature). Real images have no ground truth: no truth columns, no\n\
             # acceptance. width_px/height_px must then be the images' size.\n\
             source = {:?}\n\
             watch_dir = {:?}\nwatch_from_start = {}\n\
             # 0: the camera never ends by itself.\n\
             watch_idle_timeout_s = {:?}\nwatch_settle_ms = {}\n\
             replay_files = {:?}\n\
             # genicam_id \"\" = the first camera; genicam_exposure_us, genicam_gain_db when set;\n\
             # pixel format Mono8/10/12/16, roi \"x,y,w,h\", trigger software/hardware/free\n\
             # (\"\" = as the camera is).\n\
             genicam_id = {:?}\ngenicam_pixel_format = {:?}\ngenicam_roi = {:?}\n\
             genicam_trigger = {:?}\n",
            c.width_px,
            c.height_px,
            c.fps,
            c.bit_depth,
            c.mm_per_px,
            c.speckle_size_px,
            c.seed,
            c.threads,
            c.source,
            c.watch_dir,
            c.watch_from_start,
            c.watch_idle_timeout_s,
            c.watch_settle_ms,
            c.replay_files,
            c.genicam_id,
            c.genicam_pixel_format,
            c.genicam_roi,
            c.genicam_trigger
        );
        let k = &d.correlator;
        let _ = writeln!(
            t,
            "[correlator]\n\
             # Sub-pixel method: correli (the paper; the default, the fastest), icgn1 (inverse\n\
             # compositional Gauss-Newton, affine subsets: less noise, several times slower)\n\
             # or icgn2 (second-order subsets).\n\
             method = {:?}\n\
             # ZOI (subset) side px (any size from 9 for icgn1/icgn2, 2^s for correli) and\n\
             # distance between ZOI centres px (paper section 3.b).\n\
             zoi_px = {}\nstep_px = {}\nthreads = {}\n\
             # Node strain measure: log (m = 0), green (m = 1), nominal (m = 1/2) or small.\n\
             strain = {:?}\n\
             # Reference: fixed, incremental (consecutive frames) or auto (renewed when the\n\
             # displacement or the score call for it, mesh followed).\n\
             reference = {:?}\n\
             # Initial guess per ZOI: auto (previous field or significant global (U0, V0),\n\
             # failed nodes grown from verified neighbours, keypoints when too few verify),\n\
             # predict (previous field, neighbours) or correli (paper).\n\
             guess = {:?}\n\
             # A node is ok only when the ZNCC of its reference ZOI with the frame, sampled at\n\
             # its displacement and local gradient, reaches this (0 < min_zncc < 1).\n\
             min_zncc = {}\n\
             # Remove, to first order, the rigid ZOI's bias under a displacement gradient\n\
             # (beyond the paper; false = CORRELI-GD as published).\n\
             gradient_correction = {}\n",
            k.method,
            k.zoi_px,
            k.step_px,
            k.threads,
            k.strain,
            k.reference,
            k.guess,
            k.min_zncc,
            k.gradient_correction
        );
        let g = &d.rig;
        let _ = writeln!(
            t,
            "[rig]\n\
             # Simulated time per wall time; rig/state and rig.csv rates, Hz of simulated time.\n\
             speed = {:?}\npublish_hz = {:?}\nlog_hz = {:?}\nseed = {}\n\
             # simulated (the campaign below) or csv-follow (a test machine's CSV log, [rig.csv]).\n\
             source = {:?}\n",
            g.speed, g.publish_hz, g.log_hz, g.seed, g.source
        );
        let _ = writeln!(
            t,
            "# The campaign, in order: each test mounts its specimen (uniaxial: a 100 x 20 x 2 mm\n\
             # strip; equibiaxial: a 100 x 100 x 2 mm cruciform centre), ramps the elongation to\n\
             # `stretch` at `rate_per_s` in centroid control, holds, unloads. A test alone may\n\
             # instead be strain-controlled (the correlator's fields close the loop):\n\
             # control = \"strain\", kind = uniaxial | equibiaxial | pure_shear | biaxial,\n\
             # ratio = ln(ly)/ln(lx) (biaxial), stretch = the larger measured stretch,\n\
             # rate_per_s = log strain rate; stale_s = 1.5, min_valid_nodes = 16,\n\
             # on_interlock = \"resume\" | \"stop\"."
        );
        for test in &g.tests {
            let _ = writeln!(
                t,
                "[[rig.tests]]\nkind = {:?}\nstretch = {:?}\nrate_per_s = {:?}\n",
                test.kind, test.stretch, test.rate_per_s
            );
        }
        let v = &g.csv;
        let _ = writeln!(
            t,
            "[rig.csv]\n\
             # The CSV a test machine's software appends to (waited for if missing; a partial\n\
             # last line waits for its newline; a malformed line is reported and skipped).\n\
             file = {:?}\n\
             # Column names as in the header, without their unit (\"\" = not logged).\n\
             time_column = {:?}\nforce_x_column = {:?}\nforce_y_column = {:?}\n\
             force_z_column = {:?}\ndisplacement_x_column = {:?}\n\
             displacement_y_column = {:?}\ndisplacement_z_column = {:?}\n\
             # Units: s/ms/min, N/kN, mm/um/m; \"\" = as the header says (`Fx (kN)`).\n\
             time_unit = {:?}\nforce_unit = {:?}\ndisplacement_unit = {:?}\n\
             # \",\", \";\" or \"tab\" (with \";\" and tab a decimal comma is read too).\n\
             delimiter = {:?}\n\
             # Seconds added to the machine's time to put it on the camera's.\n\
             offset_s = {:?}\n\
             # Initial specimen sections normal to X and Y, mm² (stress = force / section).\n\
             section_x_mm2 = {:?}\nsection_y_mm2 = {:?}\n\
             # The test is over after this long without a new row.\n\
             idle_timeout_s = {:?}\n",
            v.file,
            v.time_column,
            v.force_x_column,
            v.force_y_column,
            v.force_z_column,
            v.displacement_x_column,
            v.displacement_y_column,
            v.displacement_z_column,
            v.time_unit,
            v.force_unit,
            v.displacement_unit,
            v.delimiter,
            v.offset_s,
            v.section_x_mm2,
            v.section_y_mm2,
            v.idle_timeout_s
        );
        let s = &d.specimen;
        let _ = writeln!(
            t,
            "[specimen]\n\
             # Material of the specimens: ln f(I1) = sum a_i (I1 - 3)^i and\n\
             # ln g(I2) = sum b_i (I2 - 3)^i (eqs. 22, 25; f, g in MPa). Default: Smactane,\n\
             # Tables 3 and 4 (n = 2). A virtual test must give them back.\n\
             law_f = {:?}\nlaw_g = {:?}\n",
            s.law_f, s.law_g
        );
        let _ = writeln!(
            t,
            "[identifier]\n\
             # Models ranked at each refit (see `dicstream identify --help`), or all.\n\
             models = {:?}",
            d.identifier.models
        );
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commented_defaults_parse_back_to_the_defaults() {
        let text = RunConfig::commented_defaults();
        let parsed = RunConfig::from_toml(&text, "defaults").unwrap();
        assert_eq!(parsed, RunConfig::default());
        RunConfig::default().validate().unwrap();
        let round = RunConfig::from_toml(&RunConfig::default().to_toml(), "round").unwrap();
        assert_eq!(round, RunConfig::default());
        assert_eq!(
            RunConfig::default().campaign_spec(),
            "uniaxial:3@0.08,equibiaxial:2@0.04"
        );
    }

    #[test]
    fn the_example_configs_are_valid_strain_controlled_runs() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/configs");
        for (name, ratio) in [
            ("strain_equibiaxial.toml", 1.0),
            ("strain_biaxial_rho05.toml", 0.5),
        ] {
            let text = std::fs::read_to_string(dir.join(name)).unwrap();
            let config = RunConfig::from_toml(&text, name).unwrap();
            config.validate().unwrap();
            let test = config.strain_test().unwrap().expect(name);
            assert_eq!((test.ratio, test.stretch), (ratio, 1.8), "{name}");
        }
    }

    #[test]
    fn strain_controlled_tests_are_checked_and_the_default_is_unchanged() {
        // Displacement control stays the default, and its config file does not change.
        let d = RunConfig::default();
        assert!(d.strain_test().unwrap().is_none());
        assert!(!d.to_toml().contains("control"), "{}", d.to_toml());
        let strain = |body: &str| {
            RunConfig::from_toml(&format!("[[rig.tests]]\n{body}"), "t.toml")
                .unwrap()
                .validate()
        };
        strain("kind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.8\nrate_per_s = 0.02\n")
            .unwrap();
        strain("kind = \"pure_shear\"\ncontrol = \"strain\"\nstretch = 1.8\nrate_per_s = 0.02\n")
            .unwrap();
        let config = RunConfig::from_toml(
            "[[rig.tests]]\nkind = \"biaxial\"\ncontrol = \"strain\"\nratio = 0.5\nstretch = 1.5\n\
             rate_per_s = 0.02\nmin_valid_nodes = 50\n",
            "t.toml",
        )
        .unwrap();
        let test = config.strain_test().unwrap().unwrap();
        assert_eq!((test.ratio, test.stretch), (0.5, 1.5));
        assert_eq!(test.limits.min_valid_nodes, 50);
        assert_eq!(test.limits.stale_s, rig::strain::test::DEFAULT_STALE_S);
        // Round trip through the results' config.toml.
        let round = RunConfig::from_toml(&config.to_toml(), "round").unwrap();
        assert_eq!(round, config);
        let refused = |body: &str, expected: &str| {
            let error = format!("{:#}", strain(body).unwrap_err());
            assert!(error.contains(expected), "{body}: {error}");
        };
        refused(
            "kind = \"uniaxial\"\ncontrol = \"strain\"\nratio = 0.5\nstretch = 1.5\nrate_per_s = 0.02\n",
            "only a biaxial",
        );
        refused(
            "kind = \"biaxial\"\ncontrol = \"strain\"\nratio = nan\nstretch = 1.5\nrate_per_s = 0.02\n",
            "ratio NaN",
        );
        refused(
            "kind = \"biaxial\"\ncontrol = \"strain\"\nstretch = 1.5\nrate_per_s = 0.02\n",
            "needs its ratio",
        );
        refused(
            "kind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.0\nrate_per_s = 0.02\n",
            "stretch 1",
        );
        refused(
            "kind = \"equibiaxial\"\ncontrol = \"force\"\nstretch = 1.5\nrate_per_s = 0.02\n",
            "expected displacement or strain",
        );
        refused(
            "kind = \"equibiaxial\"\nratio = 1.0\nstretch = 1.5\nrate_per_s = 0.02\n",
            "ratio applies to control = \"strain\" only",
        );
        refused(
            "kind = \"pure_shear\"\nstretch = 1.5\nrate_per_s = 0.02\n",
            "set control = \"strain\"",
        );
        refused(
            "kind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.5\nrate_per_s = 0.02\n\
             on_interlock = \"pause\"\n",
            "resume or stop",
        );
        refused(
            "kind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.5\nrate_per_s = 0.02\n\
             [[rig.tests]]\nkind = \"uniaxial\"\nstretch = 2.0\nrate_per_s = 0.08\n",
            "runs alone",
        );
        let csv = RunConfig::from_toml(
            "[camera]\nsource = \"watch\"\nwatch_dir = \"/tmp/x\"\n[rig]\nsource = \"csv-follow\"\n\
             [rig.csv]\nfile = \"m.csv\"\ntime_column = \"t\"\nforce_x_column = \"F\"\n\
             [[rig.tests]]\nkind = \"equibiaxial\"\ncontrol = \"strain\"\nstretch = 1.5\n\
             rate_per_s = 0.02\n",
            "t.toml",
        )
        .unwrap();
        let error = format!("{:#}", csv.strain_test().unwrap_err());
        assert!(error.contains("csv-follow"), "{error}");
    }

    #[test]
    fn bad_configurations_are_refused_with_the_key_named() {
        let unknown = RunConfig::from_toml("[camera]\nwidht_px = 512\n", "my.toml").unwrap_err();
        let unknown = format!("{unknown:#}");
        assert!(
            unknown.contains("my.toml") && unknown.contains("widht_px"),
            "{unknown}"
        );
        let refuse = |toml: &str, expected: &str| {
            let config = RunConfig::from_toml(toml, "t.toml").unwrap();
            let error = format!("{:#}", config.validate().unwrap_err());
            assert!(error.contains(expected), "{toml}: {error}");
        };
        refuse(
            "[camera]\nwidth_px = 128\nheight_px = 128\n[correlator]\nzoi_px = 256\n",
            "larger than the ROI",
        );
        refuse(
            "[correlator]\nmethod = \"correli\"\nzoi_px = 48\n",
            "power of two",
        );
        refuse("[correlator]\nmethod = \"icgn1\"\nzoi_px = 8\n", "9 to 256");
        refuse("[correlator]\nmethod = \"icgn3\"\n", "method");
        refuse(
            "[[rig.tests]]\nkind = \"uniaxial\"\nstretch = 7.0\nrate_per_s = 0.08\n",
            "stroke",
        );
        refuse(
            "[[rig.tests]]\nkind = \"equibiaxial\"\nstretch = 1.5\nrate_per_s = 50.0\n",
            "rate",
        );
        refuse(
            "[[rig.tests]]\nkind = \"shear\"\nstretch = 1.5\nrate_per_s = 0.1\n",
            "unknown test",
        );
        refuse("[rig]\ntests = []\n", "at least one");
        refuse("[rig]\nspeed = 1000.0\n", "speed");
        refuse("[camera]\nfps = -1.0\n", "fps");
        refuse("[camera]\nbit_depth = 9\n", "bit_depth");
        refuse("[specimen]\nlaw_f = []\n", "law_f");
        refuse("[identifier]\nmodels = \"nope\"\n", "models");
        refuse("[correlator]\nreference = \"sometimes\"\n", "reference");
        refuse("[camera]\nsource = \"webcam\"\n", "source");
        refuse("[camera]\nsource = \"watch\"\n", "watch_dir");
        refuse("[camera]\nsource = \"replay\"\n", "replay_files");
        refuse(
            "[camera]\nsource = \"genicam\"\ngenicam_pixel_format = \"RGB8\"\n",
            "Mono16",
        );
        refuse("[camera]\ngenicam_roi = \"1,2,3\"\n", "x,y,w,h");
        refuse("[rig]\nsource = \"csv\"\n", "csv-follow");
        refuse("[rig]\nsource = \"csv-follow\"\n", "simulated camera");
        let real = "[camera]\nsource = \"watch\"\nwatch_dir = \"/tmp/x\"\n[rig]\nsource = \"csv-follow\"\n";
        refuse(real, "file is empty");
        refuse(
            &format!("{real}[rig.csv]\nfile = \"m.csv\"\ntime_column = \"t\"\n"),
            "no force column",
        );
        refuse(
            &format!(
                "{real}[rig.csv]\nfile = \"m.csv\"\ntime_column = \"t\"\nforce_x_column = \"F\"\n\
                 force_unit = \"lbf\"\n"
            ),
            "force_unit",
        );
        let ok = RunConfig::from_toml(
            &format!(
                "{real}[rig.csv]\nfile = \"m.csv\"\ntime_column = \"t\"\nforce_x_column = \"F\"\n"
            ),
            "ok.toml",
        )
        .unwrap();
        ok.validate().unwrap();
        assert_eq!(ok.camera_source(), CameraSource::Watch);
        assert_eq!(ok.rig_source(), RigSource::CsvFollow);
        let round = RunConfig::from_toml(&ok.to_toml(), "round").unwrap();
        assert_eq!(round, ok);
    }
}
