//! The colour maps of every field figure (the field PNGs of `correlate`, the run's
//! `strain_map.png`, their colour bars, the dashboard's map) and the line colours of the charts,
//! in one place: viridis for a quantity of one sign or a range away from zero, RdBu (blue below
//! zero, white at zero, red above) for a signed quantity whose range straddles zero, both
//! perceptually uniform (a step in value is a step in seen lightness), unlike a rainbow that
//! shows bands where there are none. The tables are `colorous`'s, d3-scale-chromatic's ports of
//! the published maps; [`ColourScale`] ties a map to the values at its ends.

use serde::{Deserialize, Serialize};

/// A perceptual colour map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColourMap {
    /// Sequential, dark blue-violet to yellow (matplotlib's default since 2.0).
    Viridis,
    /// Diverging, blue (negative) through white (zero) to red (positive): ColorBrewer's RdBu
    /// read from its blue end.
    Diverging,
}

impl ColourMap {
    /// The map's colour at `t` in [0, 1] (clamped; NaN reads as 0.5), RGB 0-255.
    pub fn rgb(self, t: f64) -> [u8; 3] {
        let t = if t.is_nan() { 0.5 } else { t.clamp(0.0, 1.0) };
        let (r, g, b) = match self {
            ColourMap::Viridis => colorous::VIRIDIS.eval_continuous(t),
            ColourMap::Diverging => colorous::RED_BLUE.eval_continuous(1.0 - t),
        }
        .as_tuple();
        [r, g, b]
    }

    /// The map's name in figures and JSON.
    pub fn name(self) -> &'static str {
        match self {
            ColourMap::Viridis => "viridis",
            ColourMap::Diverging => "RdBu (blue < 0 < red)",
        }
    }

    /// `samples` colours (at least 2) evenly from t = 0 to 1, for a page that interpolates
    /// them (the dashboard).
    pub fn table(self, samples: usize) -> Vec<[u8; 3]> {
        let n = samples.max(2);
        (0..n)
            .map(|k| self.rgb(k as f64 / (n - 1) as f64))
            .collect()
    }
}

/// The line colours of a chart, distinct in turn (d3's Category10, matplotlib's tab10): the
/// `index`-th series' colour, repeating after ten.
pub fn line_colour(index: usize) -> [u8; 3] {
    let (r, g, b) = colorous::CATEGORY10[index % colorous::CATEGORY10.len()].as_tuple();
    [r, g, b]
}

/// How many distinct [`line_colour`]s there are.
pub const LINE_COLOURS: usize = 10;

/// A map with the values at its ends: a value's colour.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ColourScale {
    pub map: ColourMap,
    /// The values at the bottom and top of the colour bar (`low` < `high`).
    pub low: f64,
    pub high: f64,
}

impl ColourScale {
    /// Where `value` falls on the map, in [0, 1]. The diverging map is centred on zero: t =
    /// 0.5 + value / (2 max(|low|, |high|)), so that white is zero also when the range is not
    /// symmetric (its colour bar then shows only the part of the map its range reaches).
    pub fn t(&self, value: f64) -> f64 {
        let t = match self.map {
            ColourMap::Viridis => (value - self.low) / (self.high - self.low),
            ColourMap::Diverging => {
                let reach = self.low.abs().max(self.high.abs());
                0.5 + value.clamp(self.low, self.high) / (2.0 * reach)
            }
        };
        if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.5
        }
    }

    /// `value`'s colour, values beyond the range at the colour of its end.
    pub fn rgb(&self, value: f64) -> [u8; 3] {
        self.map.rgb(self.t(value))
    }

    /// The colour a fraction `along` in [0, 1] of the way up the colour bar, from `low` to
    /// `high`.
    pub fn bar_rgb(&self, along: f64) -> [u8; 3] {
        self.rgb(self.low + along * (self.high - self.low))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lightness proxy (Rec. 709 luma).
    fn luma(c: [u8; 3]) -> f64 {
        0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
    }

    #[test]
    fn viridis_is_the_published_map_and_grows_lighter_all_the_way() {
        // matplotlib's _viridis_data ends: #440154 and #fde725, middle #21918c.
        assert_eq!(ColourMap::Viridis.rgb(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(ColourMap::Viridis.rgb(1.0), [0xfd, 0xe7, 0x25]);
        let mid = ColourMap::Viridis.rgb(0.5);
        for (c, want) in mid.iter().zip([0x21, 0x91, 0x8c]) {
            assert!((*c as i32 - want).abs() <= 2, "{mid:?}");
        }
        let table = ColourMap::Viridis.table(64);
        assert!(table.windows(2).all(|w| luma(w[1]) > luma(w[0])));
    }

    #[test]
    fn the_diverging_map_is_blue_white_red_and_symmetric_in_lightness() {
        let low = ColourMap::Diverging.rgb(0.0);
        let high = ColourMap::Diverging.rgb(1.0);
        let mid = ColourMap::Diverging.rgb(0.5);
        assert!(low[2] > low[0] + 40, "blue end {low:?}");
        assert!(high[0] > high[2] + 40, "red end {high:?}");
        assert!(mid.iter().all(|&c| c > 235), "white centre {mid:?}");
        for k in 0..=10 {
            let t = k as f64 / 20.0;
            let (a, b) = (
                ColourMap::Diverging.rgb(t),
                ColourMap::Diverging.rgb(1.0 - t),
            );
            assert!((luma(a) - luma(b)).abs() < 30.0, "t {t}: {a:?} {b:?}");
            if k > 0 {
                let before = ColourMap::Diverging.rgb(t - 0.05);
                assert!(luma(a) > luma(before), "lighter towards zero at {t}");
            }
        }
    }

    #[test]
    fn a_diverging_scale_puts_zero_at_white_whatever_its_range() {
        let scale = ColourScale {
            map: ColourMap::Diverging,
            low: -1.0,
            high: 3.0,
        };
        assert_eq!(scale.t(0.0), 0.5);
        assert_eq!(scale.t(3.0), 1.0);
        assert!((scale.t(-1.0) - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(scale.t(-5.0), scale.t(-1.0));
        assert_eq!(scale.bar_rgb(0.25), scale.rgb(0.0));
        let viridis = ColourScale {
            map: ColourMap::Viridis,
            low: 2.0,
            high: 4.0,
        };
        assert_eq!(viridis.t(3.0), 0.5);
        assert_eq!(viridis.t(9.0), 1.0);
        assert_eq!(viridis.t(f64::NAN), 0.5);
    }

    #[test]
    fn line_colours_differ_for_ten_series() {
        let colours: Vec<[u8; 3]> = (0..LINE_COLOURS).map(line_colour).collect();
        for (i, a) in colours.iter().enumerate() {
            for b in &colours[i + 1..] {
                assert_ne!(a, b);
            }
        }
        assert_eq!(line_colour(LINE_COLOURS), line_colour(0));
    }
}
