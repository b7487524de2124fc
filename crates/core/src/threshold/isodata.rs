//! The ISODATA threshold (Ridler & Calvard 1978) as scikit-image's
//! `threshold_isodata` computes it: the first bin centre `t` with
//! `0 <= (μ_low(t) + μ_high(t))/2 − t < bin width`, where `μ_low` is the mean
//! of bins `..=t` and `μ_high` of bins above. It is the fixed-point form of
//! 2-means and a cross-check of [`super::kmeans_exact`].
use super::{Histogram, ThresholdError};

/// The ISODATA threshold of `h` (foreground `v > t`).
pub fn isodata(h: &Histogram) -> Result<f64, ThresholdError> {
    let n = h.counts.len();
    if h.total() == 0 {
        return Err(ThresholdError::Empty);
    }
    if n == 1 || h.is_constant() {
        return Ok(h.min);
    }
    let (total_w, total_s) = h.weight_and_sum();
    let width = h.centres[1] - h.centres[0];
    let (mut wl, mut sl) = (0.0f64, 0.0f64);
    for t in 0..n - 1 {
        wl += h.counts[t] as f64;
        sl += h.counts[t] as f64 * h.centres[t];
        let lower = sl / wl;
        let higher = (total_s - sl) / (total_w - wl);
        let d = (lower + higher) / 2.0 - h.centres[t];
        if d >= 0.0 && d < width {
            return Ok(h.centres[t]);
        }
    }
    Err(ThresholdError::Invalid(
        "ISODATA found no fixed point".into(),
    ))
}
