//! The strain map's colour ranges, resolved here rather than on the page: for each component
//! (exx, eyy, exy) of the field as sent (decimated), in the field's own measure and in every
//! Seth-Hill measure computed from it (`stretch_states::convert_strain`, the conversion the
//! page applies to the node values it draws), the automatic and the symmetric range by
//! `wire::colour_range::choose` (the figures' own: a floor of `NOISE_FLOOR_SIGMAS` times the
//! map's measured noise; strains are signed). A fixed range is the user's two numbers on the
//! page. JSON: `{MEASURE: {COMPONENT: {"auto": SCALE, "symmetric": SCALE}}}`, a scale being
//! `{"map": "viridis" | "diverging", "lo", "hi"}`.

use crate::stretch_states::convert_strain;
use serde_json::{json, Map, Value};
use wire::colour_range::{choose, strain_noise_lag_nodes, NodeGrid, RangeChoice};
use wire::StrainMeasure;

/// The components' names, in the order of a strain `[exx, eyy, exy]`.
pub const COMPONENTS: [&str; 3] = ["exx", "eyy", "exy"];

/// The field's strains as sent: `nx` by `ny` nodes, row-major, None where a node has none.
pub struct SentStrains<'a> {
    pub strains: &'a [Option<[f64; 3]>],
    pub nx: usize,
    pub ny: usize,
    /// Mesh nodes per sent node along a side (the field's decimation).
    pub stride: usize,
    pub measure: StrainMeasure,
}

/// The measures the page can show a field measured in `measure`: its own, and the Seth-Hill
/// measures computed from it (none from small strain, which carries no rotation).
pub fn shown_measures(measure: StrainMeasure) -> Vec<StrainMeasure> {
    match measure {
        StrainMeasure::Small => vec![StrainMeasure::Small],
        _ => vec![
            StrainMeasure::Log,
            StrainMeasure::Green,
            StrainMeasure::Nominal,
        ],
    }
}

/// The ranges of every quantity the page can show (see the module's JSON).
pub fn json(sent: &SentStrains) -> Value {
    // The live correlator's strains share a window of 1 node each way: uncorrelated past
    // `strain_noise_lag_nodes(1)` mesh nodes, fewer sent nodes when decimated.
    let lag_nodes = strain_noise_lag_nodes(1).div_ceil(sent.stride.max(1));
    let mut measures = Map::new();
    let mut values: Vec<Option<f64>> = Vec::with_capacity(sent.strains.len());
    for to in shown_measures(sent.measure) {
        let converted: Vec<Option<[f64; 3]>> = sent
            .strains
            .iter()
            .map(|e| e.and_then(|e| convert_strain(e, sent.measure, to)))
            .collect();
        let mut components = Map::new();
        for (k, name) in COMPONENTS.iter().enumerate() {
            values.clear();
            values.extend(converted.iter().map(|e| e.map(|e| e[k])));
            let grid = NodeGrid {
                values: &values,
                nx: sent.nx,
                ny: sent.ny,
            };
            let scale = |choice: RangeChoice| {
                let s = choose(grid, lag_nodes, true, choice);
                json!({"map": s.map, "lo": s.low, "hi": s.high})
            };
            components.insert(
                name.to_string(),
                json!({"auto": scale(RangeChoice::Auto), "symmetric": scale(RangeChoice::Symmetric)}),
            );
        }
        measures.insert(to.name().to_string(), Value::Object(components));
    }
    Value::Object(measures)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A uniform noisy field (a rainbow of noise on a percentile range) shows one colour; a
    /// real gradient spans the map; each measure's range is its own values'.
    #[test]
    fn every_shown_quantity_gets_the_figures_range() {
        let (nx, ny) = (30, 20);
        // Deterministic pseudo-noise of ±2e-5 on a uniform 0.479 log strain along x.
        let noise = |k: usize| 2e-5 * (((k * 7919) % 101) as f64 / 50.0 - 1.0);
        let strains: Vec<Option<[f64; 3]>> = (0..nx * ny)
            .map(|k| Some([0.479 + noise(k), -0.2 + 1e-3 * (k % nx) as f64, 0.0]))
            .collect();
        let sent = SentStrains {
            strains: &strains,
            nx,
            ny,
            stride: 1,
            measure: StrainMeasure::Log,
        };
        let ranges = json(&sent);
        let scale = |m: &str, c: &str, mode: &str| {
            let s = &ranges[m][c][mode];
            let (lo, hi) = (s["lo"].as_f64().unwrap(), s["hi"].as_f64().unwrap());
            (s["map"].as_str().unwrap().to_string(), lo, hi)
        };
        // exx, uniform: wide enough that the noise stays near the middle colour.
        let (map, lo, hi) = scale("log", "exx", "auto");
        assert_eq!(map, "viridis");
        // (A percentile range would be the noise's own 4e-5 wide: the floor widens it.)
        assert!(
            hi - lo > 3.0 * 4e-5 && lo < 0.479 && hi > 0.479,
            "{lo} {hi}"
        );
        // eyy, a gradient from -0.2 to -0.171: spans the map.
        let (_, lo, hi) = scale("log", "eyy", "auto");
        assert!(
            (lo + 0.2).abs() < 2e-3 && (hi + 0.171).abs() < 2e-3,
            "{lo} {hi}"
        );
        // Symmetric: diverging about zero.
        let (map, lo, hi) = scale("log", "eyy", "symmetric");
        assert_eq!(map, "diverging");
        assert_eq!(lo, -hi);
        // Green-Lagrange of exx: (e^(2 × 0.479) − 1) / 2 about 0.802, its own range.
        let (_, lo, hi) = scale("green", "exx", "auto");
        let green = 0.5 * ((2.0f64 * 0.479).exp() - 1.0);
        assert!(lo < green && hi > green && hi - lo < 0.01, "{lo} {hi}");
        assert!(ranges["nominal"]["exy"]["auto"].is_object());
        assert!(ranges["small"].is_null());
        // From small strain, small strain alone.
        let small = SentStrains {
            measure: StrainMeasure::Small,
            ..sent
        };
        let ranges = json(&small);
        assert!(ranges["small"]["exx"]["auto"].is_object() && ranges["log"].is_null());
    }
}
