//! The sums of a first-order reference subset (see [`super::subset`]), from per-row sums: with
//! J = (f_x, f_x dx, f_x dy, f_y, f_y dx, f_y dy) (∇f̂ times the offset monomials), every entry
//! of Σ J Jᵀ, Σ J and Σ J f̂ is a sum over the rows of dy⁰, dy¹ or dy² times a sum along the row
//! of a product of f̂, f_x, f_y with dx⁰, dx¹ or dx²: 17 row sums per row (in f32, as the
//! iterations' own row sums), combined per row in f64. 17 independent sums per pixel instead of
//! the 33 of the steepest-descent products (`subset::inverse_hessian_of`), most of whose
//! accumulators did not fit the registers: a subset's preparation is mostly this Hessian, and
//! every subset of a new reference is prepared in the first frame that needs it.

/// The row sums: Σ f_x², Σ f_x f_y, Σ f_y² (each times 1, dx, dx²), then Σ f_x, Σ f_y, Σ f̂ f_x,
/// Σ f̂ f_y (each times 1, dx).
const ROW_SUMS: usize = 17;

/// One row's sums: `values`, `gx`, `gy` are the row's f̂, ∂f̂/∂x, ∂f̂/∂y, `half` the column
/// offset of the subset centre.
fn row_sums(values: &[f32], gx: &[f32], gy: &[f32], half: f32) -> [f32; ROW_SUMS] {
    let mut s = [0.0f32; ROW_SUMS];
    for (i, ((&f, &x), &y)) in values.iter().zip(gx).zip(gy).enumerate() {
        let dx = i as f32 - half;
        let products = [x * x, x * y, y * y];
        for (p, &product) in products.iter().enumerate() {
            let weighted = product * dx;
            s[3 * p] += product;
            s[3 * p + 1] += weighted;
            s[3 * p + 2] += weighted * dx;
        }
        let linear = [x, y, f * x, f * y];
        for (q, &value) in linear.iter().enumerate() {
            s[9 + 2 * q] += value;
            s[9 + 2 * q + 1] += value * dx;
        }
    }
    s
}

/// Σ J Jᵀ (upper triangle, row-major 6 x 6 in the first 36 values) of the n x n planes f̂,
/// ∂f̂/∂x, ∂f̂/∂y, and Σ J, Σ J f̂ added into `sum_j`, `sum_jf`; the parameters in the order of
/// `subset::steepest_descent`.
pub fn sums(
    n: usize,
    [values, gx, gy]: [&[f32]; 3],
    sum_j: &mut [f64; 12],
    sum_jf: &mut [f64; 12],
) -> [f64; 144] {
    let half = (n as f64 - 1.0) / 2.0;
    let mut hessian = [0.0f64; 144];
    for j in 0..n {
        let dy = j as f64 - half;
        let row = j * n..(j + 1) * n;
        let s = row_sums(
            &values[row.clone()],
            &gx[row.clone()],
            &gy[row],
            half as f32,
        );
        let dy_power = [1.0, dy, dy * dy];
        // Parameter a is gradient a / 3 (x, y) times monomial a % 3 (1, dx, dy).
        for a in 0..6 {
            for b in a..6 {
                let (ma, mb) = (a % 3, b % 3);
                let pair = a / 3 + b / 3;
                let dx_power = usize::from(ma == 1) + usize::from(mb == 1);
                let dy_count = usize::from(ma == 2) + usize::from(mb == 2);
                hessian[a * 6 + b] += dy_power[dy_count] * s[3 * pair + dx_power] as f64;
            }
            let gradient = a / 3;
            let (plain, with_f) = (9 + 2 * gradient, 13 + 2 * gradient);
            let (j_sum, jf_sum) = match a % 3 {
                0 => (s[plain] as f64, s[with_f] as f64),
                1 => (s[plain + 1] as f64, s[with_f + 1] as f64),
                _ => (dy * s[plain] as f64, dy * s[with_f] as f64),
            };
            sum_j[a] += j_sum;
            sum_jf[a] += jf_sum;
        }
    }
    hessian
}
