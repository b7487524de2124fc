//! Rosin's unimodal threshold (P. L. Rosin, "Unimodal thresholding",
//! Pattern Recognition 34, 2001).
//!
//! The histogram is assumed to have one dominant peak (the background) and a
//! tail on the right (the object). A line runs from the peak `(p, h[p])` to
//! an end point of the tail; the threshold is the bin `i` in `(p, end]` whose
//! point `(i, h[i])` lies farthest from that line (perpendicular distance,
//! coordinates (bin index, count), first bin on ties). The argmax does not
//! depend on how the two axes are scaled.
//!
//! The end point has three readings in the literature ([`RosinEnd`]); the
//! default is the issue's wording, "the first empty bin after the last
//! non-empty one". On every reference volume it gives the same threshold as
//! the end at the last non-empty bin. The threshold may fall on an empty bin.
use super::{Histogram, ThresholdError};

/// Where the peak-to-tail line ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RosinEnd {
    /// `(last non-empty + 1, 0)`: the first empty bin after the last filled
    /// one (a virtual bin when the histogram ends there). The default.
    #[default]
    FirstEmptyAfterLast,
    /// `(last non-empty, h[last])` (the MATLAB File-Exchange implementation).
    LastNonempty,
    /// The first empty bin after the peak (Julia's HistogramThresholding.jl);
    /// differs from the others when the tail has gaps.
    FirstZeroAfterPeak,
}

/// The result of Rosin's method with the geometry that produced it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rosin {
    /// The threshold (centre of `bin`); foreground is `v > threshold`.
    pub threshold: f64,
    /// The bin farthest from the line.
    pub bin: usize,
    /// The peak bin (first bin of maximum count).
    pub peak_bin: usize,
    /// The end bin of the line (may be one past the last bin).
    pub end_bin: usize,
    /// The largest perpendicular distance, in (bin, count) units
    /// (0 when the tail is empty and the peak is returned).
    pub distance: f64,
}

/// Rosin's threshold of `h` with the given end-point rule.
pub fn rosin(h: &Histogram, end: RosinEnd) -> Result<Rosin, ThresholdError> {
    let n = h.counts.len();
    let y: Vec<f64> = h.counts.iter().map(|&c| c as f64).collect();
    let mut p = 0;
    for i in 1..n {
        if y[i] > y[p] {
            p = i;
        }
    }
    let last = h
        .counts
        .iter()
        .rposition(|&c| c > 0)
        .ok_or(ThresholdError::Empty)?;
    let (x2, y2) = match end {
        RosinEnd::LastNonempty => (last, y[last]),
        RosinEnd::FirstEmptyAfterLast => (last + 1, 0.0),
        RosinEnd::FirstZeroAfterPeak => match (p..n).find(|&i| h.counts[i] == 0) {
            Some(z) => (z, 0.0),
            None => (n - 1, y[n - 1]),
        },
    };
    let (x1, y1) = (p as f64, y[p]);
    let stop = x2.min(n - 1);
    if stop <= p {
        return Ok(Rosin {
            threshold: if h.is_constant() { h.min } else { h.centres[p] },
            bin: p,
            peak_bin: p,
            end_bin: x2,
            distance: 0.0,
        });
    }
    let dx = x2 as f64 - x1;
    let dy = y2 - y1;
    let norm = dx.hypot(dy);
    let mut best = (f64::NEG_INFINITY, p + 1);
    for (i, &yi) in y.iter().enumerate().take(stop + 1).skip(p + 1) {
        let d = (dx * (y1 - yi) - (x1 - i as f64) * dy).abs() / norm;
        if d > best.0 {
            best = (d, i);
        }
    }
    Ok(Rosin {
        threshold: h.centres[best.1],
        bin: best.1,
        peak_bin: p,
        end_bin: x2,
        distance: best.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_of_a_linear_tail() {
        // A peak at bin 0 falling to a long flat tail: the knee is the threshold.
        let counts = vec![100, 50, 10, 5, 5, 5, 5, 5, 5, 5];
        let h = Histogram::native_from_counts(0, counts).unwrap();
        let r = rosin(&h, RosinEnd::FirstEmptyAfterLast).unwrap();
        assert_eq!(r.peak_bin, 0);
        assert_eq!(r.end_bin, 10);
        assert_eq!(r.threshold, 2.0);
        let l = rosin(&h, RosinEnd::LastNonempty).unwrap();
        assert_eq!(l.end_bin, 9);
        assert_eq!(l.threshold, 2.0);
    }
}
