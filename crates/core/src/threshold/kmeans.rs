//! k-means on intensities: clusters of grey levels with the smallest
//! within-cluster sum of squares, weighted by how often each value occurs.
//!
//! [`kmeans_exact`] is the global optimum (dynamic programming over the sorted
//! distinct values, see `partition`); it is what `segment --method kmeans`
//! uses, so the result never depends on a seed. [`kmeans_lloyd`] is the
//! classic deterministic Lloyd iteration (centres start evenly spread over
//! the range), which can stop at a local optimum; it is kept for comparison.
//! The thresholds are the midpoints between neighbouring centres; a voxel is
//! in cluster `#{t : v > t}`.
use super::ThresholdError;
use super::partition::{Prefix, optimal_partition};

/// A k-means clustering of intensities.
#[derive(Debug, Clone, PartialEq)]
pub struct KMeans {
    /// Cluster centres, ascending.
    pub centres: Vec<f64>,
    /// Midpoints between neighbouring centres (`k - 1` of them).
    pub thresholds: Vec<f64>,
    /// Weighted within-cluster sum of squares.
    pub inertia: f64,
    /// The largest value of each cluster.
    pub last_values: Vec<f64>,
    /// Lloyd iterations (0 for the exact method).
    pub iterations: usize,
}

fn check(values: &[f64], counts: &[u64], k: usize) -> Result<(), ThresholdError> {
    if !(2..=16).contains(&k) {
        return Err(ThresholdError::Invalid(format!(
            "k-means needs 2 to 16 clusters, not {k}"
        )));
    }
    if values.len() != counts.len() {
        return Err(ThresholdError::Invalid(
            "values and counts differ in length".into(),
        ));
    }
    if values.is_empty() {
        return Err(ThresholdError::Empty);
    }
    if values.iter().any(|v| !v.is_finite()) {
        return Err(ThresholdError::NonFinite);
    }
    if values.windows(2).any(|w| w[0] >= w[1]) || counts.contains(&0) {
        return Err(ThresholdError::Invalid(
            "values must be distinct, ascending, with counts > 0".into(),
        ));
    }
    if values.len() < k {
        return Err(ThresholdError::TooFewValues {
            classes: k,
            found: values.len(),
        });
    }
    Ok(())
}

fn inertia(values: &[f64], weights: &[f64], centres: &[f64], ends: &[usize]) -> f64 {
    let mut start = 0;
    let mut total = 0.0;
    for (c, &e) in centres.iter().zip(ends) {
        total += (start..e)
            .map(|i| weights[i] * (values[i] - c) * (values[i] - c))
            .sum::<f64>();
        start = e;
    }
    total
}

/// The globally optimal k-means of distinct ascending `values` occurring
/// `counts` times.
pub fn kmeans_exact(values: &[f64], counts: &[u64], k: usize) -> Result<KMeans, ThresholdError> {
    check(values, counts, k)?;
    let weights: Vec<f64> = counts.iter().map(|&c| c as f64).collect();
    let p = Prefix::new(values, &weights);
    let ends = optimal_partition(&p, values.len(), k);
    let mut centres = Vec::with_capacity(k);
    let mut start = 0;
    for &e in &ends {
        let (w, s) = p.class(start, e);
        centres.push(s / w);
        start = e;
    }
    Ok(KMeans {
        thresholds: centres.windows(2).map(|c| (c[0] + c[1]) / 2.0).collect(),
        inertia: inertia(values, &weights, &centres, &ends),
        last_values: ends.iter().map(|&e| values[e - 1]).collect(),
        centres,
        iterations: 0,
    })
}

/// Deterministic Lloyd's k-means: centres start at `min + (j + ½)(max − min)/k`;
/// a value goes to the nearest centre (an exact tie to the lower one); an
/// empty cluster keeps its centre; the loop stops when no assignment changes
/// (or after `max_iter` rounds).
pub fn kmeans_lloyd(
    values: &[f64],
    counts: &[u64],
    k: usize,
    max_iter: usize,
) -> Result<KMeans, ThresholdError> {
    check(values, counts, k)?;
    let weights: Vec<f64> = counts.iter().map(|&c| c as f64).collect();
    let (lo, hi) = (values[0], values[values.len() - 1]);
    let mut c: Vec<f64> = (0..k)
        .map(|j| lo + (j as f64 + 0.5) * (hi - lo) / k as f64)
        .collect();
    let mut assign: Option<Vec<usize>> = None;
    let mut iterations = 0;
    for it in 1..=max_iter.max(1) {
        iterations = it;
        let mids: Vec<f64> = c.windows(2).map(|w| (w[0] + w[1]) / 2.0).collect();
        // Values are sorted, so clusters are contiguous: cluster = #mids < v.
        let new: Vec<usize> = values
            .iter()
            .map(|&v| mids.iter().filter(|&&m| m < v).count())
            .collect();
        if assign.as_ref() == Some(&new) {
            break;
        }
        for (j, cj) in c.iter_mut().enumerate() {
            let (mut w, mut s) = (0.0, 0.0);
            for i in 0..values.len() {
                if new[i] == j {
                    w += weights[i];
                    s += weights[i] * values[i];
                }
            }
            if w > 0.0 {
                *cj = s / w;
            }
        }
        assign = Some(new);
    }
    let assign = assign.unwrap_or_default();
    let ends: Vec<usize> = (0..k)
        .map(|j| assign.iter().filter(|&&a| a <= j).count())
        .collect();
    let last_values = ends
        .iter()
        .map(|&e| if e > 0 { values[e - 1] } else { f64::NAN })
        .collect();
    let mut total = 0.0;
    for (i, &a) in assign.iter().enumerate() {
        total += weights[i] * (values[i] - c[a]) * (values[i] - c[a]);
    }
    Ok(KMeans {
        thresholds: c.windows(2).map(|w| (w[0] + w[1]) / 2.0).collect(),
        inertia: total,
        last_values,
        centres: c,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_beats_lloyd_on_the_gap_case() {
        let v = [10.0, 11.0, 12.0, 100.0, 101.0, 200.0];
        let c = [20000, 10000, 5000, 3000, 2000, 1000];
        let e = kmeans_exact(&v, &c, 2).unwrap();
        assert!((e.thresholds[0] - 63.785714285714285).abs() < 1e-9);
        assert_eq!(e.last_values, vec![12.0, 200.0]);
        let l = kmeans_lloyd(&v, &c, 2, 1000).unwrap();
        assert!((l.thresholds[0] - 110.9).abs() < 1e-9);
        assert!(l.inertia > e.inertia);
        assert!(matches!(
            kmeans_exact(&v[..1], &c[..1], 2),
            Err(ThresholdError::TooFewValues { .. })
        ));
    }
}
