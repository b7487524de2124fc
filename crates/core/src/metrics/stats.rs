//! Order statistics of distance samples, matching numpy's defaults.

/// The `q`-th percentile (0..=100) of `v`, interpolating linearly between the
/// two nearest order statistics like `numpy.percentile` (method "linear"):
/// position `h = (n − 1)·q/100`, value `x[⌊h⌋] + (h − ⌊h⌋)·(x[⌊h⌋+1] − x[⌊h⌋])`.
///
/// Runs in O(n) by selection; reorders `v`. `None` for an empty slice.
pub fn percentile(v: &mut [f64], q: f64) -> Option<f64> {
    let n = v.len();
    if n == 0 {
        return None;
    }
    let h = (n - 1) as f64 * (q / 100.0);
    let lo = (h.floor() as usize).min(n - 1);
    let t = h - lo as f64;
    let (_, x_lo, right) = v.select_nth_unstable_by(lo, f64::total_cmp);
    let a = *x_lo;
    if t == 0.0 || right.is_empty() {
        return Some(a);
    }
    let b = right.iter().copied().fold(f64::INFINITY, f64::min);
    // numpy's _lerp: stable at both ends of the interval.
    let d = b - a;
    Some(if t >= 0.5 {
        b - d * (1.0 - t)
    } else {
        a + d * t
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_numpy_linear() {
        // numpy.percentile([1, 2, 3, 4], 95) = 3.85
        let mut v = vec![4.0, 1.0, 3.0, 2.0];
        assert!((percentile(&mut v, 95.0).unwrap() - 3.85).abs() < 1e-12);
        // numpy.percentile(range(21), 95) = 19.0 exactly
        let mut v: Vec<f64> = (0..21).rev().map(f64::from).collect();
        assert_eq!(percentile(&mut v, 95.0), Some(19.0));
        assert_eq!(percentile(&mut [7.0], 95.0), Some(7.0));
        assert_eq!(percentile(&mut [], 95.0), None);
        let mut v = vec![0.0, 10.0];
        assert_eq!(percentile(&mut v, 100.0), Some(10.0));
        assert_eq!(percentile(&mut v, 0.0), Some(0.0));
    }
}
