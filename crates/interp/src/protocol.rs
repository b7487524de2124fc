//! The benchmark protocol of the interpolation study, on one binary mask:
//! the first and last non-empty slices along the axis and every `(k + 1)`-th
//! slice from the first are drawn, every other slice is erased, and a result
//! is scored by Dice on the *skipped* slices only (the slices strictly
//! between the first and last drawn ones that were not drawn) and by Dice on
//! the whole volume (which also counts what spills past the outermost drawn
//! slices).
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::{Axis, Geometry, Mask, Volume, Voxel};

/// The drawn slices of `mask` for `k` skipped slices; `None` when the mask
/// shows on fewer than two slices.
pub fn drawn_for_skip(mask: &Mask, axis: Axis, k: usize) -> Option<Vec<usize>> {
    let n = mask.slice_count(axis);
    let nonempty: Vec<usize> = (0..n)
        .filter(|&s| mask.view(axis, s).expect("in range").iter().any(|x| x))
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
    let (mut inter, mut sum) = (0u64, 0u64);
    for &s in slices {
        let (x, y) = (
            a.view(axis, s).expect("in range"),
            b.view(axis, s).expect("in range"),
        );
        for (p, q) in x.iter().zip(y.iter()) {
            inter += u64::from(p && q);
            sum += u64::from(p) + u64::from(q);
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
    let sparse = sparse_of(truth, axis, &drawn);
    let t = std::time::Instant::now();
    let out = method.interpolate(SparseMask::new(&sparse, axis, &drawn))?;
    let seconds = t.elapsed().as_secs_f64();
    let all: Vec<usize> = (0..truth.slice_count(axis)).collect();
    Ok(Some(Score {
        skipped: dice_on(&out, truth, axis, &skipped(&drawn)),
        whole: dice_on(&out, truth, axis, &all),
        seconds,
    }))
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
