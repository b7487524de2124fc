//! Statistics of distance samples: order statistics matching numpy's
//! defaults, and the per-direction summary of the border distances.
use rayon::prelude::*;

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

/// Summary of one direction's distances.
pub(super) struct Directed {
    /// Number of distances.
    pub(super) n: usize,
    /// Largest.
    pub(super) max: Option<f64>,
    /// Mean.
    pub(super) mean: Option<f64>,
    /// 95th percentile.
    pub(super) p95: Option<f64>,
    /// Sum (compensated, in a fixed order).
    pub(super) sum: f64,
    /// How many are within the tolerance.
    pub(super) within: usize,
}

/// Distances summed per chunk of this many, then the chunks in order: the same
/// distances give the same sums whatever the threads do.
const SUM_CHUNK: usize = 1 << 14;

/// A compensated (Neumaier) running sum: millions of distances add up to
/// their sum correctly rounded in all but rare cases, in a fixed order.
#[derive(Clone, Copy, Default)]
struct Sum {
    s: f64,
    c: f64,
}

impl Sum {
    #[inline]
    fn add(self, x: f64) -> Sum {
        let t = self.s + x;
        let c = if self.s.abs() >= x.abs() {
            (self.s - t) + x
        } else {
            (x - t) + self.s
        };
        Sum {
            s: t,
            c: self.c + c,
        }
    }

    fn total(self) -> f64 {
        self.s + self.c
    }
}

/// The statistics of one direction's distances `d` (reordered) for the NSD
/// tolerance `tol`.
pub(super) fn summarise(d: &mut [f64], tol: f64) -> Directed {
    let n = d.len();
    // Distances equal to the tolerance up to rounding count as within it.
    let limit = tol * (1.0 + 1e-12);
    let parts: Vec<(Sum, f64, usize)> = d
        .par_chunks(SUM_CHUNK)
        .map(|c| {
            c.iter()
                .fold((Sum::default(), f64::NEG_INFINITY, 0), |(s, m, w), &x| {
                    (s.add(x), m.max(x), w + usize::from(x <= limit))
                })
        })
        .collect();
    let sum = parts
        .iter()
        .fold(Sum::default(), |a, p| a.add(p.0.s).add(p.0.c))
        .total();
    let max = (n > 0).then(|| parts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max));
    let within = parts.iter().map(|p| p.2).sum();
    Directed {
        n,
        max,
        mean: (n > 0).then(|| sum / n as f64),
        p95: percentile(d, 95.0),
        sum,
        within,
    }
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
