//! Otsu's threshold (N. Otsu, "A threshold selection method from gray-level
//! histograms", IEEE SMC 1979).
//!
//! Class 0 is bins `0..=t`; `t` maximises the between-class variance
//! `w0·w1·(μ0 − μ1)²`, computed in f64 from cumulative sums, and the first
//! maximum wins on ties (so on a run of empty bins the lowest bin is chosen:
//! the threshold is then the last grey level present in class 0). The value
//! returned is the centre of bin `t`; foreground is `v > t`.
use super::{Histogram, ThresholdError};

/// The bin index Otsu's method selects, or `None` when fewer than two bins
/// hold voxels (there is nothing to separate).
pub fn otsu_bin(h: &Histogram) -> Option<usize> {
    if h.nonempty_bins() < 2 {
        return None;
    }
    let n = h.counts.len();
    let (total_w, total_s) = h.weight_and_sum();
    let mut w1 = 0.0f64;
    let mut s1 = 0.0f64;
    let mut best = (f64::NEG_INFINITY, 0usize);
    for t in 0..n - 1 {
        w1 += h.counts[t] as f64;
        s1 += h.counts[t] as f64 * h.centres[t];
        let w2 = total_w - w1;
        let s2 = total_s - s1;
        let var = if w1 > 0.0 && w2 > 0.0 {
            let d = s1 / w1 - s2 / w2;
            w1 * w2 * d * d
        } else {
            -1.0
        };
        if var > best.0 {
            best = (var, t);
        }
    }
    Some(best.1)
}

/// Otsu's threshold of a histogram. A constant volume returns its value
/// (as scikit-image does: nothing lies above it); an empty histogram is an error.
pub fn otsu(h: &Histogram) -> Result<f64, ThresholdError> {
    if h.total() == 0 {
        return Err(ThresholdError::Empty);
    }
    Ok(match otsu_bin(h) {
        Some(t) => h.centres[t],
        None => h.min,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separates_two_clusters_at_the_last_value_of_the_lower_one() {
        // values 10 (x3), 11 (x1), 20 (x4): class 0 = {10, 11}.
        let mut counts = vec![0u64; 11];
        counts[0] = 3;
        counts[1] = 1;
        counts[10] = 4;
        let h = Histogram::native_from_counts(10, counts).unwrap();
        assert_eq!(otsu(&h).unwrap(), 11.0);
    }

    #[test]
    fn constant_returns_the_value() {
        let h = Histogram::native_from_counts(77, vec![5]).unwrap();
        assert_eq!(otsu(&h).unwrap(), 77.0);
        assert_eq!(otsu_bin(&h), None);
    }
}
