//! Test images from the producer crate (speckle with exact ground truth), and small helpers.
#![allow(dead_code)]

pub mod independent;

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

/// An image file as (pixels, width, height); panics naming the file when it cannot be read.
pub fn load(path: std::path::PathBuf) -> (Vec<u16>, usize, usize) {
    let image = producer::read_image(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (image.pixels, image.width as usize, image.height as usize)
}

/// The rows of a DIC Challenge `command.csv` (one per pixel column), NaN where a value does
/// not parse.
pub fn command_columns(path: std::path::PathBuf) -> Vec<Vec<f64>> {
    let command =
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    command
        .lines()
        .map(|line| {
            line.split(',')
                .map(|v| v.trim().parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// `values` (one per pixel column) linearly interpolated at x (px).
pub fn linear(values: &[f64], x: f64) -> f64 {
    let i = (x.floor() as usize).min(values.len() - 2);
    let t = x - i as f64;
    values[i] * (1.0 - t) + values[i + 1] * t
}

pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

/// An `ok` node further than this from the truth is a false `ok`.
pub const FALSE_OK_PX: f64 = 0.5;

/// A field against the exact motion.
#[derive(Debug)]
pub struct Accuracy {
    /// Nodes whose deformed ZOI lies in the image, and how many of them are `ok`.
    pub candidates: usize,
    pub ok_candidates: usize,
    /// `ok` nodes in all, their RMS and largest error (px), and how many are > 0.5 px off.
    pub ok: usize,
    pub rms_px: f64,
    pub worst_px: f64,
    pub false_ok: usize,
}

impl Accuracy {
    pub fn valid_fraction(&self) -> f64 {
        self.ok_candidates as f64 / self.candidates.max(1) as f64
    }

    /// One line of the table: case, valid fraction, RMS, worst `ok` node, false `ok` count.
    pub fn print(&self, case: &str) {
        println!(
            "| {case:<34} | {:>5.1} % ({}/{}) | {:.4} px | {:.3} px | {} |",
            100.0 * self.valid_fraction(),
            self.ok_candidates,
            self.candidates,
            self.rms_px,
            self.worst_px,
            self.false_ok
        );
    }
}

/// Compares a field with the exact motion `forward` (reference point to deformed point): node
/// errors, and which nodes could be measured at all (the four corners of their ZOI, moved by
/// the motion, inside the `size` image).
pub fn accuracy(
    field: &correlator::Field,
    zoi_px: usize,
    size: (usize, usize),
    forward: impl Fn([f64; 2]) -> [f64; 2],
) -> Accuracy {
    let half = (zoi_px as f64 - 1.0) / 2.0;
    let inside = |p: [f64; 2]| {
        p[0] >= 0.0 && p[1] >= 0.0 && p[0] <= size.0 as f64 - 1.0 && p[1] <= size.1 as f64 - 1.0
    };
    let (mut candidates, mut ok_candidates, mut ok, mut false_ok) = (0, 0, 0, 0);
    let (mut sum_sq, mut worst) = (0.0, 0.0f64);
    for node in &field.nodes {
        let corners = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];
        let candidate = corners
            .iter()
            .all(|(sx, sy)| inside(forward([node.x_px + sx * half, node.y_px + sy * half])));
        candidates += usize::from(candidate);
        if node.status != correlator::NodeStatus::Ok {
            continue;
        }
        ok += 1;
        ok_candidates += usize::from(candidate);
        let x = forward([node.x_px, node.y_px]);
        let error = (node.u_px - (x[0] - node.x_px)).hypot(node.v_px - (x[1] - node.y_px));
        sum_sq += error * error;
        worst = worst.max(error);
        false_ok += usize::from(error > FALSE_OK_PX);
    }
    Accuracy {
        candidates,
        ok_candidates,
        ok,
        rms_px: if ok > 0 {
            (sum_sq / ok as f64).sqrt()
        } else {
            f64::NAN
        },
        worst_px: worst,
        false_ok,
    }
}

/// The Cramér-Rao bound of the displacement of one subset under a translation, with white
/// noise of standard deviation `sigma_counts` in both images: var(u) >= 2 σ² / Σ (∂f/∂x)² and
/// var(v) >= 2 σ² / Σ (∂f/∂y)² over the subset of side `zoi_px` centred on each node (∂f of
/// the noise-free reference `clean`, fourth-order central differences). Returns the bound of
/// the standard deviation of u and of v, each the root of the mean bound variance over the
/// nodes whose subset lies 2 px inside the image.
pub fn cramer_rao_std_px(
    clean: &[u16],
    width: usize,
    height: usize,
    field: &correlator::Field,
    zoi_px: usize,
    sigma_counts: f64,
) -> (f64, f64) {
    let at = |x: usize, y: usize| clean[y * width + x] as f64;
    let derivative = |a: [f64; 4]| (a[0] - 8.0 * a[1] + 8.0 * a[2] - a[3]) / 12.0;
    let half = (zoi_px as f64 - 1.0) / 2.0;
    let (mut var_u, mut var_v, mut count) = (0.0, 0.0, 0usize);
    for node in &field.nodes {
        let (x0, y0) = (node.x_px - half, node.y_px - half);
        if x0 < 2.0 || y0 < 2.0 || x0 + zoi_px as f64 + 2.0 > width as f64 {
            continue;
        }
        if y0 + zoi_px as f64 + 2.0 > height as f64 {
            continue;
        }
        let (x0, y0) = (x0 as usize, y0 as usize);
        let (mut sxx, mut syy) = (0.0, 0.0);
        for y in y0..y0 + zoi_px {
            for x in x0..x0 + zoi_px {
                let fx = derivative([at(x - 2, y), at(x - 1, y), at(x + 1, y), at(x + 2, y)]);
                let fy = derivative([at(x, y - 2), at(x, y - 1), at(x, y + 1), at(x, y + 2)]);
                sxx += fx * fx;
                syy += fy * fy;
            }
        }
        var_u += 2.0 * sigma_counts * sigma_counts / sxx;
        var_v += 2.0 * sigma_counts * sigma_counts / syy;
        count += 1;
    }
    let n = count.max(1) as f64;
    ((var_u / n).sqrt(), (var_v / n).sqrt())
}
