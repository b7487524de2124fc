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

/// Drawn slices from which one run of the leave-one-out ranks the methods
/// ([`Compact::held_out_to_rank`]).
pub const MANY_DRAWN: usize = 16;

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

    /// Pooled Dice of held-out predictions against the slices they predict.
    pub fn pooled_dice<'a>(&self, held: impl IntoIterator<Item = &'a HeldOut>) -> f64 {
        let mut acc = (0u64, 0u64);
        for h in held {
            let (a, b) = overlap(&h.predicted, &self.truth(h.pos));
            acc = (acc.0 + a, acc.1 + b);
        }
        pooled_dice(acc)
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
        self.held_out_at(method, like, 2)
    }

    /// Predict drawn slices from the drawn slices `stride` positions apart
    /// (an even stride): every `stride`-th drawn slice is kept (each offset
    /// in turn, and both ends), the others are erased, and the slices
    /// halfway between two kept ones are the predictions answered. With
    /// stride 2 that is every interior drawn slice, predicted across twice
    /// the tracer's gap; with stride 4, across four times it.
    pub fn held_out_at(
        &self,
        method: &dyn Interpolator,
        like: &SparseMask<'_>,
        stride: usize,
    ) -> Result<Vec<HeldOut>, InterpError> {
        self.held_out_runs(method, like, stride, stride)
    }

    /// [`Compact::held_out`] to rank methods: with [`MANY_DRAWN`] drawn
    /// slices or more, only the first of its two runs (the drawn slices at
    /// odd positions predicted, seven or more), at half the cost. On the
    /// development data no choice of method changed.
    pub fn held_out_to_rank(
        &self,
        method: &dyn Interpolator,
        like: &SparseMask<'_>,
    ) -> Result<Vec<HeldOut>, InterpError> {
        let runs = if self.real.len() >= MANY_DRAWN { 1 } else { 2 };
        self.held_out_runs(method, like, 2, runs)
    }

    /// [`Compact::held_out_at`] across four times the gap, to carry close
    /// errors to the real gap: with twice [`MANY_DRAWN`] drawn slices or
    /// more, the first two of its four runs (half the drawn slices
    /// predicted, fifteen or more), at half the cost. The four runs took
    /// longer than the whole ranking at twice the gap on a round nucleus
    /// traced on 52 slices; on the development data (`interslice bench`,
    /// every mask, k = 1..9) no choice of method changed. From
    /// [`MANY_DRAWN`] drawn slices on, the MNI white matter at k = 9 lost
    /// 0.004.
    pub fn held_out_to_extrapolate(
        &self,
        method: &dyn Interpolator,
        like: &SparseMask<'_>,
    ) -> Result<Vec<HeldOut>, InterpError> {
        let runs = if self.real.len() >= 2 * MANY_DRAWN {
            2
        } else {
            4
        };
        self.held_out_runs(method, like, 4, runs)
    }

    /// The first `runs` of the `stride` runs of [`Compact::held_out_at`].
    fn held_out_runs(
        &self,
        method: &dyn Interpolator,
        like: &SparseMask<'_>,
        stride: usize,
        runs: usize,
    ) -> Result<Vec<HeldOut>, InterpError> {
        let n = self.real.len();
        if n < stride + 1 {
            return Ok(Vec::new());
        }
        let half = stride / 2;
        let mut out = Vec::new();
        for offset in 0..runs.min(stride) {
            let kept: Vec<usize> = (0..n)
                .filter(|&i| i % stride == offset || i == 0 || i == n - 1)
                .collect();
            let held: Vec<usize> = kept
                .windows(2)
                .filter(|w| w[1] - w[0] == stride)
                .map(|w| w[0] + half)
                .collect();
            if held.is_empty() {
                continue;
            }
            let mut sparse = self.mask.clone();
            let (w, h) = sparse.slice_shape(self.axis);
            let empty = vec![false; w * h];
            for i in (0..n).filter(|i| !kept.contains(i)) {
                sparse.set_slice(self.axis, i, &empty)?;
            }
            let pred = method.interpolate(like.on(&sparse, &kept).only(&held))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::LengthUnit;

    /// A disc on every slice whose radius grows by one pixel a slice: the
    /// drawn slices 0, 2, 4, … 20 stacked compactly.
    fn growing_disc() -> (Mask, Vec<usize>) {
        let g = Geometry::new([48, 48, 21], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for z in 0..21usize {
            let r = 2.0 + z as f64;
            for y in 0..48usize {
                for x in 0..48usize {
                    let (dx, dy) = (x as f64 - 23.5, y as f64 - 23.5);
                    if dx * dx + dy * dy <= r * r {
                        m.set(x, y, z, true);
                    }
                }
            }
        }
        (m, (0..21).step_by(2).collect())
    }

    #[test]
    fn the_held_out_slices_are_halfway_between_kept_ones() {
        let (m, drawn) = growing_disc();
        let input = SparseMask::new(&m, Axis::Z, &drawn);
        let compact = Compact::of(&input).unwrap();
        let method = crate::by_name("shape-based").unwrap();
        // Stride 2: every interior drawn slice, once.
        let two = compact.held_out(method.as_ref(), &input).unwrap();
        assert_eq!(
            two.iter().map(|h| h.pos).collect::<Vec<_>>(),
            (1..10).collect::<Vec<_>>()
        );
        // Stride 4: the slices two positions from a kept slice on each side,
        // each once (11 drawn slices: positions 2..=8).
        let four = compact.held_out_at(method.as_ref(), &input, 4).unwrap();
        assert_eq!(
            four.iter().map(|h| h.pos).collect::<Vec<_>>(),
            (2..=8).collect::<Vec<_>>()
        );
        // A cone is what blending carries exactly: the predictions are the
        // truth up to the pixels of its outline, across four gaps as across two.
        for held in [&two, &four] {
            let mut acc = (0, 0);
            for h in held.iter() {
                let (a, b) = overlap(&h.predicted, &compact.truth(h.pos));
                assert!(pooled_dice((a, b)) > 0.9, "slice {}", h.pos);
                acc = (acc.0 + a, acc.1 + b);
            }
            assert!(pooled_dice(acc) > 0.97, "{}", pooled_dice(acc));
        }
        // Ranking: with fewer than MANY_DRAWN drawn slices, both runs.
        let rank = compact.held_out_to_rank(method.as_ref(), &input).unwrap();
        assert_eq!(
            rank.iter().map(|h| h.pos).collect::<Vec<_>>(),
            (1..10).collect::<Vec<_>>()
        );
        // Too few drawn slices for the stride: nothing.
        let short = SparseMask::new(&m, Axis::Z, &drawn[..4]);
        let c = Compact::of(&short).unwrap();
        assert!(
            c.held_out_at(method.as_ref(), &short, 4)
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn with_many_drawn_slices_ranking_holds_out_the_odd_positions_only() {
        // Every slice of the growing disc drawn: 21 compact slices.
        let (m, _) = growing_disc();
        let drawn: Vec<usize> = (0..21).collect();
        assert!(drawn.len() >= MANY_DRAWN);
        let input = SparseMask::new(&m, Axis::Z, &drawn);
        let compact = Compact::of(&input).unwrap();
        let method = crate::by_name("shape-based").unwrap();
        let rank = compact.held_out_to_rank(method.as_ref(), &input).unwrap();
        assert_eq!(
            rank.iter().map(|h| h.pos).collect::<Vec<_>>(),
            (1..20).step_by(2).collect::<Vec<_>>()
        );
        // The same predictions as the full leave-one-out gives those slices.
        let all = compact.held_out(method.as_ref(), &input).unwrap();
        for h in &rank {
            let full = all.iter().find(|a| a.pos == h.pos).unwrap();
            assert_eq!(h.predicted, full.predicted, "slice {}", h.pos);
        }
    }
}
