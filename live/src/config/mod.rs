//! The configuration of a live bench run (`dicstream run --config FILE.toml`): every knob of
//! the camera, correlator, rig campaign, specimen and identifier, typed as the processes take
//! them, with defaults that run the paper's campaign in about a minute. The TOML is read once
//! into these types: a word that names no choice (`method = "icgn3"`), an unknown key (a typo
//! must not silently fall back to a default) or a value of the wrong type is refused with the
//! key and line named. [`RunConfig::validate`] then refuses, before any process starts, what
//! the processes would refuse later: a ZOI larger than the image, a campaign beyond the rig's
//! stroke or rate limits, a frame the shared memory cannot hold.
//!
//! - [`sources`]: where frames and rig samples come from;
//! - [`validate`]: the checks across keys, with the section and key named;
//! - [`campaign`]: the rig's tests, the strain-controlled one, the campaign's length;
//! - [`commented`]: `--print-config`, the defaults with a comment per key (checked to cover
//!   every key the types write).

mod campaign;
mod commented;
pub mod sources;
mod validate;

#[cfg(test)]
mod tests;

pub use sources::{BenchProcess, CameraSource, DashboardListen, RigSource};

use correlator::settings::{GuessMode, Method, ReferenceKind, StrainMeasure};
use identifier::models::ModelList;
use producer::genicam::{PixelFormat, Roi as SensorRoi, Trigger};
use rig::csv_follow::columns::{ForceUnit, LengthUnit, TimeUnit};
use rig::csv_follow::delimiter::Delimiter;
use rig::strain::control::OnRestore;
use rig::strain::{StrainKind, TestControl};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    pub run: RunSection,
    pub camera: CameraSection,
    pub correlator: CorrelatorSection,
    pub rig: RigSection,
    pub specimen: SpecimenSection,
    pub identifier: IdentifierSection,
    /// The link to another host's instance (`dicstream link`; absent: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub link: Option<link::LinkSection>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunSection {
    /// Parent folder of the per-run results folders (`<results_dir>/<date-time>/`).
    pub results_dir: PathBuf,
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
    /// Where the live dashboard listens (ADDR:PORT), or off.
    #[serde(with = "wire::names::text")]
    pub dashboard: DashboardListen,
    /// The colour range of `strain_map.png`: auto (a floor tied to the field's noise),
    /// symmetric (about zero) or LO:HI (strain, e.g. -0.01:0.05).
    #[serde(with = "wire::names::text")]
    pub map_range: wire::colour_range::RangeChoice,
    /// The processes of the bench this host's run starts (all four by default; on two hosts,
    /// each its part, the others' services coming over `[link]`).
    pub processes: Vec<BenchProcess>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraSection {
    pub width_px: u32,
    pub height_px: u32,
    pub fps: f64,
    pub bit_depth: u8,
    /// Scale of the image of the specimen (mm per px): of a cruciform or the homogeneous
    /// sheet.
    pub mm_per_px: f64,
    /// Scale of the image of a finite-element strip (the uniaxial tests' specimen on a
    /// structure: the camera is re-framed on it), mm per px.
    pub strip_mm_per_px: f64,
    /// The fields' scale, mm per px, for their mm columns (0: not given: the simulated
    /// camera's framing, none for a real camera); or from a known length, "X1,Y1 X2,Y2 MM".
    pub scale_mm_per_px: f64,
    #[serde(with = "wire::names::empty_is_none")]
    pub scale_known_length: Option<wire::scale::KnownLength>,
    pub speckle_size_px: f64,
    pub seed: u64,
    /// Rendering threads of the simulated camera.
    pub threads: usize,
    /// Where frames come from.
    pub source: CameraSource,
    /// watch: the folder another program writes images into, and its options.
    pub watch_dir: PathBuf,
    pub watch_from_start: bool,
    /// watch: the camera ends after this long without a new image (0: never).
    pub watch_idle_timeout_s: f64,
    pub watch_settle_ms: u64,
    /// replay: a folder or a glob of images, sent at `fps`.
    pub replay_files: String,
    /// genicam: the camera's id ("" = the first found), and what is set on it (absent or "":
    /// left as the camera has it).
    pub genicam_id: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub genicam_exposure_us: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub genicam_gain_db: Option<f64>,
    #[serde(with = "wire::names::empty_is_none")]
    pub genicam_pixel_format: Option<PixelFormat>,
    /// x,y,w,h px on the sensor.
    #[serde(with = "wire::names::empty_is_none")]
    pub genicam_roi: Option<SensorRoi>,
    #[serde(with = "wire::names::empty_is_none")]
    pub genicam_trigger: Option<Trigger>,
}

/// `[rig.csv]`: the test machine's CSV log a `csv-follow` rig follows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CsvFollowSection {
    pub file: PathBuf,
    /// Column names as in the header, without their unit ("" = not logged).
    pub time_column: String,
    pub force_x_column: String,
    pub force_y_column: String,
    pub force_z_column: String,
    pub displacement_x_column: String,
    pub displacement_y_column: String,
    pub displacement_z_column: String,
    /// Units; absent or "" = as the header says (`Fx (kN)`).
    #[serde(with = "wire::names::empty_is_none")]
    pub time_unit: Option<TimeUnit>,
    #[serde(with = "wire::names::empty_is_none")]
    pub force_unit: Option<ForceUnit>,
    #[serde(with = "wire::names::empty_is_none")]
    pub displacement_unit: Option<LengthUnit>,
    pub delimiter: Delimiter,
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
            file: PathBuf::new(),
            time_column: String::new(),
            force_x_column: String::new(),
            force_y_column: String::new(),
            force_z_column: String::new(),
            displacement_x_column: String::new(),
            displacement_y_column: String::new(),
            displacement_z_column: String::new(),
            time_unit: None,
            force_unit: None,
            displacement_unit: None,
            delimiter: Delimiter::default(),
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
    pub method: Method,
    pub zoi_px: usize,
    pub step_px: usize,
    pub threads: usize,
    /// Strain measure of the node strains.
    pub strain: StrainMeasure,
    pub reference: ReferenceKind,
    /// Initial guess.
    pub guess: GuessMode,
    /// A node is ok only when its final ZNCC check reaches this.
    pub min_zncc: f64,
    /// First-order correction of the rigid ZOI's bias under a displacement gradient.
    pub gradient_correction: bool,
    /// Virtual strain gauges and extensometers, read on every field into `frames.csv`.
    pub gauges: Vec<correlator::Gauge>,
    /// The gauge the fields' header carries (strain control, the identifier's gauge route).
    pub control_gauge: correlator::ControlGauge,
    /// `[correlator.region]`: where the correlator measures (the rectangle, polygons, a mask).
    pub region: correlator::Region,
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
    pub source: RigSource,
    pub csv: CsvFollowSection,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TestSection {
    /// uniaxial or equibiaxial; under strain control also pure_shear or biaxial.
    pub kind: StrainKind,
    /// Displacement: the final grip stretch; strain: the target of the larger measured stretch.
    pub stretch: f64,
    /// Displacement: the stretch rate; strain: the rate of the larger log strain (/s).
    pub rate_per_s: f64,
    /// The grips follow the program (the default), or the correlator's fields close the loop
    /// on the gauge zone's log strains (a test alone in its run).
    #[serde(default, skip_serializing_if = "TestSection::is_displacement")]
    pub control: TestControl,
    /// Strain control, biaxial: ρ = ln λy / ln λx held along the path.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ratio: Option<f64>,
    /// Strain control: hold the grips when the newest field is older than this (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stale_s: Option<f64>,
    /// Strain control: hold on a field with fewer converged nodes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_valid_nodes: Option<u32>,
    /// Strain control, once fields are usable again after a hold: resume or stop [resume].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on_interlock: Option<OnRestore>,
}

impl TestSection {
    /// A test under displacement control.
    pub fn new(kind: StrainKind, stretch: f64, rate_per_s: f64) -> TestSection {
        TestSection {
            kind,
            stretch,
            rate_per_s,
            control: TestControl::Displacement,
            ratio: None,
            stale_s: None,
            min_valid_nodes: None,
            on_interlock: None,
        }
    }

    fn is_displacement(control: &TestControl) -> bool {
        *control == TestControl::Displacement
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpecimenSection {
    /// ln f(I1) = Σ a_i (I1 − 3)^i (eq. 22), f in MPa.
    pub law_f: Vec<f64>,
    /// ln g(I2) = Σ b_i (I2 − 3)^i (eq. 25), g in MPa.
    pub law_g: Vec<f64>,
    /// The rig's specimen: `structure` (the default: the finite-element cruciform and strip of
    /// `[specimen.geometry]`, the law judged from the whole field) or `homogeneous` (the
    /// analytic sheet, the law judged from the gauge's forces over sections).
    pub model: rig::SpecimenModel,
    /// The specimen as a structure (`[specimen.geometry]`): its shape and the geometry of each
    /// shape, meshed by `membrane` (`dicstream specimen` solves it).
    pub geometry: membrane::SpecimenChoice,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IdentifierSection {
    /// Models ranked at each refit, NAME[,NAME...] or all.
    #[serde(with = "wire::names::text")]
    pub models: ModelList,
    /// The identification routes: `gauge`, `field` (the whole field of the cruciform, by the
    /// virtual fields method), `both`, or `auto` (both on a structure, the gauge otherwise).
    pub route: wire::identification::IdentifierRoutes,
    /// f_I1.png and g_I2.png show every ranked model, not only the identified law.
    pub plot_all_models: bool,
}

impl CameraSection {
    /// How the simulated camera frames the specimen mounted.
    pub fn framing(&self) -> producer::Framing {
        producer::Framing {
            mm_per_px: self.mm_per_px,
            strip_mm_per_px: self.strip_mm_per_px,
        }
    }
}

impl RunConfig {
    /// Whether this host's run starts `process` (`[run] processes`).
    pub fn runs(&self, process: BenchProcess) -> bool {
        self.run.processes.contains(&process)
    }

    /// Whether the run is one host's part of a bench split between two (`[run] processes`
    /// not all four).
    pub fn is_split(&self) -> bool {
        BenchProcess::ALL.iter().any(|&p| !self.runs(p))
    }

    /// Whether `dicstream run` starts the link (`[link] start_with_run = true`).
    pub fn link_started_by_run(&self) -> bool {
        self.link.as_ref().is_some_and(|l| l.start_with_run)
    }

    /// The identifier's routes, `auto` resolved by the specimen's model.
    pub fn identifier_routes(&self) -> wire::identification::IdentifierRoutes {
        self.identifier
            .route
            .resolved(self.specimen.model == rig::SpecimenModel::Structure)
    }
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
            dashboard: DashboardListen::default(),
            map_range: wire::colour_range::RangeChoice::Auto,
            processes: BenchProcess::ALL.to_vec(),
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
            mm_per_px: producer::DEFAULT_MM_PER_PX,
            strip_mm_per_px: producer::DEFAULT_STRIP_MM_PER_PX,
            scale_mm_per_px: 0.0,
            scale_known_length: None,
            speckle_size_px: 4.0,
            seed: 1,
            threads: 1,
            source: CameraSource::Simulated,
            watch_dir: PathBuf::new(),
            watch_from_start: false,
            watch_idle_timeout_s: 0.0,
            watch_settle_ms: producer::DEFAULT_SETTLE_MS,
            replay_files: String::new(),
            genicam_id: String::new(),
            genicam_exposure_us: None,
            genicam_gain_db: None,
            genicam_pixel_format: None,
            genicam_roi: None,
            genicam_trigger: None,
        }
    }
}

/// The correlator's own defaults (`correlator::CorrelatorSettings::default()`), but for the
/// reference, renewed automatically on the live bench.
impl Default for CorrelatorSection {
    fn default() -> Self {
        let d = correlator::CorrelatorSettings::default();
        CorrelatorSection {
            method: d.method,
            zoi_px: d.zoi_px,
            step_px: d.step_px,
            threads: d.threads,
            strain: d.strain,
            reference: ReferenceKind::Auto,
            guess: d.guess,
            min_zncc: d.min_zncc,
            gradient_correction: d.gradient_correction,
            gauges: d.gauges,
            control_gauge: d.control_gauge,
            region: d.region,
        }
    }
}

impl Default for RigSection {
    fn default() -> Self {
        let tests = rig::Campaign::paper()
            .tests()
            .iter()
            .map(|t| TestSection::new(campaign::kind_of(t.test), t.stretch, t.rate_per_s))
            .collect();
        RigSection {
            speed: 1.0,
            publish_hz: 200.0,
            log_hz: 50.0,
            seed: 1,
            tests,
            source: RigSource::Simulated,
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
            model: rig::SpecimenModel::Structure,
            geometry: membrane::SpecimenChoice::default(),
        }
    }
}

impl Default for IdentifierSection {
    fn default() -> Self {
        IdentifierSection {
            models: identifier::models::ModelList(
                identifier::online::OnlineConfig::default().models,
            ),
            route: wire::identification::IdentifierRoutes::Auto,
            plot_all_models: false,
        }
    }
}

impl RunConfig {
    /// Parses a TOML file's text; errors name the file and the offending key or line.
    pub fn from_toml(text: &str, source: &str) -> anyhow::Result<RunConfig> {
        toml::from_str(text).map_err(|error| {
            let hint = error
                .span()
                .and_then(|span| wire::toml_hint::bare_word_hint(text, span.start));
            match hint {
                Some(hint) => {
                    anyhow::anyhow!("{source}: {}\n{hint}", error.to_string().trim_end())
                }
                None => anyhow::Error::new(error).context(source.to_string()),
            }
        })
    }

    /// The configuration of `--config FILE`, or the defaults without one.
    pub fn read(path: Option<&std::path::Path>) -> anyhow::Result<RunConfig> {
        use anyhow::Context as _;
        let Some(path) = path else {
            return Ok(RunConfig::default());
        };
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("--config {}", path.display()))?;
        RunConfig::from_toml(&text, &path.display().to_string())
    }

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("the run configuration serialises")
    }

    /// The field route's settings of this run: the camera's view and the cruciform filmed
    /// (the identifier's, and `identify --fields` on the run's results).
    pub fn field_route_settings(&self) -> identifier::process::FieldRouteSettings {
        use identifier::process::FieldRouteSettings;
        FieldRouteSettings {
            mm_per_px: self.camera.mm_per_px,
            width_px: self.camera.width_px,
            height_px: self.camera.height_px,
            cruciform: self.specimen.geometry.cruciform,
            min_level_increment: FieldRouteSettings::DEFAULT_LEVEL_INCREMENT,
            max_frames: FieldRouteSettings::DEFAULT_MAX_FRAMES,
        }
    }

    /// Largest stretch any test reaches: the camera's pattern must cover it.
    pub fn max_stretch(&self) -> f64 {
        self.rig.tests.iter().map(|t| t.stretch).fold(1.0, f64::max)
    }
}
