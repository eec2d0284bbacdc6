//! The modified Hanning window of the paper, eq. (9), and its 2-D dyadic product, eq. (8).

/// H(i) for i in 0..n: raised cosine on the first and last quarter, 1 in the middle half.
pub fn modified_hanning(n: usize) -> Vec<f32> {
    assert!(
        n >= 4 && n.is_power_of_two(),
        "window size must be 2^s >= 4, got {n}"
    );
    let quarter = n / 4;
    (0..n)
        .map(|i| {
            if i < quarter || i > 3 * quarter {
                let phase = 4.0 * std::f64::consts::PI * i as f64 / (n - 1) as f64;
                (0.5 * (1.0 - phase.cos())) as f32
            } else {
                1.0
            }
        })
        .collect()
}

/// H ⊗ H, row-major n x n.
pub fn modified_hanning_2d(n: usize) -> Vec<f32> {
    let h = modified_hanning(n);
    let mut w = Vec::with_capacity(n * n);
    for &hy in &h {
        for &hx in &h {
            w.push(hy * hx);
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_shape() {
        let h = modified_hanning(32);
        assert_eq!(h[0], 0.0);
        assert!(h[31] < 1e-6);
        assert!(h[8..=24].iter().all(|&v| v == 1.0));
        // continuous at the quarter points
        assert!((h[7] - 1.0).abs() < 0.1 && (h[25] - 1.0).abs() < 0.15);
    }
}
