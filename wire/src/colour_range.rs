//! The range of a field figure's colour map: automatic (the values' 2nd to 98th percentile,
//! never narrower than a floor tied to the field's own measured noise, so that a uniform noisy
//! field shows one colour and a real gradient still spans the map), symmetric about zero, or
//! fixed by the user (`auto`, `symmetric`, `LO:HI`: `correlate --range`, `[run] map_range`).
//! The map follows the quantity: signed (u, v, strains) and straddling zero, the diverging map
//! centred on zero; otherwise viridis ([`crate::colour_map`]).

use crate::colour_map::{ColourMap, ColourScale};
use std::fmt;
use std::str::FromStr;

/// How a figure's colour range is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum RangeChoice {
    /// The 2nd to 98th percentile of the valid values, widened about its middle to
    /// [`NOISE_FLOOR_SIGMAS`] times the field's noise; symmetric about zero when a signed
    /// quantity's range straddles it.
    #[default]
    Auto,
    /// ± the larger of |2nd percentile| and |98th percentile| (and half the noise floor),
    /// diverging map.
    Symmetric,
    /// From `low` to `high`, values beyond at the colour of the end they pass.
    Fixed { low: f64, high: f64 },
}

/// The automatic range's floor, in standard deviations of the field's noise: white noise
/// stays within about ±3σ (±4σ over thousands of nodes), so on a range 30σ wide it moves the
/// colour by 0.1 of the map (0.13) each way from the middle, which reads as one colour.
pub const NOISE_FLOOR_SIGMAS: f64 = 30.0;

/// Fewer second differences than this, no noise estimate (no floor).
const MIN_DIFFERENCES: usize = 8;

/// A bad `--range`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("colour range {given:?}: {why} (expected auto, symmetric or LO:HI with LO < HI, e.g. -0.01:0.01)")]
pub struct RangeError {
    pub given: String,
    pub why: String,
}

impl FromStr for RangeChoice {
    type Err = RangeError;
    fn from_str(text: &str) -> Result<Self, RangeError> {
        let text = text.trim();
        let refuse = |why: String| RangeError {
            given: text.to_string(),
            why,
        };
        match text {
            "auto" => return Ok(RangeChoice::Auto),
            "symmetric" => return Ok(RangeChoice::Symmetric),
            _ => {}
        }
        let Some((lo, hi)) = text.split_once(':') else {
            return Err(refuse("neither a word nor LO:HI".into()));
        };
        let number = |s: &str, what: &str| -> Result<f64, RangeError> {
            let v: f64 = s
                .trim()
                .parse()
                .map_err(|_| refuse(format!("{what} {:?} is not a number", s.trim())))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(refuse(format!("{what} {v} is not finite")))
            }
        };
        let (low, high) = (number(lo, "LO")?, number(hi, "HI")?);
        if low >= high {
            return Err(refuse(format!("LO {low} is not below HI {high}")));
        }
        Ok(RangeChoice::Fixed { low, high })
    }
}

impl fmt::Display for RangeChoice {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            RangeChoice::Auto => f.write_str("auto"),
            RangeChoice::Symmetric => f.write_str("symmetric"),
            RangeChoice::Fixed { low, high } => write!(f, "{low}:{high}"),
        }
    }
}

/// A node grid's values, row-major `nx` by `ny`, `None` (or NaN) where nothing was measured.
#[derive(Clone, Copy, Debug)]
pub struct NodeGrid<'a> {
    pub values: &'a [Option<f64>],
    pub nx: usize,
    pub ny: usize,
}

impl NodeGrid<'_> {
    fn at(&self, i: usize, j: usize) -> Option<f64> {
        self.values
            .get(j * self.nx + i)
            .copied()
            .flatten()
            .filter(|v| v.is_finite())
    }
}

/// The standard deviation of the grid's noise, from the second differences along rows and
/// columns at `lag_nodes` (d = v − (v₋ + v₊)/2: zero on any linear field, σ √1.5 on white
/// noise), robustly (1.4826 × their median absolute deviation, so edges and a few outliers
/// do not count). `lag_nodes` past the values' own correlation: 1 for displacements, more
/// for strains averaged over a window of nodes. None with fewer than 8 differences.
pub fn noise_sigma(grid: NodeGrid, lag_nodes: usize) -> Option<f64> {
    let lag = lag_nodes.max(1);
    let mut d = Vec::new();
    for j in 0..grid.ny {
        for i in 0..grid.nx {
            let Some(v) = grid.at(i, j) else { continue };
            if i >= lag && i + lag < grid.nx {
                if let (Some(a), Some(b)) = (grid.at(i - lag, j), grid.at(i + lag, j)) {
                    d.push(v - 0.5 * (a + b));
                }
            }
            if j >= lag && j + lag < grid.ny {
                if let (Some(a), Some(b)) = (grid.at(i, j - lag), grid.at(i, j + lag)) {
                    d.push(v - 0.5 * (a + b));
                }
            }
        }
    }
    if d.len() < MIN_DIFFERENCES {
        return None;
    }
    let median = |x: &mut Vec<f64>| {
        x.sort_by(f64::total_cmp);
        x[x.len() / 2]
    };
    let centre = median(&mut d);
    let mut deviations: Vec<f64> = d.iter().map(|x| (x - centre).abs()).collect();
    Some(1.4826 * median(&mut deviations) / 1.5f64.sqrt())
}

/// The lag, in nodes, past which a field's strains are uncorrelated (their least-squares
/// window, `strain_window_nodes` each way, shares no node): [`noise_sigma`]'s for strains.
pub fn strain_noise_lag_nodes(strain_window_nodes: usize) -> usize {
    2 * strain_window_nodes + 1
}

/// The colour scale of `grid` under `choice`; `signed`: the quantity has a sign that means
/// something (u, v, a strain), so a range across zero takes the diverging map centred on it.
/// `lag_nodes`: as [`noise_sigma`]'s.
pub fn choose(grid: NodeGrid, lag_nodes: usize, signed: bool, choice: RangeChoice) -> ColourScale {
    let mut valid: Vec<f64> = grid
        .values
        .iter()
        .flatten()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    valid.sort_by(f64::total_cmp);
    let quantile = |q: f64| valid[((valid.len() - 1) as f64 * q).round() as usize];
    let (p2, p98) = if valid.is_empty() {
        (0.0, 0.0)
    } else {
        (quantile(0.02), quantile(0.98))
    };
    let floor = match choice {
        RangeChoice::Fixed { .. } => 0.0,
        _ => noise_sigma(grid, lag_nodes).map_or(0.0, |s| NOISE_FLOOR_SIGMAS * s),
    };
    let scale = match choice {
        RangeChoice::Fixed { low, high } => ColourScale {
            map: diverging_if(signed && low < 0.0 && high > 0.0),
            low,
            high,
        },
        RangeChoice::Symmetric => {
            let reach = p2.abs().max(p98.abs()).max(floor / 2.0);
            ColourScale {
                map: ColourMap::Diverging,
                low: -reach,
                high: reach,
            }
        }
        RangeChoice::Auto => {
            let widen = (floor - (p98 - p2)).max(0.0) / 2.0;
            let (low, high) = (p2 - widen, p98 + widen);
            if signed && low < 0.0 && high > 0.0 {
                let reach = low.abs().max(high.abs());
                ColourScale {
                    map: ColourMap::Diverging,
                    low: -reach,
                    high: reach,
                }
            } else {
                ColourScale {
                    map: ColourMap::Viridis,
                    low,
                    high,
                }
            }
        }
    };
    not_empty(scale)
}

fn diverging_if(diverging: bool) -> ColourMap {
    if diverging {
        ColourMap::Diverging
    } else {
        ColourMap::Viridis
    }
}

/// A range of no width (a noise-free uniform field, no value at all) widened a hair about
/// its value, so that its one colour is the map's middle and the bar has two distinct ends.
fn not_empty(scale: ColourScale) -> ColourScale {
    if scale.high > scale.low {
        return scale;
    }
    let middle = 0.5 * (scale.low + scale.high);
    let half = (middle.abs() * 1e-6).max(1e-12);
    ColourScale {
        low: middle - half,
        high: middle + half,
        ..scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Standard normal deviates, deterministic (xorshift, Box-Muller).
    fn gaussian(count: usize, mut seed: u64) -> Vec<f64> {
        let mut uniform = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            ((seed >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        (0..count)
            .map(|_| {
                let (a, b) = (uniform(), uniform());
                (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
            })
            .collect()
    }

    const N: usize = 40;

    fn field(value: impl Fn(usize, usize) -> f64) -> Vec<Option<f64>> {
        (0..N * N).map(|k| Some(value(k % N, k / N))).collect()
    }

    fn grid(values: &[Option<f64>]) -> NodeGrid<'_> {
        NodeGrid {
            values,
            nx: N,
            ny: N,
        }
    }

    #[test]
    fn the_noise_is_measured_and_a_gradient_is_not_noise() {
        let noise = gaussian(N * N, 7);
        let sigma = 2e-4;
        let noisy = field(|i, j| 0.01 + sigma * noise[j * N + i]);
        let measured = noise_sigma(grid(&noisy), 1).unwrap();
        assert!((measured / sigma - 1.0).abs() < 0.15, "{measured}");
        // The same noise on a steep linear gradient: the same estimate.
        let sloped = field(|i, j| 0.05 * i as f64 - 0.02 * j as f64 + sigma * noise[j * N + i]);
        let on_slope = noise_sigma(grid(&sloped), 3).unwrap();
        assert!((on_slope / sigma - 1.0).abs() < 0.2, "{on_slope}");
        assert_eq!(noise_sigma(grid(&vec![None; N * N]), 1), None);
    }

    #[test]
    fn a_uniform_noisy_field_shows_one_colour() {
        let noise = gaussian(N * N, 11);
        for (offset, signed) in [(0.4791, false), (0.0, true), (0.012, true)] {
            let values = field(|i, j| offset + 3e-4 * noise[j * N + i]);
            let scale = choose(grid(&values), 1, signed, RangeChoice::Auto);
            assert!(scale.high - scale.low >= 0.8 * NOISE_FLOOR_SIGMAS * 3e-4);
            let middle = scale.t(offset);
            for v in values.iter().flatten() {
                assert!(
                    (scale.t(*v) - middle).abs() < 0.15,
                    "{v} on {scale:?} (offset {offset})"
                );
            }
        }
        // About zero, a signed quantity is drawn on the diverging map, near its white.
        let values = field(|i, j| 3e-4 * noise[j * N + i]);
        let scale = choose(grid(&values), 1, true, RangeChoice::Auto);
        assert_eq!(scale.map, ColourMap::Diverging);
        assert_eq!(scale.low, -scale.high);
    }

    #[test]
    fn a_real_gradient_spans_the_map() {
        let noise = gaussian(N * N, 3);
        let values = field(|i, j| 1.0 + 0.01 * i as f64 + 1e-4 * noise[j * N + i]);
        let scale = choose(grid(&values), 1, false, RangeChoice::Auto);
        assert_eq!(scale.map, ColourMap::Viridis);
        assert!(scale.t(1.0) < 0.05 && scale.t(1.0 + 0.01 * (N - 1) as f64) > 0.95);
        // Signed and across zero: diverging, symmetric, both ends reached.
        let values = field(|i, j| -0.195 + 0.01 * i as f64 + 1e-4 * noise[j * N + i]);
        let scale = choose(grid(&values), 1, true, RangeChoice::Auto);
        assert_eq!(scale.map, ColourMap::Diverging);
        assert_eq!(scale.low, -scale.high);
        assert!(scale.t(-0.195) < 0.05 && scale.t(0.195) > 0.95, "{scale:?}");
    }

    #[test]
    fn fixed_and_symmetric_ranges_are_obeyed() {
        let values = field(|i, _| 0.01 * i as f64 - 0.1);
        let fixed: RangeChoice = "-0.05:0.2".parse().unwrap();
        let scale = choose(grid(&values), 1, true, fixed);
        assert_eq!((scale.low, scale.high), (-0.05, 0.2));
        assert_eq!(scale.map, ColourMap::Diverging);
        assert_eq!(scale.t(0.0), 0.5);
        let positive = choose(grid(&values), 1, true, "0.1:0.2".parse().unwrap());
        assert_eq!(positive.map, ColourMap::Viridis);
        let symmetric = choose(grid(&values), 1, false, RangeChoice::Symmetric);
        assert_eq!(symmetric.map, ColourMap::Diverging);
        let reach = 0.01 * (N - 1) as f64 - 0.1;
        assert!((symmetric.high - reach).abs() < 1e-12, "{symmetric:?}");
        assert_eq!(symmetric.low, -symmetric.high);
        // Nothing measured, or a noise-free uniform field: one middle colour, a range all the same.
        let flat = field(|_, _| 0.25);
        let scale = choose(grid(&flat), 1, false, RangeChoice::Auto);
        assert!(scale.high > scale.low && (scale.t(0.25) - 0.5).abs() < 1e-6);
        let none = vec![None; N * N];
        let scale = choose(grid(&none), 1, true, RangeChoice::Auto);
        assert!(scale.high > scale.low);
    }

    #[test]
    fn ranges_are_read_and_bad_ones_refused() {
        assert_eq!("auto".parse::<RangeChoice>(), Ok(RangeChoice::Auto));
        assert_eq!(" symmetric".parse(), Ok(RangeChoice::Symmetric));
        assert_eq!(
            "-1e-3:2e-3".parse(),
            Ok(RangeChoice::Fixed {
                low: -1e-3,
                high: 2e-3
            })
        );
        let fixed = RangeChoice::Fixed {
            low: -0.5,
            high: 1.0,
        };
        assert_eq!(fixed.to_string().parse(), Ok(fixed));
        for (bad, why) in [
            ("0.2:0.1", "is not below"),
            ("0.1:0.1", "is not below"),
            ("NaN:1", "not finite"),
            ("0:inf", "not finite"),
            ("a:1", "not a number"),
            ("wide", "neither a word nor LO:HI"),
        ] {
            let e = bad.parse::<RangeChoice>().unwrap_err();
            let message = e.to_string();
            assert!(message.contains(why), "{bad}: {message}");
            assert!(message.contains("expected auto, symmetric or LO:HI"));
        }
    }
}
