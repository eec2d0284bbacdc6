//! Sub-pixel peak: least-squares quadratic surface on the 3x3 neighbourhood of the maximum.

/// Offset (dx, dy) of the maximum of the quadratic fitted to `c[row][col]` (centre = integer
/// maximum) and the interpolated maximum value. Offsets are clamped to ±1 px.
///
/// Basis 1, x, y, x²-2/3, xy, y²-2/3 is orthogonal on the 3x3 grid, so each coefficient is a
/// plain weighted sum. When the surface is not a maximum (degenerate or saddle), separable 1-D
/// parabolas through the centre row and column are used instead.
pub fn quadratic_peak_3x3(c: &[[f32; 3]; 3]) -> (f64, f64, f64) {
    let mut s0 = 0.0f64;
    let mut sx = 0.0f64;
    let mut sy = 0.0f64;
    let mut sxx = 0.0f64;
    let mut syy = 0.0f64;
    let mut sxy = 0.0f64;
    for (row, values) in c.iter().enumerate() {
        let y = row as f64 - 1.0;
        for (col, &value) in values.iter().enumerate() {
            let x = col as f64 - 1.0;
            let v = value as f64;
            s0 += v;
            sx += x * v;
            sy += y * v;
            sxx += (x * x - 2.0 / 3.0) * v;
            syy += (y * y - 2.0 / 3.0) * v;
            sxy += x * y * v;
        }
    }
    let a = s0 / 9.0;
    let bx = sx / 6.0;
    let by = sy / 6.0;
    let dxx = sxx / 2.0;
    let dyy = syy / 2.0;
    let exy = sxy / 4.0;
    let model = |x: f64, y: f64| {
        a + bx * x + by * y + dxx * (x * x - 2.0 / 3.0) + exy * x * y + dyy * (y * y - 2.0 / 3.0)
    };
    // Gradient zero: [2dxx exy; exy 2dyy] [x y]^T = -[bx by]^T
    let det = 4.0 * dxx * dyy - exy * exy;
    if dxx < 0.0 && dyy < 0.0 && det > 1e-12 * (dxx * dyy).abs().max(1e-30) {
        let x = (-bx * 2.0 * dyy + by * exy) / det;
        let y = (-by * 2.0 * dxx + bx * exy) / det;
        let x = x.clamp(-1.0, 1.0);
        let y = y.clamp(-1.0, 1.0);
        return (x, y, model(x, y));
    }
    let parabola = |m: f32, z: f32, p: f32| -> f64 {
        let denom = (m as f64) - 2.0 * (z as f64) + (p as f64);
        if denom < 0.0 {
            (0.5 * (m as f64 - p as f64) / denom).clamp(-1.0, 1.0)
        } else {
            0.0
        }
    };
    let x = parabola(c[1][0], c[1][1], c[1][2]);
    let y = parabola(c[0][1], c[1][1], c[2][1]);
    (x, y, c[1][1] as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_quadratic() {
        let (x0, y0) = (0.3, -0.2);
        let mut c = [[0.0f32; 3]; 3];
        for (row, values) in c.iter_mut().enumerate() {
            for (col, v) in values.iter_mut().enumerate() {
                let x = col as f64 - 1.0;
                let y = row as f64 - 1.0;
                *v = (1.0 - (x - x0).powi(2) - 0.5 * (y - y0).powi(2) - 0.1 * (x - x0) * (y - y0))
                    as f32;
            }
        }
        let (x, y, m) = quadratic_peak_3x3(&c);
        assert!((x - x0).abs() < 1e-5 && (y - y0).abs() < 1e-5, "{x} {y}");
        assert!((m - 1.0).abs() < 1e-5);
    }
}
