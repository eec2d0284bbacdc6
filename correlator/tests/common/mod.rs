//! Test images from the producer crate (speckle with exact ground truth), and small helpers.
#![allow(dead_code)]

use producer::motion::Affine;
use producer::Motion;

/// Renders a speckle (default producer parameters, seed 1) covering the image plus `margin_px`,
/// moved by `motion`, exposed by a 16-bit camera with Gaussian read noise `noise` (fraction of
/// full scale, no shot noise) and noise seed `seed`.
pub fn render(
    width: usize,
    height: usize,
    margin_px: f64,
    motion: Motion,
    noise: f64,
    seed: u64,
) -> Vec<u16> {
    producer::exact_test_frame(width, height, margin_px, &motion, noise, seed)
}

pub fn translation(u_px: f64, v_px: f64) -> Motion {
    Motion::Affine(Affine {
        translation_px: [u_px, v_px],
        ..Affine::IDENTITY
    })
}

pub fn rotation_deg(deg: f64, centre_px: [f64; 2]) -> Motion {
    let (s, c) = deg.to_radians().sin_cos();
    Motion::Affine(Affine {
        f: [[c, -s], [s, c]],
        translation_px: [0.0, 0.0],
        centre_px,
    })
}

pub fn stretch(ex: f64, ey: f64, centre_px: [f64; 2]) -> Motion {
    Motion::Affine(Affine {
        f: [[1.0 + ex, 0.0], [0.0, 1.0 + ey]],
        translation_px: [0.0, 0.0],
        centre_px,
    })
}

/// Folder of the shared data, or None (with a visible message) when absent.
pub fn shared_data() -> Option<std::path::PathBuf> {
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data"));
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("SKIPPED: shared data folder {} is absent", dir.display());
        None
    }
}

pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}
