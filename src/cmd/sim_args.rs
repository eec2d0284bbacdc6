//! The command-line options of the simulated camera, shared by `dicstream synth` and
//! `dicstream producer` (`#[command(flatten)]`), turned into the producer's settings.

use super::named_arg::named;
use producer::{
    check_frame_size, CameraModel, ProducerError, RendererKind, Scenario, ScenarioTimeline,
    SimulatedCamera, SimulatedConfig, SpeckleParams,
};

/// Scenario, pattern and camera options.
#[derive(Clone, Debug, clap::Args)]
pub struct SimArgs {
    /// Scenario NAME or NAME:key=value,...; names: static, translation, rotation, gradient,
    /// uniaxial, equibiaxial, chirp, bulge, bad-positioning
    #[arg(long, default_value = "rotation")]
    pub scenario: String,
    /// Extra scenario parameter, KEY=VALUE (repeatable), e.g. --param angle_deg=5
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Frame width, px
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    /// Frame height, px
    #[arg(long, default_value_t = 1024)]
    pub height: u32,
    /// Seed of the speckle pattern and of the noise
    #[arg(long, default_value_t = SpeckleParams::default().seed)]
    pub seed: u64,
    /// Speckle size (spot FWHM), px
    #[arg(long, default_value_t = SpeckleParams::default().size_px)]
    pub speckle_size_px: f64,
    /// Speckle density (spots per spot area)
    #[arg(long, default_value_t = SpeckleParams::default().density)]
    pub speckle_density: f64,
    /// Speckle contrast in (0, 1]
    #[arg(long, default_value_t = SpeckleParams::default().contrast)]
    pub contrast: f64,
    /// Camera bit depth: 8, 10, 12 or 16
    #[arg(long, default_value_t = SimulatedConfig::new(1, 1).camera.bit_depth)]
    pub bit_depth: u8,
    /// Read noise standard deviation, DN [default: 0.2 % of full scale]
    #[arg(long = "noise", alias = "read-noise-dn")]
    pub read_noise_dn: Option<f64>,
    /// Turn photon (shot) noise off
    #[arg(long)]
    pub no_shot_noise: bool,
    /// Photo-electrons at pattern value 1
    #[arg(long, default_value_t = CameraModel::with_bit_depth(8).illumination_e)]
    pub illumination_e: f64,
    /// Gain, DN per electron [default: white at 90 % of full scale]
    #[arg(long)]
    pub gain_dn_per_e: Option<f64>,
    /// Black level, DN [default: 5 % of full scale]
    #[arg(long)]
    pub offset_dn: Option<f64>,
    /// Gaussian blur sigma of the optics, px (0: none)
    #[arg(long, default_value_t = 0.0)]
    pub blur_px: f64,
    /// Renderer: fast (oversampled texture + bicubic, live) or exact (analytic pattern + pixel
    /// integration: ground truth, slow)
    #[arg(long, value_parser = named::<RendererKind>(), default_value_t = RendererKind::Fast)]
    pub renderer: RendererKind,
    /// Texels per px of the fast renderer (2, 4, 6, 8)
    #[arg(long, default_value_t = SimulatedConfig::new(1, 1).oversample)]
    pub oversample: usize,
    /// Rendering threads [default: all cores]
    #[arg(long)]
    pub threads: Option<usize>,
}

impl SimArgs {
    /// The scenario spec with the `--param` pairs appended.
    pub fn scenario_spec(&self) -> String {
        let mut spec = self.scenario.clone();
        for (k, param) in self.params.iter().enumerate() {
            spec.push(if k == 0 && !self.scenario.contains(':') {
                ':'
            } else {
                ','
            });
            spec.push_str(param);
        }
        spec
    }

    /// The parsed scenario (for a frame size within the limits).
    pub fn scenario(&self) -> Result<Scenario, ProducerError> {
        check_frame_size(self.width, self.height)?;
        Scenario::parse(&self.scenario_spec(), self.width, self.height)
    }

    /// The camera configuration.
    pub fn config(&self) -> Result<SimulatedConfig, ProducerError> {
        let mut config = SimulatedConfig::new(self.width, self.height);
        config.speckle = SpeckleParams {
            size_px: self.speckle_size_px,
            density: self.speckle_density,
            contrast: self.contrast,
            seed: self.seed,
        };
        CameraModel {
            bit_depth: self.bit_depth,
            ..CameraModel::with_bit_depth(8)
        }
        .validate()?;
        let mut camera = CameraModel::with_bit_depth(self.bit_depth);
        camera.illumination_e = self.illumination_e;
        camera.gain_dn_per_e = self
            .gain_dn_per_e
            .unwrap_or(0.85 * f64::from(camera.max_dn()) / self.illumination_e);
        if let Some(offset) = self.offset_dn {
            camera.offset_dn = offset;
        }
        if let Some(noise) = self.read_noise_dn {
            camera.read_noise_dn = noise;
        }
        camera.shot_noise = !self.no_shot_noise;
        camera.blur_sigma_px = self.blur_px;
        camera.seed = self.seed;
        camera.validate()?;
        config.camera = camera;
        config.renderer = self.renderer;
        config.oversample = self.oversample;
        if let Some(threads) = self.threads {
            config.threads = threads.max(1);
        }
        Ok(config)
    }

    /// A simulated camera playing the scenario over `frames` frames.
    pub fn build(&self, frames: u64) -> Result<SimulatedCamera, ProducerError> {
        self.scenario()?;
        scenario_camera(&self.config()?, &self.scenario_spec(), frames)
    }
}

/// A simulated camera of `config` playing the scenario `spec` (`NAME` or `NAME:key=value,...`)
/// over `frames` frames.
pub fn scenario_camera(
    config: &SimulatedConfig,
    spec: &str,
    frames: u64,
) -> Result<SimulatedCamera, ProducerError> {
    if frames == 0 {
        return Err(ProducerError::InvalidParameter {
            name: "frames".to_owned(),
            value: "0".to_owned(),
            expected: "at least 1 frame".to_owned(),
        });
    }
    check_frame_size(config.width, config.height)?;
    let timeline = ScenarioTimeline {
        scenario: Scenario::parse(spec, config.width, config.height)?,
        frames,
    };
    SimulatedCamera::new(*config, Box::new(timeline))
}
