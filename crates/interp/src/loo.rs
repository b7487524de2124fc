//! Leave-one-out on the tracer's own drawn slices: every interior drawn slice
//! is predicted from its drawn neighbours, so a method (or a weight) can be
//! chosen per volume by how well it recovers slices whose truth is known.
//!
//! The drawn slices are first stacked into a *compact* volume (one slice per
//! drawn slice, the slice spacing set to the mean gap between them), then
//! interpolated twice: once from the even positions (predicting the odd
//! ones) and once from the odd positions plus both ends (predicting the even
//! ones). Each prediction therefore spans two real gaps, about `2k + 1`
//! skipped slices when the tracer skipped `k`; the compact stack makes both
//! runs cost about as much as interpolating `n` slices, not the volume.
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::{Axis, Geometry, Mask, Volume, Voxel};

/// The drawn slices of a volume stacked along the same axis.
pub struct Compact {
    /// The stacked tracing (every slice is a drawn slice).
    pub mask: Mask,
    /// The axis of the stack (the drawn axis).
    pub axis: Axis,
    /// Real slice index of every compact slice.
    pub real: Vec<usize>,
}

/// One held-out drawn slice and its prediction.
pub struct HeldOut {
    /// Position in the compact stack (= in the drawn list).
    pub pos: usize,
    /// The predicted slice, row-major in the slice plane.
    pub predicted: Vec<bool>,
}

/// Stack the slices `real` of `vol` along `axis`, the slice spacing being the
/// mean gap (at least one slice) times the real spacing.
pub fn stack<T: Voxel>(
    vol: &Volume<T>,
    axis: Axis,
    real: &[usize],
) -> Result<Volume<T>, InterpError> {
    let g = vol.geometry();
    let mut dims = g.dims;
    let mut spacing = g.spacing;
    let ax = axis.dim();
    dims[ax] = real.len();
    let span = real.last().copied().unwrap_or(0) - real.first().copied().unwrap_or(0);
    let gap = span as f64 / (real.len().max(2) - 1) as f64;
    spacing[ax] *= gap.max(1.0);
    let geometry = Geometry::new(dims, spacing, g.unit)?;
    let mut out: Volume<T> = Volume::zeros(geometry);
    for (c, &r) in real.iter().enumerate() {
        out.set_slice(axis, c, &vol.slice(axis, r)?)?;
    }
    Ok(out)
}

impl Compact {
    /// The compact stack of the drawn slices of `input`.
    pub fn of(input: &SparseMask<'_>) -> Result<Compact, InterpError> {
        Ok(Compact {
            mask: stack(input.mask, input.axis, input.drawn)?,
            axis: input.axis,
            real: input.drawn.to_vec(),
        })
    }

    /// The tracing of compact slice `pos`.
    pub fn truth(&self, pos: usize) -> Vec<bool> {
        self.mask.slice(self.axis, pos).expect("compact index")
    }

    /// Real slices between compact slice `pos` and its nearest kept
    /// neighbour in the leave-one-out runs (the distance the prediction spans).
    pub fn reach(&self, pos: usize) -> usize {
        let r = &self.real;
        (r[pos] - r[pos - 1]).min(r[pos + 1] - r[pos])
    }

    /// Predict every interior drawn slice from its neighbours with `method`,
    /// the runs being like `like` (the input the stack was made of: its
    /// cancel, cached maps and box). Empty when there are fewer than three
    /// drawn slices.
    pub fn held_out(
        &self,
        method: &dyn Interpolator,
        like: &SparseMask<'_>,
    ) -> Result<Vec<HeldOut>, InterpError> {
        let n = self.real.len();
        if n < 3 {
            return Ok(Vec::new());
        }
        let mut out = Vec::new();
        for parity in [0usize, 1] {
            let kept: Vec<usize> = (0..n)
                .filter(|&i| i % 2 == parity || i == 0 || i == n - 1)
                .collect();
            let held: Vec<usize> = (1..n - 1).filter(|i| !kept.contains(i)).collect();
            if held.is_empty() {
                continue;
            }
            let mut sparse = self.mask.clone();
            for &h in &held {
                let (w, hh) = sparse.slice_shape(self.axis);
                sparse.set_slice(self.axis, h, &vec![false; w * hh])?;
            }
            let pred = method.interpolate(like.on(&sparse, &kept))?;
            for h in held {
                out.push(HeldOut {
                    pos: h,
                    predicted: pred.slice(self.axis, h)?,
                });
            }
        }
        out.sort_by_key(|h| h.pos);
        Ok(out)
    }
}

/// Overlap counts `(2|A ∩ B|, |A| + |B|)` of two slices, to pool into one Dice.
pub fn overlap(a: &[bool], b: &[bool]) -> (u64, u64) {
    let mut inter = 0u64;
    let mut sum = 0u64;
    for (&x, &y) in a.iter().zip(b) {
        inter += u64::from(x && y);
        sum += u64::from(x) + u64::from(y);
    }
    (2 * inter, sum)
}

/// Pooled Dice of summed overlap counts; 1 when both are empty.
pub fn pooled_dice((num, den): (u64, u64)) -> f64 {
    if den == 0 {
        1.0
    } else {
        num as f64 / den as f64
    }
}
