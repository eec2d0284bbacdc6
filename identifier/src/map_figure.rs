//! A field map as a figure a report can take: the map (an RGB image made by the caller, e.g.
//! the correlator's colour map over the reference image), a title, and a colour bar with its
//! values and unit. Text as in [`crate::plot`] (a system font; without one, no text).

use crate::plot::{text_available, PlotError};
use plotters::prelude::*;
use std::path::Path;
use wire::colour_map::ColourScale;

/// Margins around the map, px: top (title), left and bottom.
const TOP_PX: usize = 44;
const SIDE_PX: usize = 12;
/// The colour bar's width and the room for its labels, px.
const BAR_PX: usize = 26;
const LABELS_PX: usize = 150;
/// Room for the bar's title (written upwards) at the right of its labels, px.
const BAR_TITLE_PX: usize = 24;
/// Values written beside the bar.
const TICKS: usize = 5;

/// What the figure shows.
pub struct MapFigure<'a> {
    /// The map, RGB bytes row-major, `width_px` x `height_px`.
    pub rgb: &'a [u8],
    pub width_px: usize,
    pub height_px: usize,
    /// E.g. `exx (log strain), frame 530`.
    pub title: &'a str,
    /// The map's colours and the values at the bar's bottom and top: the scale the map
    /// was coloured with, so that the bar shows the map's own colours.
    pub scale: ColourScale,
    /// How a bar value is written, e.g. `|v| format!("{:.2} %", 100.0 * v)`.
    pub label: &'a dyn Fn(f64) -> String,
    /// What the bar's colour is, with its unit or normalisation: written upwards along the
    /// bar's labels (None: the title says it).
    pub bar_title: Option<&'a str>,
}

/// The figure's size, px.
fn canvas_size(figure: &MapFigure) -> (usize, usize) {
    (
        SIDE_PX
            + figure.width_px
            + SIDE_PX
            + BAR_PX
            + LABELS_PX
            + if figure.bar_title.is_some() {
                BAR_TITLE_PX
            } else {
                0
            },
        TOP_PX + figure.height_px + SIDE_PX,
    )
}

/// The figure as RGB bytes and its size.
pub fn draw(figure: &MapFigure) -> Result<(Vec<u8>, (usize, usize)), PlotError> {
    let (w, h) = (figure.width_px, figure.height_px);
    if figure.rgb.len() != w * h * 3 || w == 0 || h == 0 {
        return Err(PlotError(format!(
            "a map of {} bytes is not {w} x {h} RGB",
            figure.rgb.len()
        )));
    }
    let (cw, ch) = canvas_size(figure);
    let mut canvas = vec![255u8; cw * ch * 3];
    for y in 0..h {
        let to = 3 * ((TOP_PX + y) * cw + SIDE_PX);
        canvas[to..to + 3 * w].copy_from_slice(&figure.rgb[3 * y * w..3 * (y + 1) * w]);
    }
    let bar_x = SIDE_PX + w + SIDE_PX;
    for y in 0..h {
        // Top: the high end.
        let colour = figure.scale.bar_rgb(1.0 - y as f64 / (h - 1).max(1) as f64);
        for x in bar_x..bar_x + BAR_PX {
            let at = 3 * ((TOP_PX + y) * cw + x);
            canvas[at..at + 3].copy_from_slice(&colour);
        }
    }
    if text_available() {
        let err = |e: &dyn std::fmt::Display| PlotError(format!("map figure: {e}"));
        let root =
            BitMapBackend::with_buffer(&mut canvas, (cw as u32, ch as u32)).into_drawing_area();
        let style = ("sans-serif", 22).into_font().color(&BLACK);
        root.draw_text(figure.title, &style, (SIDE_PX as i32, 10))
            .map_err(|e| err(&e))?;
        let small = ("sans-serif", 16).into_font().color(&BLACK);
        for k in 0..TICKS {
            let t = k as f64 / (TICKS - 1) as f64;
            let value = figure.scale.low + t * (figure.scale.high - figure.scale.low);
            let y = TOP_PX as f64 + (1.0 - t) * (h - 1) as f64;
            let x = (bar_x + BAR_PX) as i32;
            root.draw(&PathElement::new(
                vec![(x, y as i32), (x + 5, y as i32)],
                BLACK.stroke_width(1),
            ))
            .map_err(|e| err(&e))?;
            root.draw_text(&(figure.label)(value), &small, (x + 8, y as i32 - 8))
                .map_err(|e| err(&e))?;
        }
        if let Some(bar_title) = figure.bar_title {
            let upwards = ("sans-serif", 16)
                .into_font()
                .transform(FontTransform::Rotate270)
                .color(&BLACK);
            let x = (cw - BAR_TITLE_PX) as i32;
            let y = (TOP_PX + h - 1) as i32;
            root.draw_text(bar_title, &upwards, (x, y))
                .map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    Ok((canvas, (cw, ch)))
}

/// The figure as a PNG written atomically at `path`.
pub fn write(path: &Path, figure: &MapFigure) -> Result<(), PlotError> {
    let (canvas, (w, h)) = draw(figure)?;
    crate::plot::write_png_sized(path, &canvas, (w as u32, h as u32))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_sits_under_its_title_beside_a_bar_from_low_to_high() {
        let (w, h) = (40, 30);
        let rgb = vec![7u8; w * h * 3];
        let scale = ColourScale {
            map: wire::colour_map::ColourMap::Diverging,
            low: -1.0,
            high: 1.0,
        };
        let label = |v: f64| format!("{v:.1}");
        let figure = MapFigure {
            rgb: &rgb,
            width_px: w,
            height_px: h,
            title: "exx",
            scale,
            label: &label,
            bar_title: None,
        };
        let (canvas, (cw, ch)) = draw(&figure).unwrap();
        assert_eq!((cw, ch), canvas_size(&figure));
        let px = |x: usize, y: usize| &canvas[3 * (y * cw + x)..3 * (y * cw + x) + 3];
        assert_eq!(px(SIDE_PX + 5, TOP_PX + 5), [7, 7, 7]);
        let bar_x = SIDE_PX + w + SIDE_PX + 3;
        // The scale's colours: red (high) at the top of the bar, blue (low) at its bottom.
        assert_eq!(px(bar_x, TOP_PX), scale.rgb(1.0));
        assert_eq!(px(bar_x, TOP_PX + h - 1), scale.rgb(-1.0));
        assert_eq!(
            px(bar_x, TOP_PX + h / 2),
            scale.bar_rgb(1.0 - (h / 2) as f64 / (h - 1) as f64)
        );
        let short = MapFigure {
            rgb: &rgb[3..],
            ..figure
        };
        assert!(draw(&short).is_err());
    }
}
