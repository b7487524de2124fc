//! The triangle threshold (Zack, Rogers & Latt 1977) exactly as
//! scikit-image's `threshold_triangle` computes it: the histogram is mirrored
//! when the tail left of the peak is the shorter one, the line runs from the
//! peak to the far end of the longer tail taken at height 0, and the bin
//! farthest below the line is the threshold. Kept as a cross-check of
//! [`rosin()`](fn@super::rosin), which it equals on right-tailed histograms.
use super::{Histogram, ThresholdError};

/// The triangle threshold of `h` (foreground `v > t`); a constant volume
/// returns its value.
pub fn triangle(h: &Histogram) -> Result<f64, ThresholdError> {
    let nbins = h.counts.len();
    let low0 = h
        .counts
        .iter()
        .position(|&c| c > 0)
        .ok_or(ThresholdError::Empty)?;
    let high0 = h
        .counts
        .iter()
        .rposition(|&c| c > 0)
        .ok_or(ThresholdError::Empty)?;
    if low0 == high0 {
        return Ok(if h.is_constant() {
            h.min
        } else {
            h.centres[low0]
        });
    }
    let mut peak = 0;
    for i in 1..nbins {
        if h.counts[i] > h.counts[peak] {
            peak = i;
        }
    }
    let peak_height = h.counts[peak] as f64;
    let flip = peak - low0 < high0 - peak;
    let hist: Vec<f64> = if flip {
        h.counts.iter().rev().map(|&c| c as f64).collect()
    } else {
        h.counts.iter().map(|&c| c as f64).collect()
    };
    let (low, peak) = if flip {
        (nbins - high0 - 1, nbins - peak - 1)
    } else {
        (low0, peak)
    };
    let width = (peak - low) as f64;
    let norm = (peak_height * peak_height + width * width).sqrt();
    let (ph, w) = (peak_height / norm, width / norm);
    let mut best = (f64::NEG_INFINITY, 0usize);
    for x in 0..peak - low {
        let len = ph * x as f64 - w * hist[x + low];
        if len > best.0 {
            best = (len, x);
        }
    }
    let mut level = best.1 + low;
    if flip {
        level = nbins - level - 1;
    }
    Ok(h.centres[level])
}
