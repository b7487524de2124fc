//! Slices: the 2D planes of a volume along x, y or z.
//!
//! Slice `z=k` shows the (i, j) plane (u = i, v = j), `y=j` shows (i, k)
//! (u = i, v = k) and `x=i` shows (j, k) (u = j, v = k).
use crate::CoreError;
use serde::{Deserialize, Serialize};
use std::fmt;

/// An axis of the volume.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// The x axis (index i).
    X,
    /// The y axis (index j).
    Y,
    /// The z axis (index k).
    Z,
}

impl Axis {
    /// All axes in order x, y, z.
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// 0 for x, 1 for y, 2 for z.
    pub fn dim(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }

    /// The volume dims (as indices 0..3) that become the slice's u and v.
    pub fn in_plane(self) -> (usize, usize) {
        match self {
            Axis::X => (1, 2),
            Axis::Y => (0, 2),
            Axis::Z => (0, 1),
        }
    }

    /// Parse "x", "y" or "z" (case-insensitive).
    pub fn parse(s: &str) -> Result<Axis, CoreError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "x" => Ok(Axis::X),
            "y" => Ok(Axis::Y),
            "z" => Ok(Axis::Z),
            other => Err(CoreError::Invalid(format!(
                "unknown axis '{other}' (expected x, y or z)"
            ))),
        }
    }

    /// Voxel (i, j, k) of in-slice pixel (u, v) on slice `index`.
    #[inline]
    pub fn voxel(self, index: usize, u: usize, v: usize) -> [usize; 3] {
        match self {
            Axis::X => [index, u, v],
            Axis::Y => [u, index, v],
            Axis::Z => [u, v, index],
        }
    }

    /// (slice index, u, v) of voxel (i, j, k).
    #[inline]
    pub fn split(self, ijk: [usize; 3]) -> (usize, usize, usize) {
        match self {
            Axis::X => (ijk[0], ijk[1], ijk[2]),
            Axis::Y => (ijk[1], ijk[0], ijk[2]),
            Axis::Z => (ijk[2], ijk[0], ijk[1]),
        }
    }
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        })
    }
}

impl std::str::FromStr for Axis {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Axis::parse(s)
    }
}

/// A slice `(axis, index)` of a volume.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct SliceRef {
    /// Axis normal to the slice.
    pub axis: Axis,
    /// Index along the axis.
    pub index: usize,
}

impl fmt::Display for SliceRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}={}", self.axis, self.index)
    }
}

/// The sparse selection of slices between `first` and `last` (both
/// included): every `n`-th slice counted from `first` (`first`, `first + n`,
/// `first + 2n`, …) plus `last`, ascending and without repeats.
///
/// `n` is the spacing of the selected slices: `n = 1` selects every slice,
/// `n = 3` selects one and skips two. (Where a count of *skipped* slices `k`
/// is given, as in the interpolation study, `n = k + 1`.) `n = 0` is taken
/// as 1. Empty when `first > last`. This is how a sparse tracing is
/// simulated everywhere (contour extraction, the study, the campaign).
pub fn every_nth_slice(first: usize, last: usize, n: usize) -> Vec<usize> {
    if first > last {
        return Vec::new();
    }
    let mut keep: Vec<usize> = (first..=last).step_by(n.max(1)).collect();
    if keep.last() != Some(&last) {
        keep.push(last);
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::every_nth_slice;
    use proptest::prelude::*;

    #[test]
    fn every_nth_examples() {
        assert_eq!(every_nth_slice(4, 9, 3), vec![4, 7, 9]);
        assert_eq!(every_nth_slice(4, 7, 3), vec![4, 7]);
        assert_eq!(every_nth_slice(2, 2, 5), vec![2]);
        assert_eq!(every_nth_slice(1, 3, 1), vec![1, 2, 3]);
        assert_eq!(every_nth_slice(1, 3, 0), vec![1, 2, 3]);
        assert_eq!(every_nth_slice(5, 4, 2), Vec::<usize>::new());
    }

    proptest! {
        #[test]
        fn first_last_sorted_unique_spaced(first in 0usize..200, len in 0usize..200, n in 1usize..40) {
            let last = first + len;
            let s = every_nth_slice(first, last, n);
            prop_assert_eq!(s.first(), Some(&first));
            prop_assert_eq!(s.last(), Some(&last));
            for w in s.windows(2) {
                prop_assert!(w[0] < w[1]);
                prop_assert!(w[1] - w[0] <= n);
            }
            // Every n-th from the first is there.
            for k in (first..=last).step_by(n) {
                prop_assert!(s.contains(&k));
            }
            prop_assert!(s.len() <= len / n + 2);
        }
    }
}
