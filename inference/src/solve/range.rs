//! Range regularization (thesis eq. 3.8): a barrier
//! g(t) = 1/((t+δ)(1+δ−t)), δ = 1/512, on t = x / range, weighted by
//! ε_b (n_s/n_t) / (g(0) − g(½)). Convex on (−δ, 1+δ), infinite at the ends.

pub const RANGE_DELTA: f64 = 1.0 / 512.0;

/// g(t); +∞ outside the open domain (−δ, 1+δ).
pub fn g(t: f64) -> f64 {
    let (u, v) = (t + RANGE_DELTA, 1.0 + RANGE_DELTA - t);
    if u <= 0.0 || v <= 0.0 {
        f64::INFINITY
    } else {
        1.0 / (u * v)
    }
}

/// (g′(t), g″(t)) inside the domain.
pub fn g_derivatives(t: f64) -> (f64, f64) {
    let w = (t + RANGE_DELTA) * (1.0 + RANGE_DELTA - t);
    let dw = 1.0 - 2.0 * t;
    (-dw / (w * w), 2.0 / (w * w) + 2.0 * dw * dw / (w * w * w))
}

/// 1 / (g(0) − g(½)): makes the term comparable in size to the data term.
pub fn calibration() -> f64 {
    1.0 / (g(0.0) - g(0.5))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        for t in [-0.001, 0.0, 0.1, 0.5, 0.9, 1.0] {
            let h = 1e-7;
            let (d1, d2) = g_derivatives(t);
            let fd1 = (g(t + h) - g(t - h)) / (2.0 * h);
            let fd2 = (g_derivatives(t + h).0 - g_derivatives(t - h).0) / (2.0 * h);
            assert!((d1 - fd1).abs() <= 1e-5 * d1.abs().max(1.0), "g' at {t}");
            assert!((d2 - fd2).abs() <= 1e-5 * d2.abs().max(1.0), "g'' at {t}");
            assert!(d2 > 0.0);
        }
        assert_eq!(g(-RANGE_DELTA), f64::INFINITY);
        assert_eq!(g(1.0 + RANGE_DELTA), f64::INFINITY);
        assert!(calibration() > 0.0 && g(0.5) < g(0.0));
    }
}
