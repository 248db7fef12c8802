//! Vector helpers shared by every module.

/// Euclidean norm, computed without intermediate overflow or underflow (the entries are
/// scaled by the largest magnitude first, as LAPACK's dnrm2 does); +∞ only when the norm
/// itself exceeds the largest f64 or an entry is infinite, NaN when an entry is NaN.
#[inline]
pub fn norm(x: &[f64]) -> f64 {
    // one pass for the common case: the plain sum of squares, exact when the largest entry
    // lies in [1e-150, 1e150] (no overflow, no underflow of the squares that matter)
    let mut max = 0.0f64;
    let mut sum = 0.0;
    for &v in x {
        sum += v * v;
        let a = v.abs();
        // NaN compares false: it is caught by the test below, through `sum`
        if a > max {
            max = a;
        }
    }
    if (1e-150..=1e150).contains(&max) && sum.is_finite() {
        return sum.sqrt();
    }
    if x.iter().any(|v| v.is_nan()) {
        return f64::NAN;
    }
    if max == 0.0 || max.is_infinite() {
        return max;
    }
    if !(1e-150..=1e150).contains(&max) {
        // an exact power of two near max, so that the scaling itself does not round
        let e = max.log2().floor().clamp(-1022.0, 1023.0) as i32;
        let (down, up) = (2f64.powi(-e), 2f64.powi(e));
        let s = x
            .iter()
            .map(|v| (v * down) * (v * down))
            .sum::<f64>()
            .sqrt();
        s * up
    } else {
        x.iter().map(|v| v * v).sum::<f64>().sqrt()
    }
}
