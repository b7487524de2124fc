//! Multi-class Otsu (Liao, Chen & Chung 2001 generalisation of Otsu 1979):
//! `K` classes `[0..=t_1], [t_1+1..=t_2], …` maximising `Σ W_c μ_c²`.
//!
//! The search is exact in f64 (see `partition`), not the float32 search of
//! scikit-image: on `u8_trimodal` scikit-image returns [74, 159] while the
//! exact optimum is [79, 160] (the two objectives differ by 6e-8 relative,
//! below float32 resolution). The thresholds are the centres of the last
//! non-empty bin of each lower class; a voxel `v` gets class `#{t : v > t}`.
use super::partition::{Prefix, optimal_partition};
use super::{Histogram, ThresholdError, otsu};

/// The `classes - 1` thresholds of multi-class Otsu (`classes` in 2..=16).
/// Two classes give exactly [`otsu()`](fn@super::otsu). Errs when fewer bins than classes hold voxels.
pub fn multi_otsu(h: &Histogram, classes: usize) -> Result<Vec<f64>, ThresholdError> {
    if !(2..=16).contains(&classes) {
        return Err(ThresholdError::Invalid(format!(
            "multi-Otsu needs 2 to 16 classes, not {classes}"
        )));
    }
    let found = h.nonempty_bins();
    if found == 0 {
        return Err(ThresholdError::Empty);
    }
    if found < classes {
        return Err(ThresholdError::TooFewValues { classes, found });
    }
    if classes == 2 {
        return Ok(vec![otsu(h)?]);
    }
    // Empty bins change no class sums; search over the non-empty ones only.
    let (values, weights): (Vec<f64>, Vec<f64>) = h
        .centres
        .iter()
        .zip(&h.counts)
        .filter(|(_, c)| **c > 0)
        .map(|(&x, &c)| (x, c as f64))
        .unzip();
    let p = Prefix::new(&values, &weights);
    let ends = optimal_partition(&p, values.len(), classes);
    Ok(ends[..classes - 1].iter().map(|&e| values[e - 1]).collect())
}

/// The objective `Σ S_c² / W_c` of the classes that `thresholds` make on
/// `h` (class of a bin = number of thresholds below its centre). Used to
/// compare a threshold set with another, e.g. scikit-image's float32 answer.
pub fn multi_otsu_objective(h: &Histogram, thresholds: &[f64]) -> f64 {
    let mut w = vec![0.0f64; thresholds.len() + 1];
    let mut s = vec![0.0f64; thresholds.len() + 1];
    for (&c, &x) in h.counts.iter().zip(&h.centres) {
        let k = thresholds.iter().filter(|&&t| x > t).count();
        w[k] += c as f64;
        s[k] += c as f64 * x;
    }
    w.iter()
        .zip(&s)
        .filter(|(w, _)| **w > 0.0)
        .map(|(w, s)| s * s / w)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_separated_groups() {
        // 10 (x20000), 11 (x10000), 12 (x5000), 100 (x3000), 101 (x2000), 200 (x1000)
        let mut c = vec![0u64; 191];
        for (v, n) in [
            (10, 20000),
            (11, 10000),
            (12, 5000),
            (100, 3000),
            (101, 2000),
            (200, 1000),
        ] {
            c[v - 10] = n;
        }
        let h = Histogram::native_from_counts(10, c).unwrap();
        assert_eq!(multi_otsu(&h, 3).unwrap(), vec![12.0, 101.0]);
        assert_eq!(multi_otsu(&h, 2).unwrap(), vec![12.0]);
        assert!(matches!(
            multi_otsu(&h, 7),
            Err(ThresholdError::TooFewValues {
                classes: 7,
                found: 6
            })
        ));
        let best = multi_otsu_objective(&h, &[12.0, 101.0]);
        assert!(best > multi_otsu_objective(&h, &[11.0, 101.0]));
    }
}
