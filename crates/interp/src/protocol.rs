//! The benchmark protocol of the interpolation study, on one binary mask:
//! the first and last non-empty slices along the axis and every `(k + 1)`-th
//! slice from the first are drawn, every other slice is erased, and a result
//! is scored by Dice on the *skipped* slices only (the slices strictly
//! between the first and last drawn ones that were not drawn) and by Dice on
//! the whole volume (which also counts what spills past the outermost drawn
//! slices).
//!
//! A label volume (every nucleus of a segmentation its own label) runs the
//! same way on its foreground's slices, every label interpolated on its own
//! ([`crate::interpolate_labels`]), and is scored by the label-matched Dice
//! ([`label_dice_on`]).
use crate::slices::shows_on;
use crate::{InterpError, Interpolator, SparseMask, interpolate_labels};
use interslice_core::{Axis, Geometry, LabelVolume, Mask, Volume, Voxel};

/// The drawn slices of `mask` for `k` skipped slices; `None` when the mask
/// shows on fewer than two slices.
pub fn drawn_for_skip(mask: &Mask, axis: Axis, k: usize) -> Option<Vec<usize>> {
    let n = mask.slice_count(axis);
    let nonempty: Vec<usize> = (0..n)
        .filter(|&s| shows_on(mask, axis, s).expect("in range"))
        .collect();
    let (&first, &last) = (nonempty.first()?, nonempty.last()?);
    (last > first).then(|| drawn_for(first, last, k))
}

/// The drawn slices of a run for `k` skipped slices: `first`, every
/// `(k + 1)`-th after it, and `last`
/// ([`interslice_core::slice::every_nth_slice`] with `n = k + 1`).
pub fn drawn_for(first: usize, last: usize, k: usize) -> Vec<usize> {
    interslice_core::slice::every_nth_slice(first, last, k + 1)
}

/// `mask` (a mask or a label volume) with every slice but `drawn` erased.
pub fn sparse_of<T: Voxel>(mask: &Volume<T>, axis: Axis, drawn: &[usize]) -> Volume<T> {
    let mut out: Volume<T> = Volume::zeros(mask.geometry().clone());
    for &d in drawn {
        out.set_slice(axis, d, &mask.slice(axis, d).expect("in range"))
            .expect("same shape");
    }
    out
}

/// Dice of `a` against `b` over the slices `slices` only (1 when both are empty there).
pub fn dice_on(a: &Mask, b: &Mask, axis: Axis, slices: &[usize]) -> f64 {
    dice_where(a, b, axis, slices, |x| x)
}

/// Label-matched Dice of the label volume `a` against `b` over the slices
/// `slices`: `2 Σ_l |A_l ∩ B_l| / (|A > 0| + |B > 0|)`, so a voxel counts as
/// agreeing only where both hold the same label (a nucleus painted with its
/// neighbour's label is wrong twice). 1 when both are empty there.
pub fn label_dice_on(a: &LabelVolume, b: &LabelVolume, axis: Axis, slices: &[usize]) -> f64 {
    dice_where(a, b, axis, slices, |l| l != 0)
}

/// Dice over `slices` of the voxels where `inside`, a voxel of both
/// agreeing where it holds the same value.
fn dice_where<T: Voxel + PartialEq>(
    a: &Volume<T>,
    b: &Volume<T>,
    axis: Axis,
    slices: &[usize],
    inside: impl Fn(T) -> bool,
) -> f64 {
    let (mut inter, mut sum) = (0u64, 0u64);
    for &s in slices {
        let (x, y) = (
            a.view(axis, s).expect("in range"),
            b.view(axis, s).expect("in range"),
        );
        for (p, q) in x.iter().zip(y.iter()) {
            inter += u64::from(inside(p) && p == q);
            sum += u64::from(inside(p)) + u64::from(inside(q));
        }
    }
    if sum == 0 {
        1.0
    } else {
        2.0 * inter as f64 / sum as f64
    }
}

/// The skipped slices of a drawn set: strictly between the first and last
/// drawn slices, not drawn.
pub fn skipped(drawn: &[usize]) -> Vec<usize> {
    let (Some(&a), Some(&b)) = (drawn.first(), drawn.last()) else {
        return Vec::new();
    };
    (a..=b)
        .filter(|s| drawn.binary_search(s).is_err())
        .collect()
}

/// One scored run.
#[derive(Debug, Clone, Copy)]
pub struct Score {
    /// Dice on the skipped slices.
    pub skipped: f64,
    /// Dice on the whole volume.
    pub whole: f64,
    /// Wall time of the interpolation (s).
    pub seconds: f64,
}

/// Run `method` on `truth` with `k` skipped slices and score it; `None`
/// when the mask shows on fewer than two slices.
pub fn score(
    method: &dyn Interpolator,
    truth: &Mask,
    axis: Axis,
    k: usize,
) -> Result<Option<Score>, InterpError> {
    let Some(drawn) = drawn_for_skip(truth, axis, k) else {
        return Ok(None);
    };
    scored(truth, axis, &drawn, dice_on, |sparse| {
        method.interpolate(SparseMask::new(sparse, axis, &drawn))
    })
    .map(Some)
}

/// [`score`] on a label volume: the drawn slices those of its foreground,
/// every label interpolated on its own, scored by [`label_dice_on`]; `None`
/// when the foreground shows on fewer than two slices.
pub fn score_labels(
    method: &dyn Interpolator,
    truth: &LabelVolume,
    axis: Axis,
    k: usize,
) -> Result<Option<Score>, InterpError> {
    let Some(drawn) = drawn_for_skip(&truth.map(|l| l > 0), axis, k) else {
        return Ok(None);
    };
    scored(truth, axis, &drawn, label_dice_on, |sparse| {
        interpolate_labels(method, sparse, axis, &drawn)
    })
    .map(Some)
}

/// `truth` kept on `drawn` only, filled by `run` (timed) and scored by
/// `dice` on the skipped slices and on the whole volume.
fn scored<T: Voxel>(
    truth: &Volume<T>,
    axis: Axis,
    drawn: &[usize],
    dice: fn(&Volume<T>, &Volume<T>, Axis, &[usize]) -> f64,
    run: impl FnOnce(&Volume<T>) -> Result<Volume<T>, InterpError>,
) -> Result<Score, InterpError> {
    let sparse = sparse_of(truth, axis, drawn);
    let t = std::time::Instant::now();
    let out = run(&sparse)?;
    let seconds = t.elapsed().as_secs_f64();
    let all: Vec<usize> = (0..truth.slice_count(axis)).collect();
    Ok(Score {
        skipped: dice(&out, truth, axis, &skipped(drawn)),
        whole: dice(&out, truth, axis, &all),
        seconds,
    })
}

/// The box of `mask`'s voxels grown by `margin` (clamped to the volume), as
/// `[lo, hi)` per axis; `None` for an empty mask.
pub fn bounding_box(mask: &Mask, margin: usize) -> Option<[[usize; 2]; 3]> {
    let d = mask.dims();
    let mut lo = d;
    let mut hi = [0usize; 3];
    for (idx, &x) in mask.data().iter().enumerate() {
        if x {
            let p = mask.geometry().ijk(idx);
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a] + 1);
            }
        }
    }
    if hi[0] == 0 {
        return None;
    }
    Some(std::array::from_fn(|a| {
        [lo[a].saturating_sub(margin), (hi[a] + margin).min(d[a])]
    }))
}

/// The sub-volume `bbox` of `v` (spacing and unit kept, origin at 0).
pub fn crop<T: Voxel>(v: &Volume<T>, bbox: [[usize; 2]; 3]) -> Result<Volume<T>, InterpError> {
    let g = v.geometry();
    let dims = std::array::from_fn(|a| bbox[a][1] - bbox[a][0]);
    let geometry = Geometry::new(dims, g.spacing, g.unit)?;
    let mut data = Vec::with_capacity(geometry.len());
    for k in bbox[2][0]..bbox[2][1] {
        for j in bbox[1][0]..bbox[1][1] {
            for i in bbox[0][0]..bbox[0][1] {
                data.push(v.get(i, j, k));
            }
        }
    }
    Ok(Volume::from_vec(geometry, data)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nearest::Nearest;

    /// Two labels side by side on every slice of a 12 × 6 × 9 volume.
    fn two_labels() -> LabelVolume {
        let g = Geometry::new([12, 6, 9], [1.0; 3], Default::default()).unwrap();
        let mut v: LabelVolume = Volume::zeros(g);
        for z in 0..9 {
            for y in 1..5 {
                for x in 1..5 {
                    v.set(x, y, z, 1);
                    v.set(x + 6, y, z, 2);
                }
            }
        }
        v
    }

    #[test]
    fn label_dice_counts_a_voxel_only_where_the_labels_agree() {
        let truth = two_labels();
        let all: Vec<usize> = (0..9).collect();
        assert_eq!(label_dice_on(&truth, &truth, Axis::Z, &all), 1.0);
        // The two labels swapped: the same foreground, no agreement.
        let swapped = truth.map(|l| [0, 2, 1][l as usize]);
        assert_eq!(label_dice_on(&swapped, &truth, Axis::Z, &all), 0.0);
        // Label 2 missing on slice 4: 16 of 32 voxels there, 16 of 16 found.
        let mut half = truth.clone();
        half.set_slice(
            Axis::Z,
            4,
            &truth
                .map(|l| if l == 2 { 0 } else { l })
                .slice(Axis::Z, 4)
                .unwrap(),
        )
        .unwrap();
        assert!((label_dice_on(&half, &truth, Axis::Z, &[4]) - 32.0 / 48.0).abs() < 1e-12);
        // Both empty there: 1.
        let empty: LabelVolume = Volume::zeros(truth.geometry().clone());
        assert_eq!(label_dice_on(&empty, &empty, Axis::Z, &[0]), 1.0);
    }

    #[test]
    fn label_volumes_score_on_their_foregrounds_drawn_slices() {
        // Prisms: every method that copies a drawn slice is exact.
        let truth = two_labels();
        let s = score_labels(&Nearest, &truth, Axis::Z, 3).unwrap().unwrap();
        assert_eq!((s.skipped, s.whole), (1.0, 1.0));
        // A label volume on one slice only: nothing to score.
        let mut flat: LabelVolume = Volume::zeros(truth.geometry().clone());
        flat.set(2, 2, 4, 1);
        assert!(score_labels(&Nearest, &flat, Axis::Z, 3).unwrap().is_none());
    }
}
