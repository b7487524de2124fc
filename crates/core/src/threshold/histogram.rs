//! Intensity histograms with the two binning conventions of the threshold
//! references (`refs/THRESHOLDS.md`):
//!
//! * **native**: one bin per integer value from `min` to `max` (what
//!   scikit-image does for integer images). Thresholds are integers, so a
//!   threshold on native bins is exactly one of the volume's grey levels.
//! * **uniform**: `n` equal-width bins over `[min, max]`, with the bin
//!   assignment of `numpy.histogram` (bins `[e_i, e_{i+1})`, the last one
//!   closed). Thresholds are bin centres. Float volumes always use this.
//!
//! The bin assignment follows numpy to the last ulp (edges computed as
//! `min + i * (max - min) / n`, the last edge set to `max`, an index estimate
//! corrected against the edges) so that counts agree with the references on
//! every voxel, not just on average.
use super::ThresholdError;
use crate::{AnyVolume, Volume, Voxel};
use rayon::prelude::*;

/// How the bins of a [`Histogram`] were laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binning {
    /// One bin per integer value from the minimum to the maximum.
    Native,
    /// This many equal-width bins over `[min, max]` (numpy's rule).
    Uniform(usize),
}

/// A histogram: counts per bin, the centre of every bin and the data range.
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Voxel count of every bin.
    pub counts: Vec<u64>,
    /// Centre of every bin: the integer value for native bins,
    /// `(e_i + e_{i+1}) / 2` for uniform bins.
    pub centres: Vec<f64>,
    /// Bin edges (`counts.len() + 1` of them) for uniform bins; empty for native bins.
    pub edges: Vec<f64>,
    /// Smallest value of the data (for a constant volume: the value itself).
    pub min: f64,
    /// Largest value of the data.
    pub max: f64,
    /// The bin layout.
    pub binning: Binning,
}

/// Edges of `n` equal bins over `[lo, hi]` exactly as `numpy.linspace` makes
/// them (`lo + i * step`, last edge set to `hi`); a constant range is widened
/// to `[lo - 0.5, hi + 0.5]` as `numpy.histogram` does.
pub fn uniform_edges(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let (lo, hi) = if lo == hi {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    };
    let step = (hi - lo) / n as f64;
    let mut e: Vec<f64> = (0..=n).map(|i| i as f64 * step + lo).collect();
    e[n] = hi;
    e
}

/// The uniform bin of `x` given `edges` (numpy's rule: estimate, then correct
/// against the edges; values equal to the last edge go to the last bin).
/// `x` must lie in `[edges[0], edges[n]]`.
#[inline]
pub fn uniform_bin(x: f64, edges: &[f64]) -> usize {
    let n = edges.len() - 1;
    let first = edges[0];
    let last = edges[n];
    let f = ((x - first) / (last - first)) * n as f64;
    let mut idx = if f <= 0.0 { 0 } else { (f as usize).min(n) };
    if idx == n {
        idx -= 1;
    }
    if x < edges[idx] && idx > 0 {
        idx -= 1;
    }
    if x >= edges[idx + 1] && idx != n - 1 {
        idx += 1;
    }
    idx
}

impl Histogram {
    /// A native histogram from counts of the integer values
    /// `first_value, first_value + 1, ...` (the `histogram_native` records of
    /// the references). Leading and trailing empty bins are kept as given.
    pub fn native_from_counts(
        first_value: i64,
        counts: Vec<u64>,
    ) -> Result<Histogram, ThresholdError> {
        let first = counts
            .iter()
            .position(|&c| c > 0)
            .ok_or(ThresholdError::Empty)?;
        let last = counts
            .iter()
            .rposition(|&c| c > 0)
            .ok_or(ThresholdError::Empty)?;
        let centres = (0..counts.len())
            .map(|i| (first_value + i as i64) as f64)
            .collect();
        Ok(Histogram {
            counts,
            centres,
            edges: Vec::new(),
            min: (first_value + first as i64) as f64,
            max: (first_value + last as i64) as f64,
            binning: Binning::Native,
        })
    }

    /// A uniform histogram from its counts and first/last edge (the
    /// `histogram_float256` records). The data range is taken to be the edges
    /// (which it is for any non-constant volume).
    pub fn uniform_from_counts(
        first_edge: f64,
        last_edge: f64,
        counts: Vec<u64>,
    ) -> Result<Histogram, ThresholdError> {
        if counts.is_empty()
            || !(first_edge.is_finite() && last_edge.is_finite() && first_edge < last_edge)
        {
            return Err(ThresholdError::Invalid(format!(
                "bad uniform histogram: {} bins over [{first_edge}, {last_edge}]",
                counts.len()
            )));
        }
        if counts.iter().all(|&c| c == 0) {
            return Err(ThresholdError::Empty);
        }
        let n = counts.len();
        let edges = uniform_edges(first_edge, last_edge, n);
        let centres = edges.windows(2).map(|w| (w[0] + w[1]) / 2.0).collect();
        Ok(Histogram {
            counts,
            centres,
            edges,
            min: first_edge,
            max: last_edge,
            binning: Binning::Uniform(n),
        })
    }

    /// The histogram of a volume. Native bins need an integer volume (u8, u16,
    /// i16); float volumes must use uniform bins. NaN or infinite voxels are
    /// an error. Counting runs in parallel.
    pub fn of_volume(v: &AnyVolume, binning: Binning) -> Result<Histogram, ThresholdError> {
        match (v, binning) {
            (AnyVolume::F32(_), Binning::Native) => Err(ThresholdError::Invalid(
                "native bins need an integer volume (u8, u16 or i16); this one is f32".into(),
            )),
            (AnyVolume::F32(f), Binning::Uniform(n)) => uniform_of_floats(f, n),
            (_, Binning::Native) => integer_histogram(v),
            (_, Binning::Uniform(n)) => {
                // Every voxel of one integer value lands in the same bin, so bin the
                // native histogram's values instead of every voxel.
                let native = integer_histogram(v)?;
                native.rebin_uniform(n)
            }
        }
    }

    /// Re-bin a native histogram into `n` uniform bins over its `[min, max]`.
    fn rebin_uniform(&self, n: usize) -> Result<Histogram, ThresholdError> {
        if n == 0 {
            return Err(ThresholdError::Invalid(
                "a histogram needs at least one bin".into(),
            ));
        }
        let edges = uniform_edges(self.min, self.max, n);
        let mut counts = vec![0u64; n];
        for (c, &x) in self.counts.iter().zip(&self.centres) {
            if *c > 0 {
                counts[uniform_bin(x, &edges)] += c;
            }
        }
        let centres = edges.windows(2).map(|w| (w[0] + w[1]) / 2.0).collect();
        Ok(Histogram {
            counts,
            centres,
            edges,
            min: self.min,
            max: self.max,
            binning: Binning::Uniform(n),
        })
    }

    /// Total number of voxels counted.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// The total weight (voxel count, as f64) and the weighted sum of the
    /// bin centres, summed in bin order (the moments Otsu and ISODATA split).
    pub fn weight_and_sum(&self) -> (f64, f64) {
        let w: f64 = self.counts.iter().map(|&c| c as f64).sum();
        let s: f64 = self
            .counts
            .iter()
            .zip(&self.centres)
            .map(|(&c, &x)| c as f64 * x)
            .sum();
        (w, s)
    }

    /// Number of bins that hold at least one voxel.
    pub fn nonempty_bins(&self) -> usize {
        self.counts.iter().filter(|&&c| c > 0).count()
    }

    /// True when every voxel has the same value.
    pub fn is_constant(&self) -> bool {
        self.min == self.max
    }

    /// `(#(v > t), #(v >= t))` from a native histogram (exact, since every bin
    /// is one value). For uniform bins the answer is exact only when `t` lies on
    /// a bin edge, so this errs for them: count on the volume instead.
    pub fn count_above(&self, t: f64) -> Result<(u64, u64), ThresholdError> {
        if self.binning != Binning::Native {
            return Err(ThresholdError::Invalid(
                "exact counts need native bins; count on the volume".into(),
            ));
        }
        let mut gt = 0;
        let mut ge = 0;
        for (&c, &x) in self.counts.iter().zip(&self.centres) {
            if x > t {
                gt += c;
            }
            if x >= t {
                ge += c;
            }
        }
        Ok((gt, ge))
    }
}

/// One bin per integer from the minimum to the maximum of an integer volume.
fn integer_histogram(v: &AnyVolume) -> Result<Histogram, ThresholdError> {
    let (offset, full) = match v {
        AnyVolume::U8(x) => (0i64, full_counts(x.data(), 256, |v| v as usize)),
        AnyVolume::U16(x) => (0, full_counts(x.data(), 65536, |v| v as usize)),
        AnyVolume::I16(x) => (
            -32768,
            full_counts(x.data(), 65536, |v| (v as i32 + 32768) as usize),
        ),
        AnyVolume::F32(_) => {
            return Err(ThresholdError::Invalid(
                "native bins need an integer volume".into(),
            ));
        }
    };
    let first = full
        .iter()
        .position(|&c| c > 0)
        .ok_or(ThresholdError::Empty)?;
    let last = full
        .iter()
        .rposition(|&c| c > 0)
        .ok_or(ThresholdError::Empty)?;
    Histogram::native_from_counts(offset + first as i64, full[first..=last].to_vec())
}

/// Counts of every possible value, counted in parallel chunks.
///
/// Each chunk counts into two interleaved u32 tables (even and odd voxels)
/// before adding them to the u64 total: runs of one grey level (a zero
/// background) would otherwise make every increment wait for the previous
/// one to the same counter, and u32 tables halve the cache footprint of
/// 65 536 bins. A chunk of 4 Mi voxels cannot overflow a u32 counter.
fn full_counts<T: Voxel>(data: &[T], n: usize, index: impl Fn(T) -> usize + Sync) -> Vec<u64> {
    const CHUNK: usize = 1 << 22;
    data.par_chunks(CHUNK)
        .fold(
            || (vec![0u64; n], vec![0u32; 2 * n]),
            |(mut acc, mut local), chunk| {
                local.fill(0);
                let (even, odd) = local.split_at_mut(n);
                let mut pairs = chunk.chunks_exact(2);
                for p in &mut pairs {
                    even[index(p[0])] += 1;
                    odd[index(p[1])] += 1;
                }
                for &v in pairs.remainder() {
                    even[index(v)] += 1;
                }
                for ((a, &e), &o) in acc.iter_mut().zip(even.iter()).zip(odd.iter()) {
                    *a += u64::from(e) + u64::from(o);
                }
                (acc, local)
            },
        )
        .map(|(acc, _)| acc)
        .reduce(
            || vec![0u64; n],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            },
        )
}

/// Uniform bins of a float volume (values taken as f64, as numpy does).
fn uniform_of_floats(v: &Volume<f32>, n: usize) -> Result<Histogram, ThresholdError> {
    if n == 0 {
        return Err(ThresholdError::Invalid(
            "a histogram needs at least one bin".into(),
        ));
    }
    if v.data().par_iter().any(|x| !x.is_finite()) {
        return Err(ThresholdError::NonFinite);
    }
    let (min, max) = v.min_max();
    let edges = uniform_edges(min, max, n);
    let counts = v
        .data()
        .par_chunks(1 << 20)
        .fold(
            || vec![0u64; n],
            |mut acc, chunk| {
                for &x in chunk {
                    acc[uniform_bin(x as f64, &edges)] += 1;
                }
                acc
            },
        )
        .reduce(
            || vec![0u64; n],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            },
        );
    let centres = edges.windows(2).map(|w| (w[0] + w[1]) / 2.0).collect();
    Ok(Histogram {
        counts,
        centres,
        edges,
        min,
        max,
        binning: Binning::Uniform(n),
    })
}

/// `(#(v > t), #(v >= t))` over the voxels of a volume, in parallel.
pub fn count_above(v: &AnyVolume, t: f64) -> (u64, u64) {
    fn go<T: Voxel>(d: &[T], t: f64) -> (u64, u64) {
        d.par_iter()
            .fold(
                || (0u64, 0u64),
                |(a, b), &x| {
                    let x = x.to_f64();
                    (a + (x > t) as u64, b + (x >= t) as u64)
                },
            )
            .reduce(|| (0, 0), |p, q| (p.0 + q.0, p.1 + q.1))
    }
    match v {
        AnyVolume::U8(x) => go(x.data(), t),
        AnyVolume::U16(x) => go(x.data(), t),
        AnyVolume::I16(x) => go(x.data(), t),
        AnyVolume::F32(x) => go(x.data(), t),
    }
}

/// The distinct values of a volume, ascending, with how often each occurs
/// (the input of exact 1-D k-means). Integer volumes use their native
/// histogram; float volumes are sorted (a copy of the data).
pub fn distinct_values(v: &AnyVolume) -> Result<(Vec<f64>, Vec<u64>), ThresholdError> {
    match v {
        AnyVolume::F32(f) => {
            if f.data().par_iter().any(|x| !x.is_finite()) {
                return Err(ThresholdError::NonFinite);
            }
            let mut s: Vec<f32> = f.data().to_vec();
            s.par_sort_unstable_by(|a, b| a.total_cmp(b));
            let mut vals: Vec<f64> = Vec::new();
            let mut wts: Vec<u64> = Vec::new();
            for x in s {
                // -0.0 and 0.0 are one value.
                let x = x as f64;
                match vals.last() {
                    Some(&l) if l == x => *wts.last_mut().expect("paired") += 1,
                    _ => {
                        vals.push(x);
                        wts.push(1);
                    }
                }
            }
            if vals.is_empty() {
                return Err(ThresholdError::Empty);
            }
            Ok((vals, wts))
        }
        _ => {
            let h = integer_histogram(v)?;
            let (counts, vals): (Vec<u64>, Vec<f64>) = h
                .counts
                .iter()
                .zip(&h.centres)
                .filter(|(c, _)| **c > 0)
                .map(|(&c, &x)| (c, x))
                .unzip();
            Ok((vals, counts))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Geometry, LengthUnit};

    fn vol_u8(data: Vec<u8>) -> AnyVolume {
        let g = Geometry::new([data.len(), 1, 1], [1.0; 3], LengthUnit::Micrometre).unwrap();
        AnyVolume::U8(Volume::from_vec(g, data).unwrap())
    }

    #[test]
    fn native_bins_span_min_to_max() {
        let h = Histogram::of_volume(&vol_u8(vec![3, 5, 5, 9]), Binning::Native).unwrap();
        assert_eq!(h.counts, vec![1, 0, 2, 0, 0, 0, 1]);
        assert_eq!(h.centres[0], 3.0);
        assert_eq!(h.centres[6], 9.0);
        assert_eq!(h.count_above(5.0).unwrap(), (1, 3));
    }

    #[test]
    fn uniform_bins_follow_numpy() {
        // numpy.histogram([0, 1, 2, 3, 4], bins=4, range=(0, 4)) -> [1, 1, 1, 2]
        let h = Histogram::of_volume(&vol_u8(vec![0, 1, 2, 3, 4]), Binning::Uniform(4)).unwrap();
        assert_eq!(h.counts, vec![1, 1, 1, 2]);
        assert_eq!(h.centres, vec![0.5, 1.5, 2.5, 3.5]);
        // A constant volume widens the range by 0.5 on each side.
        let c = Histogram::of_volume(&vol_u8(vec![7; 4]), Binning::Uniform(2)).unwrap();
        assert_eq!(c.edges, vec![6.5, 7.0, 7.5]);
        assert_eq!(c.counts, vec![0, 4]);
        assert!(c.is_constant());
    }

    #[test]
    fn distinct_values_of_floats() {
        let g = Geometry::new([4, 1, 1], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let v = AnyVolume::F32(Volume::from_vec(g.clone(), vec![2.5, -1.0, 2.5, 0.0]).unwrap());
        assert_eq!(
            distinct_values(&v).unwrap(),
            (vec![-1.0, 0.0, 2.5], vec![1, 1, 2])
        );
        let bad = AnyVolume::F32(Volume::from_vec(g, vec![f32::NAN, 0.0, 1.0, 2.0]).unwrap());
        assert_eq!(distinct_values(&bad), Err(ThresholdError::NonFinite));
        assert_eq!(count_above(&v, 0.0), (2, 3));
    }
}
