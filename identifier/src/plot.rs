//! PNG plots: data and fitted curves per load case, and the paper's f(I1) (Fig. 8) and
//! g(I2) (Fig. 14) plots. Text uses a TrueType font read at run time from the usual system
//! locations (DejaVu, Liberation); without one, the plots are drawn without text.

use crate::data::{Curve, LoadCase};
use crate::fit::Fit;
use crate::law::InvariantFn;
use crate::route::RouteResult;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use wire::colour_map::ColourScale;

/// Fits drawn per plot (best AIC first).
pub const MAX_FITS_PLOTTED: usize = 6;
const SIZE_PX: (u32, u32) = (1000, 700);
const CURVE_SAMPLES: usize = 200;
const FONT_CANDIDATES: [&str; 4] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];
/// The `index`-th line's colour (`wire::colour_map::line_colour`, ten distinct in turn).
fn palette(index: usize) -> RGBColor {
    let [r, g, b] = wire::colour_map::line_colour(index);
    RGBColor(r, g, b)
}

/// A plotting error naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct PlotError(pub String);

/// Registers a system font once; true if text can be drawn.
pub fn text_available() -> bool {
    static AVAILABLE: OnceLock<bool> = OnceLock::new();
    *AVAILABLE.get_or_init(|| {
        for path in FONT_CANDIDATES {
            if let Ok(bytes) = std::fs::read(path) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                    return true;
                }
            }
        }
        false
    })
}

/// A fitted invariant function with its legend label.
type LabelledFn = (String, InvariantFn);

/// One series of a chart.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Markers (data) rather than a line (model).
    pub markers: bool,
}

/// A PNG chart of `series` (lines, or markers for data) with a legend, at `path`. Text only
/// where a system font is found (see [`text_available`]).
pub fn chart(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
) -> Result<(), PlotError> {
    chart_paired(path, title, x_desc, y_desc, series, false)
}

/// [`chart`], where with `paired` a series of markers takes the colour of the line just
/// before it (a model's points against its reference curve). Otherwise every series takes
/// the next of ten distinct colours, but for a chart's only series of markers (its data),
/// black.
pub fn chart_paired(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    paired: bool,
) -> Result<(), PlotError> {
    let rgb = draw_chart(path, Some(title), x_desc, y_desc, series, paired, None)?;
    write_png(path, &rgb)
}

/// Points coloured by a value on a scale, drawn under a chart's series, with a colour bar.
pub struct ColouredPoints<'a> {
    /// (x, y, value), drawn in this order (the last on top).
    pub points: &'a [(f64, f64, f64)],
    pub scale: ColourScale,
    /// What the colour is, with its unit or normalisation (beside the bar).
    pub bar_title: &'a str,
    /// How a bar value is written.
    pub label: &'a dyn Fn(f64) -> String,
}

/// [`chart`] over points coloured by their value (`coloured`, small markers drawn first), the
/// colour bar of their scale on the right ([`crate::map_figure`]).
pub fn chart_coloured(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    coloured: &ColouredPoints,
) -> Result<(), PlotError> {
    let rgb = draw_chart(path, None, x_desc, y_desc, series, false, Some(coloured))?;
    crate::map_figure::write(
        path,
        &crate::map_figure::MapFigure {
            rgb: &rgb,
            width_px: SIZE_PX.0 as usize,
            height_px: SIZE_PX.1 as usize,
            title,
            scale: coloured.scale,
            label: coloured.label,
            bar_title: Some(coloured.bar_title),
        },
    )
}

/// Marker radius of a coloured point, px.
const COLOURED_RADIUS_PX: i32 = 2;

/// The chart as RGB bytes of [`SIZE_PX`]: `title` as its caption (None: none), the coloured
/// points under the series.
fn draw_chart(
    path: &Path,
    title: Option<&str>,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    paired: bool,
    coloured: Option<&ColouredPoints>,
) -> Result<Vec<u8>, PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError(format!("{}: {e}", path.display()));
    let scatter = Series {
        label: String::new(),
        points: coloured.map_or(vec![], |c| c.points.iter().map(|p| (p.0, p.1)).collect()),
        markers: true,
    };
    let mut all: Vec<&Series> = series.iter().collect();
    all.push(&scatter);
    let Some((x0, x1, y0, y1)) = bounds(all) else {
        return Err(PlotError(format!("{}: nothing to plot", path.display())));
    };
    let pad = 0.05 * (y1 - y0).max(1e-9);
    let text = text_available();
    // Drawn in memory, then encoded and written atomically: a full disk leaves no partial or
    // empty PNG.
    let mut rgb = vec![0u8; SIZE_PX.0 as usize * SIZE_PX.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE_PX).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut builder = ChartBuilder::on(&root);
        builder.margin(20);
        if let (true, Some(title)) = (text, title) {
            builder.caption(title, ("sans-serif", 24));
        }
        if text {
            builder.x_label_area_size(45).y_label_area_size(70);
        }
        let mut chart = builder
            .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
            .map_err(|e| err(&e))?;
        if text {
            chart
                .configure_mesh()
                .x_desc(x_desc)
                .y_desc(y_desc)
                .draw()
                .map_err(|e| err(&e))?;
        } else {
            let area = chart.plotting_area();
            area.draw(&Rectangle::new(
                [(x0, y0 - pad), (x1, y1 + pad)],
                BLACK.stroke_width(1),
            ))
            .map_err(|e| err(&e))?;
        }
        if let Some(c) = coloured {
            let finite = c
                .points
                .iter()
                .filter(|p| p.0.is_finite() && p.1.is_finite());
            chart
                .draw_series(finite.map(|&(x, y, v)| {
                    let [r, g, b] = c.scale.rgb(v);
                    Circle::new((x, y), COLOURED_RADIUS_PX, RGBColor(r, g, b).filled())
                }))
                .map_err(|e| err(&e))?;
        }
        // Paired: the lines take the palette in turn and each line's markers its colour.
        let only_data = series.iter().filter(|s| s.markers).count() == 1;
        let (mut lines, mut coloured) = (0, 0);
        for s in series {
            let color = match (s.markers, paired) {
                (true, true) if lines > 0 => palette(lines - 1),
                (true, true) => BLACK,
                (false, true) => palette(lines),
                (true, false) if only_data => BLACK,
                (_, false) => palette(coloured),
            };
            lines += usize::from(!s.markers);
            coloured += usize::from(!(paired || s.markers && only_data));
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .collect();
            let drawn = if s.markers {
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
                    .map_err(|e| err(&e))?
            } else {
                chart
                    .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                    .map_err(|e| err(&e))?
            };
            if text {
                let labelled = drawn.label(s.label.clone());
                // The legend shows what the series draws: a marker or a line.
                if s.markers {
                    labelled.legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
                } else {
                    labelled.legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                    });
                }
            }
        }
        if text {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 16))
                .draw()
                .map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    Ok(rgb)
}

/// The finite points' (x0, x1, y0, y1); None when they span no x range.
fn bounds<'a>(series: impl IntoIterator<Item = &'a Series>) -> Option<(f64, f64, f64, f64)> {
    let finite = series
        .into_iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in finite {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    (x0 < x1 && y0 <= y1).then_some((x0, x1, y0, y1))
}

/// The RGB image of a chart's size encoded as a PNG and written atomically at `path`.
fn write_png(path: &Path, rgb: &[u8]) -> Result<(), PlotError> {
    write_png_sized(path, rgb, SIZE_PX)
}

/// The RGB image of `size_px` (width, height) encoded as a PNG and written atomically at `path`.
pub fn write_png_sized(path: &Path, rgb: &[u8], size_px: (u32, u32)) -> Result<(), PlotError> {
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        rgb,
        size_px.0,
        size_px.1,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| PlotError(format!("{}: cannot encode the PNG: {e}", path.display())))?;
    wire::files::write_atomic(path, &png).map_err(|e| PlotError(e.to_string()))
}

fn sample(from: f64, to: f64) -> impl Iterator<Item = f64> {
    (0..=CURVE_SAMPLES).map(move |k| from + (to - from) * k as f64 / CURVE_SAMPLES as f64)
}

/// What the f(I1) and g(I2) plots show besides the route's points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlotOptions {
    /// Every shown fit (at most [`MAX_FITS_PLOTTED`]) and the route's own fitted f and g, not
    /// only the identified law (the best-ranked fit).
    pub all_models: bool,
}

/// Writes `stress_<case>.png` per load case, `f_I1.png` and `g_I2.png` into `dir`; returns the
/// paths. `route`: the paper's route, or why it could not run (the f and g plots then say so
/// in their title, over the identified law alone).
pub fn write_plots(
    dir: &Path,
    curves: &[Curve],
    fits: &[Fit],
    route: Result<&RouteResult, &str>,
    options: PlotOptions,
) -> Result<Vec<PathBuf>, PlotError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| PlotError(format!("{}: cannot create the folder: {e}", dir.display())))?;
    let mut written = Vec::new();
    let shown = &fits[..fits.len().min(MAX_FITS_PLOTTED)];
    for curve in curves {
        let path = dir.join(format!("stress_{}.png", curve.case));
        chart(
            &path,
            &format!("{} tension", curve.case),
            "stretch",
            "nominal stress (MPa)",
            &stress_series(curve, shown),
        )?;
        written.push(path);
    }
    // f(I1) along the uniaxial path and g(I2) along the equibiaxial path (Figs 8 and 14): the
    // route's points against the identified law (the best-ranked fit that has f and g).
    // A model without f and g (Ogden's is in the principal stretches) is passed over: the
    // law drawn is then the best-ranked one that has them, and its label says so.
    let wanted = if options.all_models {
        MAX_FITS_PLOTTED
    } else {
        1
    };
    let invariant_fits: Vec<&Fit> = shown
        .iter()
        .filter(|f| {
            f.model
                .invariant_derivatives_mpa(&f.params, 3.0, 3.0)
                .is_some()
        })
        .take(wanted)
        .collect();
    let identified = match (invariant_fits.first(), shown.first()) {
        (Some(law), Some(best)) if std::ptr::eq(*law, best) => "identified law",
        _ => "best-ranked law with f and g",
    };
    for (case, which, name) in [
        (LoadCase::Uniaxial, 0, "f_I1"),
        (LoadCase::Equibiaxial, 1, "g_I2"),
    ] {
        let Some(curve) = curves.iter().find(|c| c.case == case) else {
            continue;
        };
        let max_stretch = curve.stretch.last().copied().unwrap_or(1.0);
        let mut series = match route {
            Ok(r) => route_series(r, case, which, max_stretch, options.all_models),
            Err(_) => Vec::new(),
        };
        series.extend(invariant_series(&invariant_fits, case, which, max_stretch));
        if let (Some(law), false) = (series.iter_mut().find(|s| !s.markers), options.all_models) {
            law.label = format!("{identified}: {}", law.label);
        }
        if series.is_empty() {
            continue;
        }
        let path = dir.join(format!("{name}.png"));
        let (title, x, y) = if which == 0 {
            ("f(I1) = dW/dI1 along the uniaxial path", "I1", "f (MPa)")
        } else {
            ("g(I2) = dW/dI2 along the equibiaxial path", "I2", "g (MPa)")
        };
        let title = match route {
            Ok(_) => title.to_string(),
            Err(why) => format!("{title}: no data points ({why})"),
        };
        chart(&path, &title, x, y, &series)?;
        written.push(path);
    }
    Ok(written)
}

/// A curve's data and each shown fit's nominal stress along it.
fn stress_series(curve: &Curve, shown: &[Fit]) -> Vec<Series> {
    let max_stretch = curve.stretch.last().copied().unwrap_or(1.0);
    let mut series = vec![Series {
        label: format!("{} data", curve.case),
        points: curve
            .stretch
            .iter()
            .copied()
            .zip(curve.nominal_stress_mpa.iter().copied())
            .collect(),
        markers: true,
    }];
    for fit in shown {
        let points = sample(1.0, max_stretch)
            .filter_map(|l| {
                fit.model
                    .nominal_stress_mpa(&fit.params, curve.case, l)
                    .map(|p| (l, p))
            })
            .collect();
        series.push(Series {
            label: fit.model.name(),
            points,
            markers: false,
        });
    }
    series
}

/// The paper's route along `case`'s path: f (`which` 0: eq. 19 and 20, and with `fitted` its
/// fit) or g (1: eq. 23, and with `fitted` its two fits).
fn route_series(
    r: &RouteResult,
    case: LoadCase,
    which: usize,
    max_stretch: f64,
    fitted: bool,
) -> Vec<Series> {
    let mut series = Vec::new();
    let (points, label, functions): (&Vec<(f64, f64)>, &str, Vec<LabelledFn>) = if which == 0 {
        (
            &r.f_points,
            "f from eq. 19 (g-corrected)",
            vec![(
                "ln f = Σ a_i (I1-3)^i".into(),
                InvariantFn::ExpPoly(r.a.clone()),
            )],
        )
    } else {
        (
            &r.g_points,
            "g from eq. 23",
            vec![
                (
                    "g = exp Σ b_i (I2-3)^i".into(),
                    InvariantFn::ExpPoly(r.b.clone()),
                ),
                (
                    "g = Σ c_i / I2^i".into(),
                    InvariantFn::InversePower(r.c.clone()),
                ),
            ],
        )
    };
    series.push(Series {
        label: label.into(),
        points: points.clone(),
        markers: true,
    });
    if which == 0 {
        series.push(Series {
            label: "f from eq. 20 (no g)".into(),
            points: r.f_points_uncorrected.clone(),
            markers: true,
        });
    }
    for (label, func) in functions.into_iter().filter(|_| fitted) {
        let points = sample(1.0 + 1e-3, max_stretch)
            .map(|l| {
                let (i1, i2) = case.invariants(l);
                let inv = if which == 0 { i1 } else { i2 };
                (inv, func.value_mpa(inv))
            })
            .collect();
        series.push(Series {
            label,
            points,
            markers: false,
        });
    }
    series
}

/// Each fit's f (`which` 0) or g (1) along `case`'s path.
fn invariant_series(fits: &[&Fit], case: LoadCase, which: usize, max_stretch: f64) -> Vec<Series> {
    fits.iter()
        .map(|fit| Series {
            label: fit.model.name(),
            points: sample(1.0 + 1e-3, max_stretch)
                .filter_map(|l| {
                    let (i1, i2) = case.invariants(l);
                    let (w1, w2) = fit.model.invariant_derivatives_mpa(&fit.params, i1, i2)?;
                    Some(if which == 0 { (i1, w1) } else { (i2, w2) })
                })
                .collect(),
            markers: false,
        })
        .collect()
}
