//! What the simulated camera costs filming the finite-element cruciform, as a default run's
//! camera films it: the default `[camera]` and `[specimen.geometry]` (the camera's framing,
//! pattern, noise, bit depth and threads; its texture over the campaign's reach), at the
//! bench's frame size. The cruciform is solved once at an equibiaxial grip stretch of
//! [`GRIP_STRETCH`] with the run's law, and each frame films a new state of that field, its
//! displacements scaled from a tenth to the whole (a ramp; a new `FieldMotion` per frame, as
//! the live camera builds one per rig sample), rendered and exposed into a frame buffer. The
//! process's CPU time over the frames gives the camera's share of a core at the run's rate.
//! The trials of `bench pipeline` film the homogeneous sheet; this is the figure of the run a
//! user starts.

use crate::config::RunConfig;
use anyhow::Context;
use serde::Serialize;

/// The cruciform's equibiaxial grip stretch filmed (its fillets' strain concentrations and
/// the room between the arms in view).
pub const GRIP_STRETCH: f64 = 1.3;

/// The camera's cost on the cruciform.
#[derive(Clone, Debug, Serialize)]
pub struct CameraCost {
    pub width_px: u32,
    pub height_px: u32,
    pub mm_per_px: f64,
    pub grip_stretch: f64,
    pub frames: usize,
    /// CPU time per frame (rendering and exposure), ms.
    pub cpu_ms_per_frame: f64,
    /// The default run's frame rate, and the camera's share of one core at it.
    pub fps: f64,
    pub cores: f64,
}

/// Films `frames` frames of the default cruciform at `width_px` × `height_px`.
pub fn on_cruciform(width_px: u32, height_px: u32, frames: usize) -> anyhow::Result<CameraCost> {
    let mut config = RunConfig::default();
    config.camera.width_px = width_px;
    config.camera.height_px = height_px;
    let (camera, follow) = crate::run::child_launch::rig_camera(&config);
    let reach_px = producer::RigFollower::new(follow, width_px, height_px)?.reach_px();
    let mut camera = producer::SimulatedCamera::for_reach(camera, reach_px)?;
    let specimen = config
        .specimen
        .geometry
        .cruciform
        .mesh()
        .context("the default cruciform")?;
    let law = config.law()?;
    let stretch = membrane::GripStretch {
        x: GRIP_STRETCH,
        y: GRIP_STRETCH,
    };
    let solved = specimen
        .solve_at(&law, stretch)
        .context("the default cruciform at the bench's grip stretch")?;
    let framing = config.camera.framing();
    let view = framing.view(specimen.grips.len(), width_px, height_px);
    let reference = producer::ReferenceMesh::new(specimen.mesh.clone());
    let mut frame = vec![0u16; width_px as usize * height_px as usize];
    let mut film = |k: usize| -> anyhow::Result<()> {
        let scale = 0.1 + 0.9 * k as f64 / frames.max(1) as f64;
        let u = solved.displacement_mm.iter().map(|u| u * scale).collect();
        let field = producer::FieldMotion::new(reference.clone(), u, view)?;
        camera.render_field_frame(&field, k as u64, &mut frame)?;
        Ok(())
    };
    // One frame first: the texture and the frame buffer in memory.
    film(0)?;
    let started = crate::children::own_cpu_s();
    for k in 1..=frames {
        film(k)?;
    }
    let cpu_ms_per_frame = (crate::children::own_cpu_s() - started) * 1e3 / frames.max(1) as f64;
    Ok(CameraCost {
        width_px,
        height_px,
        mm_per_px: view.mm_per_px,
        grip_stretch: GRIP_STRETCH,
        frames,
        cpu_ms_per_frame,
        fps: config.camera.fps,
        cores: cpu_ms_per_frame * config.camera.fps / 1e3,
    })
}
