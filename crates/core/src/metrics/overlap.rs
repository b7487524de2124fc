//! Voxel-count (confusion-matrix) metrics: TP, FP, FN, TN and the ratios built on them.
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Voxels per parallel work item of the counting passes (64 Ki voxels: large
/// enough to amortise scheduling, small enough to balance two cores).
const CHUNK: usize = 1 << 16;

/// The confusion matrix of a segmentation against a ground truth for one label.
///
/// `tp`: foreground in both; `fp`: foreground in the segmentation only; `fn_`:
/// foreground in the ground truth only; `tn`: background in both.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Confusion {
    /// True positives.
    pub tp: u64,
    /// False positives.
    pub fp: u64,
    /// False negatives (`fn` is a keyword; serialised as `fn`).
    #[serde(rename = "fn")]
    pub fn_: u64,
    /// True negatives.
    pub tn: u64,
}

/// `num / den`, or `None` when `den` is 0 (the 0/0 cases of empty masks).
fn ratio(num: u64, den: u64) -> Option<f64> {
    (den != 0).then(|| num as f64 / den as f64)
}

impl Confusion {
    /// The counts from the foreground sizes of both masks and their intersection.
    pub fn from_counts(total: u64, gt: u64, seg: u64, both: u64) -> Confusion {
        Confusion {
            tp: both,
            fp: seg - both,
            fn_: gt - both,
            tn: total - (gt + seg - both),
        }
    }

    /// Number of voxels.
    pub fn total(&self) -> u64 {
        self.tp + self.fp + self.fn_ + self.tn
    }

    /// Foreground voxels of the ground truth (`tp + fn`).
    pub fn gt_voxels(&self) -> u64 {
        self.tp + self.fn_
    }

    /// Foreground voxels of the segmentation (`tp + fp`).
    pub fn seg_voxels(&self) -> u64 {
        self.tp + self.fp
    }

    /// Dice = 2TP / (2TP + FP + FN); `None` when both masks are empty.
    pub fn dice(&self) -> Option<f64> {
        ratio(2 * self.tp, 2 * self.tp + self.fp + self.fn_)
    }

    /// Jaccard = TP / (TP + FP + FN); `None` when both masks are empty.
    pub fn jaccard(&self) -> Option<f64> {
        ratio(self.tp, self.tp + self.fp + self.fn_)
    }

    /// Sensitivity (recall) = TP / (TP + FN); `None` when the ground truth is empty.
    pub fn sensitivity(&self) -> Option<f64> {
        ratio(self.tp, self.tp + self.fn_)
    }

    /// Specificity = TN / (TN + FP); `None` when the ground truth fills the volume.
    pub fn specificity(&self) -> Option<f64> {
        ratio(self.tn, self.tn + self.fp)
    }

    /// Precision = TP / (TP + FP); `None` when the segmentation is empty.
    pub fn precision(&self) -> Option<f64> {
        ratio(self.tp, self.tp + self.fp)
    }

    /// Volume similarity (Taha & Hanbury 2015) = 1 − |FN − FP| / (2TP + FP + FN);
    /// `None` when both masks are empty.
    pub fn volume_similarity(&self) -> Option<f64> {
        let den = 2 * self.tp + self.fp + self.fn_;
        (den != 0).then(|| 1.0 - self.fn_.abs_diff(self.fp) as f64 / den as f64)
    }
}

/// Count the confusion matrix of the voxels equal to `fg` in one parallel pass
/// over both arrays, without building masks.
///
/// # Panics
/// If the slices differ in length (callers check the geometry first).
pub fn confusion_of<T: Copy + PartialEq + Sync>(gt: &[T], seg: &[T], fg: T) -> Confusion {
    confusion_where(gt, seg, |x| x == fg)
}

/// Count the confusion matrix of the voxels for which `is_fg` holds, in one
/// parallel pass over both arrays.
///
/// # Panics
/// If the slices differ in length (callers check the geometry first).
pub fn confusion_where<T: Copy + Sync>(
    gt: &[T],
    seg: &[T],
    is_fg: impl Fn(T) -> bool + Sync,
) -> Confusion {
    assert_eq!(
        gt.len(),
        seg.len(),
        "volumes must have the same number of voxels"
    );
    let (ng, ns, both) = gt
        .par_chunks(CHUNK)
        .zip(seg.par_chunks(CHUNK))
        .map(|(a, b)| count_chunk(a, b, &is_fg))
        .reduce(|| (0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
    Confusion::from_counts(gt.len() as u64, ng, ns, both)
}

/// Lanes of the counting loop: a vector register of `u8`.
const LANES: usize = 32;

/// `(gt, seg, both)` foreground counts of two equal-length runs. The counts
/// go to `u8` lane accumulators (one compare and add a voxel in a vector
/// register), flushed to `u64` before 255 steps could overflow them.
#[inline]
fn count_chunk<T: Copy>(a: &[T], b: &[T], is_fg: &impl Fn(T) -> bool) -> (u64, u64, u64) {
    let (mut ng, mut ns, mut both) = (0u64, 0u64, 0u64);
    let flush = LANES * 255;
    for (x, y) in a.chunks(flush).zip(b.chunks(flush)) {
        let mut lg = [0u8; LANES];
        let mut ls = [0u8; LANES];
        let mut lb = [0u8; LANES];
        let xs = x.chunks_exact(LANES);
        let ys = y.chunks_exact(LANES);
        let (xt, yt) = (xs.remainder(), ys.remainder());
        for (xc, yc) in xs.zip(ys) {
            for l in 0..LANES {
                let p = u8::from(is_fg(xc[l]));
                let q = u8::from(is_fg(yc[l]));
                lg[l] += p;
                ls[l] += q;
                lb[l] += p & q;
            }
        }
        for (&p, &q) in xt.iter().zip(yt) {
            let (p, q) = (u64::from(is_fg(p)), u64::from(is_fg(q)));
            ng += p;
            ns += q;
            both += p & q;
        }
        let sum = |v: [u8; LANES]| v.iter().map(|&c| u64::from(c)).sum::<u64>();
        ng += sum(lg);
        ns += sum(ls);
        both += sum(lb);
    }
    (ng, ns, both)
}

/// Per-label voxel counts of two label volumes and of the voxels where they
/// agree, from one parallel pass: enough for the confusion matrix of every label.
#[derive(Debug, Clone)]
pub struct LabelHistograms {
    total: u64,
    gt: Vec<u64>,
    seg: Vec<u64>,
    both: Vec<u64>,
}

impl LabelHistograms {
    /// Count both label volumes (equal lengths) in one pass.
    ///
    /// # Panics
    /// If the slices differ in length (callers check the geometry first).
    pub fn count(gt: &[u16], seg: &[u16]) -> LabelHistograms {
        assert_eq!(
            gt.len(),
            seg.len(),
            "volumes must have the same number of voxels"
        );
        let zero = || (vec![0u64; 65536], vec![0u64; 65536], vec![0u64; 65536]);
        let (g, s, b) = gt
            .par_chunks(CHUNK)
            .zip(seg.par_chunks(CHUNK))
            .fold(zero, |(mut g, mut s, mut b), (x, y)| {
                for (&p, &q) in x.iter().zip(y) {
                    g[p as usize] += 1;
                    s[q as usize] += 1;
                    if p == q {
                        b[p as usize] += 1;
                    }
                }
                (g, s, b)
            })
            .reduce(zero, |(mut g, mut s, mut b), (g2, s2, b2)| {
                for (x, y) in g.iter_mut().zip(g2) {
                    *x += y;
                }
                for (x, y) in s.iter_mut().zip(s2) {
                    *x += y;
                }
                for (x, y) in b.iter_mut().zip(b2) {
                    *x += y;
                }
                (g, s, b)
            });
        LabelHistograms {
            total: gt.len() as u64,
            gt: g,
            seg: s,
            both: b,
        }
    }

    /// Non-zero labels present in either volume, ascending.
    pub fn labels(&self) -> Vec<u16> {
        (1..=u16::MAX)
            .filter(|&l| self.gt[l as usize] > 0 || self.seg[l as usize] > 0)
            .collect()
    }

    /// The confusion matrix of `label`.
    pub fn confusion(&self, label: u16) -> Confusion {
        let l = label as usize;
        Confusion::from_counts(self.total, self.gt[l], self.seg[l], self.both[l])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn one_pass_counts_match_a_naive_count(
            pairs in proptest::collection::vec((0u16..4, 0u16..4), 0..3000),
            label in 0u16..4,
        ) {
            let (gt, seg): (Vec<u16>, Vec<u16>) = pairs.into_iter().unzip();
            let c = confusion_of(&gt, &seg, label);
            let mut want = Confusion::default();
            for (&a, &b) in gt.iter().zip(&seg) {
                match (a == label, b == label) {
                    (true, true) => want.tp += 1,
                    (false, true) => want.fp += 1,
                    (true, false) => want.fn_ += 1,
                    (false, false) => want.tn += 1,
                }
            }
            prop_assert_eq!(c, want);
            prop_assert_eq!(LabelHistograms::count(&gt, &seg).confusion(label), want);
        }
    }

    /// Runs longer than a lane flush and a parallel chunk, all foreground
    /// (every lane counter at its limit) or patterned, against a naive count.
    #[test]
    fn lane_counters_flush_before_overflow() {
        let n = CHUNK + LANES * 255 * 2 + 37;
        let ones = vec![1u8; n];
        assert_eq!(
            confusion_of(&ones, &ones, 1),
            Confusion::from_counts(n as u64, n as u64, n as u64, n as u64)
        );
        let a: Vec<u8> = (0..n).map(|i| u8::from((i * 7919) % 5 < 2)).collect();
        let b: Vec<u8> = (0..n).map(|i| u8::from((i * 104_729) % 3 == 0)).collect();
        let count = |f: &dyn Fn(usize) -> bool| (0..n).filter(|&i| f(i)).count() as u64;
        let want = Confusion::from_counts(
            n as u64,
            count(&|i| a[i] == 1),
            count(&|i| b[i] == 1),
            count(&|i| a[i] == 1 && b[i] == 1),
        );
        assert_eq!(confusion_of(&a, &b, 1), want);
        assert_eq!(
            confusion_of(&a[..LANES * 255 + 31], &b[..LANES * 255 + 31], 1).total(),
            (LANES * 255 + 31) as u64
        );
    }

    #[test]
    fn ratios_and_empty_rules() {
        let c = Confusion {
            tp: 6,
            fp: 2,
            fn_: 4,
            tn: 8,
        };
        assert_eq!(c.dice(), Some(12.0 / 18.0));
        assert_eq!(c.jaccard(), Some(6.0 / 12.0));
        assert_eq!(c.sensitivity(), Some(0.6));
        assert_eq!(c.specificity(), Some(0.8));
        assert_eq!(c.precision(), Some(0.75));
        assert_eq!(c.volume_similarity(), Some(1.0 - 2.0 / 18.0));
        let empty = Confusion {
            tp: 0,
            fp: 0,
            fn_: 0,
            tn: 10,
        };
        assert_eq!(empty.dice(), None);
        assert_eq!(empty.jaccard(), None);
        assert_eq!(empty.sensitivity(), None);
        assert_eq!(empty.precision(), None);
        assert_eq!(empty.volume_similarity(), None);
        assert_eq!(empty.specificity(), Some(1.0));
        let full = Confusion {
            tp: 5,
            fp: 0,
            fn_: 1,
            tn: 0,
        };
        assert_eq!(full.specificity(), None);
    }
}
