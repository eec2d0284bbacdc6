//! The deformed specimen's outline in the image: its boundary edges (the element edges no other
//! element shares: the outer edges, fillets and slits), each the quadratic curve of its three
//! nodes, split where its y turns so that each piece crosses a row at most once. Where a row of
//! pixels crosses the outline tells which of its pixels show material without locating them in
//! the mesh: a point off the specimen costs the walk nothing (locating it there fails only after
//! a Newton in every element whose box holds it).
//!
//! Crossings follow the half-open rule (a piece from y₀ to y₁ counts for min ≤ y < max), so a
//! row through a node counts it once; a row with an odd count (a degenerate outline) gives no
//! spans and the walk locates every point as before.

use crate::motion::Vec2;

/// A point farther than this outside every span is off the specimen, px (the spans' own
/// round-off is some 1e-12 px; the mesh's inside test is within 1e-9 of the natural
/// coordinates).
pub const SLACK_PX: f64 = 1e-6;

/// One piece of a boundary edge, x(t) = a + b t + c t² for t in [t0, t1], y monotone on it.
#[derive(Clone, Copy, Debug)]
struct Piece {
    a: Vec2,
    b: Vec2,
    c: Vec2,
    t0: f64,
    t1: f64,
    y_low: f64,
    y_high: f64,
}

/// The outline of a deformed mesh in image px.
#[derive(Clone, Debug, Default)]
pub struct Outline {
    pieces: Vec<Piece>,
}

impl Outline {
    /// The outline of the edges `edges` (corner, midside, corner: node indices) of the mesh
    /// whose nodes are at `nodes_px` (image px).
    pub fn new(edges: &[[usize; 3]], nodes_px: &[Vec2]) -> Outline {
        let mut pieces = Vec::with_capacity(2 * edges.len());
        for &[first, middle, last] in edges {
            let (p0, pm, p1) = (nodes_px[first], nodes_px[middle], nodes_px[last]);
            let coefficient = |f: &dyn Fn(usize) -> f64| [f(0), f(1)];
            let a = p0;
            let b = coefficient(&|i| -3.0 * p0[i] + 4.0 * pm[i] - p1[i]);
            let c = coefficient(&|i| 2.0 * p0[i] - 4.0 * pm[i] + 2.0 * p1[i]);
            let turn = -b[1] / (2.0 * c[1]);
            let mut add = |t0: f64, t1: f64| {
                let y = |t: f64| a[1] + t * (b[1] + t * c[1]);
                let (y0, y1) = (y(t0), y(t1));
                if y0 != y1 {
                    pieces.push(Piece {
                        a,
                        b,
                        c,
                        t0,
                        t1,
                        y_low: y0.min(y1),
                        y_high: y0.max(y1),
                    });
                }
            };
            if turn > 0.0 && turn < 1.0 {
                add(0.0, turn);
                add(turn, 1.0);
            } else {
                add(0.0, 1.0);
            }
        }
        Outline { pieces }
    }

    /// Where row `y_px` crosses the outline, sorted, into `crossings` (pairs: the spans on the
    /// specimen); false when the count is odd (no spans to trust).
    pub fn crossings(&self, y_px: f64, crossings: &mut Vec<f64>) -> bool {
        crossings.clear();
        for p in &self.pieces {
            if !(p.y_low <= y_px && y_px < p.y_high) {
                continue;
            }
            let t = root_between(p.a[1] - y_px, p.b[1], p.c[1], p.t0, p.t1);
            crossings.push(p.a[0] + t * (p.b[0] + t * p.c[0]));
        }
        crossings.sort_unstable_by(f64::total_cmp);
        crossings.len().is_multiple_of(2)
    }
}

/// The root in [t0, t1] of a + b t + c t², monotone there with a sign change.
fn root_between(a: f64, b: f64, c: f64, t0: f64, t1: f64) -> f64 {
    let value = |t: f64| a + t * (b + t * c);
    let (mut low, mut high) = (t0, t1);
    if value(low) > 0.0 {
        std::mem::swap(&mut low, &mut high);
    }
    // Newton from the chord's root, kept inside the bracket (bisection when it leaves it).
    let (v0, v1) = (value(low), value(high));
    let mut t = low + (high - low) * (-v0 / (v1 - v0)).clamp(0.0, 1.0);
    for _ in 0..60 {
        let v = value(t);
        if v == 0.0 {
            return t;
        }
        if v < 0.0 {
            low = t;
        } else {
            high = t;
        }
        let slope = b + 2.0 * c * t;
        let next = t - v / slope;
        let inside = (next - low) * (next - high) < 0.0;
        let next = if inside { next } else { 0.5 * (low + high) };
        if (next - t).abs() < 1e-14 {
            return next;
        }
        t = next;
    }
    t
}

/// Whether `x_px` is within [`SLACK_PX`] of a span of `crossings` (pairs).
#[inline]
pub fn near_a_span(crossings: &[f64], from_px: f64, to_px: f64) -> bool {
    crossings
        .chunks_exact(2)
        .any(|s| from_px <= s[1] + SLACK_PX && to_px >= s[0] - SLACK_PX)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square with one curved side (x = 10 + 2 sin-like bulge), rows across it.
    #[test]
    fn rows_cross_a_curved_outline_where_its_curves_are() {
        // Corners (0,0) (10,0) (10,10) (0,10); the right side's midside bulges to x = 12.
        let nodes = [
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [0.0, 10.0],
            [5.0, 0.0],
            [12.0, 5.0],
            [5.0, 10.0],
            [0.0, 5.0],
        ];
        let edges = [[0, 4, 1], [1, 5, 2], [2, 6, 3], [3, 7, 0]];
        let outline = Outline::new(&edges, &nodes);
        let mut crossings = Vec::new();
        for y in [0.0, 2.5, 5.0, 9.99] {
            assert!(outline.crossings(y, &mut crossings));
            // The right side: x(t) = 10 + 8 t (1 − t), y = 10 t.
            let t = y / 10.0;
            let want = 10.0 + 8.0 * t * (1.0 - t);
            assert_eq!(crossings.len(), 2, "{y}: {crossings:?}");
            assert!(crossings[0].abs() < 1e-12, "{y}: {crossings:?}");
            assert!((crossings[1] - want).abs() < 1e-12, "{y}: {crossings:?}");
            assert!(near_a_span(&crossings, want, want + 0.5));
            assert!(!near_a_span(&crossings, want + 1e-3, want + 0.5));
        }
        for y in [-0.1, 10.0, 11.0] {
            assert!(outline.crossings(y, &mut crossings));
            assert!(crossings.is_empty(), "{y}: {crossings:?}");
        }
    }
}
