//! Where the correlator measures: a rectangle (`roi`: the whole image less a margin, the paper's
//! centred 2^p square, or the user's x,y,w,h) and inside it, optionally, a shape: polygons in
//! image pixels and a mask image the size of the frames (non-zero = measure). A pixel is in the
//! region when it is in the rectangle, inside one of the polygons (when there are any) and
//! non-zero in the mask (when there is one).
//!
//! The mesh is laid over the rectangle's part that holds the shape (its bounding box), and a
//! node is measured only when its whole ZOI lies inside the region; the others are
//! `outside_region` for good (never correlated, never counted as failed, left out of the gauge
//! and the strain fits). The ZOIs of the measured nodes are whole, as in a rectangular ROI, so a
//! measured node is as accurate as it would be there; the price is that the region's border
//! half a ZOI deep is not measured. (Ncorr instead takes a subset centred on any ROI point and
//! truncates it to the ROI's contiguous pixels, `get_cirroi`; that needs a correlation of masked
//! subsets, which neither the FFT stage nor the final check here has.)

use crate::settings::{Roi, SettingsError};
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The rectangle the mesh covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RoiChoice {
    /// The whole image less [`RoiChoice::margin_px`] on each side: half a ZOI, so that a node
    /// on the border is a whole ZOI from the image's edge and can move by the integer search's
    /// reach (half the FFT ZOI) before its deformed ZOI leaves the image.
    #[default]
    Margin,
    /// The paper's largest centred 2^p square (CORRELI-GD, section 3.b).
    CentredPow2,
    /// The user's rectangle.
    Rect(Roi),
}

impl RoiChoice {
    /// The default margin (px on each side) for a ZOI of `zoi_px`.
    pub fn margin_px(zoi_px: usize) -> usize {
        zoi_px / 2
    }
}

/// As `--roi` and `[correlator.region] roi` take it: `margin`, `centred-pow2` or `x,y,w,h`.
impl fmt::Display for RoiChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RoiChoice::Margin => f.write_str("margin"),
            RoiChoice::CentredPow2 => f.write_str("centred-pow2"),
            RoiChoice::Rect(roi) => write!(f, "{roi}"),
        }
    }
}

/// Why a region's text was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RegionParseError {
    #[error("ROI '{text}': expected margin (the whole image less half a ZOI), centred-pow2 (the paper's centred 2^p square) or four non-negative integers x,y,w,h")]
    Roi { text: String },
    #[error("polygon '{text}': expected vertices x,y separated by spaces or ';' (image px), e.g. \"16,16 400,16 400,300\"; '{vertex}' is not x,y with finite numbers")]
    Vertex { text: String, vertex: String },
}

impl FromStr for RoiChoice {
    type Err = RegionParseError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let refused = || RegionParseError::Roi {
            text: text.to_owned(),
        };
        match text.trim() {
            "margin" => return Ok(RoiChoice::Margin),
            "centred-pow2" | "centered-pow2" => return Ok(RoiChoice::CentredPow2),
            _ => {}
        }
        let values: Vec<usize> = text
            .split(',')
            .map(|v| v.trim().parse::<usize>())
            .collect::<Result<_, _>>()
            .map_err(|_| refused())?;
        match values[..] {
            [x_px, y_px, width_px, height_px] => Ok(RoiChoice::Rect(Roi {
                x_px,
                y_px,
                width_px,
                height_px,
            })),
            _ => Err(refused()),
        }
    }
}

/// A polygon in image pixels (x = column, y = row; a pixel's centre is at its integer
/// coordinates), closed from its last vertex to its first.
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    pub vertices_px: Vec<(f64, f64)>,
}

impl Polygon {
    /// Whether the point is inside (even-odd rule, the one [`Region`]'s pixels follow; a point
    /// exactly on a left or top edge is inside, on a right or bottom edge outside).
    pub fn contains(&self, (x, y): (f64, f64)) -> bool {
        let v = &self.vertices_px;
        let mut inside = false;
        for i in 0..v.len() {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            if (a.1 <= y && y < b.1) || (b.1 <= y && y < a.1) {
                let crossing = a.0 + (y - a.1) * (b.0 - a.0) / (b.1 - a.1);
                if crossing <= x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

/// As `--polygon` and `polygons` take it: `x,y x,y x,y ...`.
impl fmt::Display for Polygon {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (x, y)) in self.vertices_px.iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{x},{y}")?;
        }
        Ok(())
    }
}

impl FromStr for Polygon {
    type Err = RegionParseError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let vertex = |v: &str| -> Result<(f64, f64), RegionParseError> {
            let refused = || RegionParseError::Vertex {
                text: text.to_owned(),
                vertex: v.to_owned(),
            };
            let (x, y) = v.split_once(',').ok_or_else(refused)?;
            let number = |s: &str| s.trim().parse::<f64>().ok().filter(|n| n.is_finite());
            Ok((
                number(x).ok_or_else(refused)?,
                number(y).ok_or_else(refused)?,
            ))
        };
        let vertices_px = text
            .split(|c: char| c == ';' || c.is_whitespace())
            .filter(|v| !v.is_empty())
            .map(vertex)
            .collect::<Result<_, _>>()?;
        Ok(Polygon { vertices_px })
    }
}

text_serde!(Polygon);

/// Where the correlator measures (module documentation).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Region {
    /// The rectangle the mesh covers.
    #[serde(with = "wire::names::text")]
    pub roi: RoiChoice,
    /// Polygons in image px; when there are any, a node is measured only if its ZOI lies
    /// inside one of them.
    pub polygons: Vec<Polygon>,
    /// A mask image the size of the frames (PNG, TIFF or BMP; non-zero = measure).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mask: Option<PathBuf>,
}

impl Region {
    /// The paper's region: the largest centred 2^p square, no shape.
    pub fn centred_pow2() -> Region {
        Region {
            roi: RoiChoice::CentredPow2,
            ..Region::default()
        }
    }

    /// A rectangle, no shape.
    pub fn rect(roi: Roi) -> Region {
        Region {
            roi: RoiChoice::Rect(roi),
            ..Region::default()
        }
    }

    /// What the shape is, for a summary: `polygon 5 vertices`, `2 polygons`, `mask m.png`;
    /// None for a rectangle alone.
    pub fn shape_description(&self) -> Option<String> {
        let mut parts = Vec::new();
        match &self.polygons[..] {
            [] => {}
            [one] => parts.push(format!("polygon {} vertices", one.vertices_px.len())),
            many => parts.push(format!("{} polygons", many.len())),
        }
        if let Some(mask) = &self.mask {
            parts.push(format!("mask {}", mask.display()));
        }
        (!parts.is_empty()).then(|| parts.join(", "))
    }

    /// The rectangle, the mesh's rectangle and the pixels of the shape for frames of
    /// `width_px` x `height_px` and ZOIs of `zoi_px`; every refusal names its setting.
    pub fn resolve(
        &self,
        width_px: usize,
        height_px: usize,
        zoi_px: usize,
    ) -> Result<ResolvedRegion, SettingsError> {
        if width_px < 16 || height_px < 16 {
            return Err(SettingsError::ImageTooSmall {
                width_px,
                height_px,
            });
        }
        let roi = self.rectangle(width_px, height_px, zoi_px)?;
        if zoi_px > roi.width_px || zoi_px > roi.height_px {
            return Err(SettingsError::ZoiLargerThanRoi {
                zoi_px,
                roi_width_px: roi.width_px,
                roi_height_px: roi.height_px,
            });
        }
        let shape = self.shape(width_px, height_px, roi)?;
        let mesh_rect = match &shape {
            None => roi,
            Some(shape) => {
                let bounds = shape.bounds.ok_or_else(|| SettingsError::EmptyRegion {
                    region: self.to_string(),
                })?;
                if zoi_px > bounds.width_px || zoi_px > bounds.height_px {
                    return Err(SettingsError::RegionSmallerThanZoi {
                        region: self.to_string(),
                        zoi_px,
                    });
                }
                bounds
            }
        };
        Ok(ResolvedRegion {
            roi,
            mesh_rect,
            shape,
        })
    }

    fn rectangle(
        &self,
        width_px: usize,
        height_px: usize,
        zoi_px: usize,
    ) -> Result<Roi, SettingsError> {
        Ok(match self.roi {
            RoiChoice::Rect(roi) => {
                let fits = roi.width_px > 0
                    && roi.height_px > 0
                    && roi.x_px + roi.width_px <= width_px
                    && roi.y_px + roi.height_px <= height_px;
                if !fits {
                    return Err(SettingsError::RoiOutside {
                        roi,
                        width_px,
                        height_px,
                    });
                }
                roi
            }
            RoiChoice::CentredPow2 => {
                crate::settings::centred_power_of_two_square(width_px, height_px)
            }
            RoiChoice::Margin => {
                let margin = RoiChoice::margin_px(zoi_px);
                Roi {
                    x_px: margin,
                    y_px: margin,
                    width_px: width_px.saturating_sub(2 * margin),
                    height_px: height_px.saturating_sub(2 * margin),
                }
            }
        })
    }

    /// The pixels of the rectangle that are in the region, None when every one is.
    fn shape(
        &self,
        width_px: usize,
        height_px: usize,
        roi: Roi,
    ) -> Result<Option<Shape>, SettingsError> {
        if self.polygons.is_empty() && self.mask.is_none() {
            return Ok(None);
        }
        let mut inside = vec![false; width_px * height_px];
        for y in roi.y_px..roi.y_px + roi.height_px {
            inside[y * width_px + roi.x_px..y * width_px + roi.x_px + roi.width_px].fill(true);
        }
        if !self.polygons.is_empty() {
            let mut in_polygons = vec![false; width_px * height_px];
            for (index, polygon) in self.polygons.iter().enumerate() {
                check_polygon(index, polygon, width_px, height_px)?;
                rasterise(polygon, width_px, height_px, &mut in_polygons);
            }
            for (a, b) in inside.iter_mut().zip(&in_polygons) {
                *a &= *b;
            }
        }
        if let Some(path) = &self.mask {
            let mask = read_mask(path, width_px, height_px)?;
            for (a, b) in inside.iter_mut().zip(&mask) {
                *a &= *b;
            }
        }
        Ok(Some(Shape::new(&inside, width_px, height_px)))
    }
}

/// The region as a summary names it: `roi margin, polygons "16,16 400,16 400,300", mask m.png`.
impl fmt::Display for Region {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "roi {}", self.roi)?;
        for polygon in &self.polygons {
            write!(f, ", polygon \"{polygon}\"")?;
        }
        if let Some(mask) = &self.mask {
            write!(f, ", mask {}", mask.display())?;
        }
        Ok(())
    }
}

/// A [`Region`] for one image size.
#[derive(Clone, Debug)]
pub struct ResolvedRegion {
    /// The rectangle chosen (`roi`).
    pub roi: Roi,
    /// Where the mesh is laid: the rectangle, or the bounding box of its pixels in the shape.
    pub mesh_rect: Roi,
    /// The pixels in the region, None when the rectangle is the region.
    shape: Option<Shape>,
}

impl ResolvedRegion {
    /// Whether the `n` x `n` block at `top_left` lies wholly inside the region.
    pub fn contains_block(&self, top_left: (usize, usize), n: usize) -> bool {
        let (x, y) = top_left;
        let r = self.mesh_rect;
        let in_rect = x >= r.x_px
            && y >= r.y_px
            && x + n <= r.x_px + r.width_px
            && y + n <= r.y_px + r.height_px;
        in_rect
            && self
                .shape
                .as_ref()
                .is_none_or(|s| s.count(x, y, n) == n * n)
    }
}

/// The region's pixels as a summed-area table (a block's count in four reads) and their
/// bounding box.
#[derive(Clone, Debug)]
struct Shape {
    width_px: usize,
    /// `sums[(y) * (w + 1) + x]`: pixels in the region above and left of (x, y).
    sums: Vec<u32>,
    bounds: Option<Roi>,
}

impl Shape {
    fn new(inside: &[bool], width_px: usize, height_px: usize) -> Shape {
        let stride = width_px + 1;
        let mut sums = vec![0u32; stride * (height_px + 1)];
        let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
        for y in 0..height_px {
            let mut row = 0u32;
            for x in 0..width_px {
                let set = inside[y * width_px + x];
                if set {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
                row += u32::from(set);
                sums[(y + 1) * stride + x + 1] = sums[y * stride + x + 1] + row;
            }
        }
        let bounds = (x0 != usize::MAX).then(|| Roi {
            x_px: x0,
            y_px: y0,
            width_px: x1 - x0 + 1,
            height_px: y1 - y0 + 1,
        });
        Shape {
            width_px,
            sums,
            bounds,
        }
    }

    fn count(&self, x: usize, y: usize, n: usize) -> usize {
        let s = self.width_px + 1;
        let at = |x: usize, y: usize| self.sums[y * s + x] as i64;
        (at(x + n, y + n) - at(x, y + n) - at(x + n, y) + at(x, y)) as usize
    }
}

/// Fewer than 3 vertices, a vertex outside the image, or two edges that cross.
fn check_polygon(
    index: usize,
    polygon: &Polygon,
    width_px: usize,
    height_px: usize,
) -> Result<(), SettingsError> {
    let v = &polygon.vertices_px;
    if v.len() < 3 {
        return Err(SettingsError::PolygonTooFewVertices {
            index,
            polygon: polygon.to_string(),
            vertices: v.len(),
        });
    }
    let (w, h) = (width_px as f64, height_px as f64);
    if let Some(&(x, y)) = v
        .iter()
        .find(|&&(x, y)| !(0.0..=w).contains(&x) || !(0.0..=h).contains(&y))
    {
        return Err(SettingsError::PolygonOutside {
            index,
            polygon: polygon.to_string(),
            x,
            y,
            width_px,
            height_px,
        });
    }
    let n = v.len();
    let edge = |i: usize| (v[i], v[(i + 1) % n]);
    for i in 0..n {
        for j in i + 1..n {
            let (a, b) = (edge(i), edge(j));
            let crossing = if j == i + 1 {
                folded_back(a, b)
            } else if i == 0 && j == n - 1 {
                folded_back(b, a)
            } else {
                segments_meet(a, b)
            };
            if crossing {
                return Err(SettingsError::PolygonSelfCrossing {
                    index,
                    polygon: polygon.to_string(),
                    edges: (i + 1, j + 1),
                });
            }
        }
    }
    Ok(())
}

type Segment = ((f64, f64), (f64, f64));

fn cross(o: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
}

/// Whether point p, collinear with segment s, lies on it.
fn on_segment(s: Segment, p: (f64, f64)) -> bool {
    p.0 >= s.0 .0.min(s.1 .0)
        && p.0 <= s.0 .0.max(s.1 .0)
        && p.1 >= s.0 .1.min(s.1 .1)
        && p.1 <= s.0 .1.max(s.1 .1)
}

/// Whether two non-adjacent edges touch or cross.
fn segments_meet(a: Segment, b: Segment) -> bool {
    let (d1, d2) = (cross(b.0, b.1, a.0), cross(b.0, b.1, a.1));
    let (d3, d4) = (cross(a.0, a.1, b.0), cross(a.0, a.1, b.1));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on_segment(b, a.0))
        || (d2 == 0.0 && on_segment(b, a.1))
        || (d3 == 0.0 && on_segment(a, b.0))
        || (d4 == 0.0 && on_segment(a, b.1))
}

/// Whether edge b, which starts where a ends, goes back along a (the two overlap).
fn folded_back(a: Segment, b: Segment) -> bool {
    let (p, q, r) = (a.0, a.1, b.1);
    let along = (p.0 - q.0) * (r.0 - q.0) + (p.1 - q.1) * (r.1 - q.1);
    cross(q, p, r) == 0.0 && along > 0.0
}

/// Sets the pixels whose centre is inside the polygon (even-odd rule; a centre exactly on a
/// left or top edge is inside, on a right or bottom edge outside).
fn rasterise(polygon: &Polygon, width_px: usize, height_px: usize, inside: &mut [bool]) {
    let v = &polygon.vertices_px;
    let n = v.len();
    let mut crossings = Vec::with_capacity(n);
    for y in 0..height_px {
        let yc = y as f64;
        crossings.clear();
        for i in 0..n {
            let (a, b) = (v[i], v[(i + 1) % n]);
            if (a.1 <= yc && yc < b.1) || (b.1 <= yc && yc < a.1) {
                crossings.push(a.0 + (yc - a.1) * (b.0 - a.0) / (b.1 - a.1));
            }
        }
        crossings.sort_by(f64::total_cmp);
        for pair in crossings.chunks_exact(2) {
            let first = pair[0].ceil().max(0.0) as usize;
            let end = (pair[1].ceil().max(0.0) as usize).min(width_px);
            for x in first..end {
                inside[y * width_px + x] = true;
            }
        }
    }
}

/// The mask image's pixels that are set (any channel non-zero), refused unless it is the
/// frames' size.
fn read_mask(path: &Path, width_px: usize, height_px: usize) -> Result<Vec<bool>, SettingsError> {
    let unreadable = |reason: String| SettingsError::MaskUnreadable {
        path: path.to_owned(),
        reason,
    };
    let reader = image::ImageReader::open(path)
        .map_err(|e| unreadable(e.to_string()))?
        .with_guessed_format()
        .map_err(|e| unreadable(e.to_string()))?;
    let decoded = reader.decode().map_err(|e| unreadable(e.to_string()))?;
    let (w, h) = (decoded.width() as usize, decoded.height() as usize);
    if (w, h) != (width_px, height_px) {
        return Err(SettingsError::MaskSize {
            path: path.to_owned(),
            width_px: w,
            height_px: h,
            expected_width_px: width_px,
            expected_height_px: height_px,
        });
    }
    let rgb = decoded.to_rgb16();
    Ok(rgb.pixels().map(|p| p.0.iter().any(|&c| c != 0)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polygon(text: &str) -> Polygon {
        text.parse().unwrap()
    }

    #[test]
    fn roi_choices_read_and_write_back() {
        for text in ["margin", "centred-pow2", "1,2,30,40"] {
            assert_eq!(text.parse::<RoiChoice>().unwrap().to_string(), text);
        }
        assert_eq!(
            "centered-pow2".parse::<RoiChoice>(),
            Ok(RoiChoice::CentredPow2)
        );
        assert!("1,2,3".parse::<RoiChoice>().is_err());
        assert!("whole".parse::<RoiChoice>().is_err());
    }

    #[test]
    fn polygons_read_with_spaces_or_semicolons() {
        let p = polygon("16,16; 400,16;400.5,300");
        assert_eq!(
            p.vertices_px,
            vec![(16.0, 16.0), (400.0, 16.0), (400.5, 300.0)]
        );
        assert_eq!(polygon(&p.to_string()), p);
        assert!("16,16 400".parse::<Polygon>().is_err());
        assert!("16,nan 1,1 2,2".parse::<Polygon>().is_err());
    }

    #[test]
    fn the_default_is_the_image_less_half_a_zoi() {
        let resolved = Region::default().resolve(2048, 589, 32).unwrap();
        assert_eq!(
            resolved.roi,
            "16,16,2016,557"
                .parse::<RoiChoice>()
                .map(|r| match r {
                    RoiChoice::Rect(r) => r,
                    _ => unreachable!(),
                })
                .unwrap()
        );
        assert_eq!(resolved.mesh_rect, resolved.roi);
        let pow2 = Region::centred_pow2().resolve(2048, 589, 32).unwrap();
        assert_eq!((pow2.roi.x_px, pow2.roi.width_px), (768, 512));
    }

    #[test]
    fn a_polygon_keeps_the_zois_wholly_inside() {
        let region = Region {
            polygons: vec![polygon("10,10 110,10 110,60 10,60")],
            ..Region::default()
        };
        let resolved = region.resolve(200, 100, 16).unwrap();
        // Pixel centres 10..=109 x 10..=59.
        assert_eq!(
            resolved.mesh_rect,
            Roi {
                x_px: 10,
                y_px: 10,
                width_px: 100,
                height_px: 50
            }
        );
        assert!(resolved.contains_block((10, 10), 16));
        assert!(resolved.contains_block((94, 44), 16));
        assert!(!resolved.contains_block((95, 44), 16));
        assert!(!resolved.contains_block((9, 10), 16));
        // A triangle: its right-angle corner holds a ZOI, the far corner does not.
        let triangle = Region {
            polygons: vec![polygon("20,20 180,20 20,90")],
            ..Region::default()
        };
        let resolved = triangle.resolve(200, 100, 16).unwrap();
        assert!(resolved.contains_block((20, 20), 16));
        assert!(!resolved.contains_block((150, 60), 16));
    }

    #[test]
    fn bad_polygons_are_refused_naming_them() {
        let with = |text: &str| Region {
            polygons: vec![polygon("0,0 50,0 0,50"), polygon(text)],
            ..Region::default()
        };
        let error = |text: &str| with(text).resolve(200, 100, 16).unwrap_err();
        assert!(matches!(
            error("10,10 20,20"),
            SettingsError::PolygonTooFewVertices {
                index: 1,
                vertices: 2,
                ..
            }
        ));
        assert!(matches!(
            error("10,10 100,90 100,10 10,90"),
            SettingsError::PolygonSelfCrossing { index: 1, .. }
        ));
        assert!(matches!(
            error("10,10 250,10 10,90"),
            SettingsError::PolygonOutside { index: 1, .. }
        ));
        assert!(error("10,10 250,10 10,90")
            .to_string()
            .contains("--polygon"));
        // Collinear: it folds back on itself.
        assert!(matches!(
            error("10,10 50,10 90,10"),
            SettingsError::PolygonSelfCrossing { index: 1, .. }
        ));
        // Between pixel centres: no pixel at all.
        let flat = Region {
            polygons: vec![polygon("10.2,10.2 10.8,10.2 10.8,10.8")],
            ..Region::default()
        };
        assert!(matches!(
            flat.resolve(200, 100, 16).unwrap_err(),
            SettingsError::EmptyRegion { .. }
        ));
        let small = Region {
            polygons: vec![polygon("10,10 20,10 20,20 10,20")],
            ..Region::default()
        };
        assert!(matches!(
            small.resolve(200, 100, 16).unwrap_err(),
            SettingsError::RegionSmallerThanZoi { zoi_px: 16, .. }
        ));
    }

    #[test]
    fn masks_of_the_wrong_size_or_unreadable_are_refused() {
        let dir = std::env::temp_dir().join(format!("dicstream_mask_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.png");
        let mut img = image::GrayImage::new(200, 100);
        for y in 20..80 {
            for x in 30..130 {
                img.put_pixel(x, y, image::Luma([255]));
            }
        }
        img.save(&good).unwrap();
        let region = |path: &Path| Region {
            mask: Some(path.to_owned()),
            ..Region::default()
        };
        let resolved = region(&good).resolve(200, 100, 16).unwrap();
        assert_eq!(
            resolved.mesh_rect,
            Roi {
                x_px: 30,
                y_px: 20,
                width_px: 100,
                height_px: 60
            }
        );
        let wrong = region(&good).resolve(201, 100, 16).unwrap_err();
        assert!(matches!(
            wrong,
            SettingsError::MaskSize { width_px: 200, .. }
        ));
        assert!(wrong.to_string().contains("--mask"), "{wrong}");
        let text = dir.join("not.png");
        std::fs::write(&text, b"not an image").unwrap();
        assert!(matches!(
            region(&text).resolve(200, 100, 16).unwrap_err(),
            SettingsError::MaskUnreadable { .. }
        ));
        assert!(matches!(
            region(&dir.join("absent.png"))
                .resolve(200, 100, 16)
                .unwrap_err(),
            SettingsError::MaskUnreadable { .. }
        ));
        let black = dir.join("black.png");
        image::GrayImage::new(200, 100).save(&black).unwrap();
        assert!(matches!(
            region(&black).resolve(200, 100, 16).unwrap_err(),
            SettingsError::EmptyRegion { .. }
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
