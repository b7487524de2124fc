//! The box one label's interpolation runs in.
//!
//! A structure usually fills a small part of its volume (a nucleus in a 256³
//! cell, a lesion in a CT), yet a method given the whole volume computes
//! distance maps and blends over every slice. The shape methods cannot put a
//! voxel outside
//! - the in-plane bounding box of the label's drawn outlines (signed-distance
//!   blends and monotone cubics are positive where every outline is, copies
//!   and aligned shapes stay between them), nor
//! - past the drawn slice after the last drawn slice that shows the label,
//!   nor before the one before the first (a gap between two drawn slices
//!   where the label is absent stays empty: the invariant of every method),
//!
//! so the runner hands them that box plus a margin of background and
//! [`AXIS_SLICES`] more drawn slices along the axis, and pastes the result
//! back. How wide the margin is depends on what the method reads
//! ([`BoxReach`]): a method whose every value on a pixel comes from that
//! pixel's distances to the outlines ([`BoxReach::Outline`]) needs
//! [`MARGIN`], and gives the whole volume's result voxel for voxel; one that
//! follows objects as they move between drawn slices ([`BoxReach::Drift`],
//! `shape-aligned` and so the default) reads as far as they move, and gets
//! that drift three times over on top. The claim is checked, not trusted: a
//! result that reaches the box's in-plane sides (where the volume goes on) is
//! computed again on the whole volume. Tests compare both ways.
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::{Axis, Geometry, Mask, Volume, Voxel};

/// Background voxels kept around the drawn outlines, in-plane.
pub const MARGIN: usize = 2;

/// What a method reads past the drawn outlines of a label
/// ([`crate::Interpolator::box_reach`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoxReach {
    /// The whole volume: never run on a box (image-aware and mesh methods).
    Whole,
    /// Each pixel's own distances to the outlines: the box plus [`MARGIN`]
    /// gives the whole volume's result exactly.
    Outline,
    /// Distances sampled where the objects move to between drawn slices:
    /// the box grows by three times the largest step of an outline's box
    /// between consecutive drawn slices ([`drift`]).
    Drift,
}

/// Drawn slices kept beyond the first and last drawn slice that show the
/// label: the cubic slopes of `shape-cubic` and `shape-aligned` read one
/// drawn slice past a gap, so the gap next to the label's last drawn slice
/// sees the same neighbours as in the whole volume.
pub const AXIS_SLICES: usize = 2;

/// A box of the volume: first voxel and size, per dimension (x, y, z).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LabelBox {
    /// First voxel.
    pub lo: [usize; 3],
    /// Voxels along x, y, z.
    pub dims: [usize; 3],
}

/// In-plane extent `[u_lo, u_hi, v_lo, v_hi]` of the pixels inside, on a
/// slice `w` pixels wide; `None` when there are none.
pub(crate) fn extent(inside: &[bool], w: usize) -> Option<[usize; 4]> {
    let mut e: Option<[usize; 4]> = None;
    for (p, _) in inside.iter().enumerate().filter(|(_, x)| **x) {
        grow_extent(&mut e, p % w, p / w);
    }
    e
}

/// Grow extent `e` to hold pixel `(u, v)`.
#[inline]
pub(crate) fn grow_extent(e: &mut Option<[usize; 4]>, u: usize, v: usize) {
    let x = e.get_or_insert([u, u, v, v]);
    *x = [x[0].min(u), x[1].max(u), x[2].min(v), x[3].max(v)];
}

/// The extent holding every one of `extents`; `None` when there are none.
pub(crate) fn joint_extent(extents: impl IntoIterator<Item = [usize; 4]>) -> Option<[usize; 4]> {
    extents.into_iter().reduce(|e, x| {
        [
            e[0].min(x[0]),
            e[1].max(x[1]),
            e[2].min(x[2]),
            e[3].max(x[3]),
        ]
    })
}

/// The largest step, in pixels, of any side of the outlines' extent between
/// two consecutive drawn slices that show the label: how far an object can
/// be followed from one drawn slice to the next.
pub fn drift(extents: &[Option<[usize; 4]>]) -> usize {
    let shown: Vec<&[usize; 4]> = extents.iter().flatten().collect();
    shown
        .windows(2)
        .flat_map(|p| (0..4).map(move |i| p[0][i].abs_diff(p[1][i])))
        .max()
        .unwrap_or(0)
}

/// One drawn slice of a label: its index and its whole-structure mask
/// (row-major `width * height`, as [`Volume::slice`] gives).
#[derive(Clone, Copy)]
pub struct DrawnSlice<'a> {
    /// Index along the axis.
    pub index: usize,
    /// Pixels inside the traced outline.
    pub inside: &'a [bool],
    /// Their in-plane extent (`extent` of `inside`: `[u_lo, u_hi, v_lo, v_hi]`), known to the caller
    /// that read the slice, so the box does not scan every slice again.
    pub extent: Option<[usize; 4]>,
}

impl<'a> DrawnSlice<'a> {
    /// A drawn slice `w` pixels wide, its extent measured.
    pub fn new(index: usize, inside: &'a [bool], w: usize) -> DrawnSlice<'a> {
        DrawnSlice {
            index,
            inside,
            extent: extent(inside, w),
        }
    }
}

impl LabelBox {
    /// The box of a label drawn on `slices` (sorted by index) of a volume of
    /// `dims` along `axis` for a method that reads as far as `reach`, or
    /// `None` when the label is on no drawn slice, the method reads the whole
    /// volume, or the box is the whole volume (nothing to gain).
    pub fn of(
        dims: [usize; 3],
        axis: Axis,
        slices: &[DrawnSlice<'_>],
        reach: BoxReach,
    ) -> Option<LabelBox> {
        let follows_drift = match reach {
            BoxReach::Whole => return None,
            BoxReach::Outline => false,
            BoxReach::Drift => true,
        };
        let (a, b) = axis.in_plane();
        let (w, h) = (dims[a], dims[b]);
        // In-plane extent of each drawn slice's outlines: [u_lo, u_hi, v_lo, v_hi].
        let extents: Vec<Option<[usize; 4]>> = slices.iter().map(|s| s.extent).collect();
        let first = extents.iter().position(Option::is_some);
        let last = extents.iter().rposition(Option::is_some);
        let ext = joint_extent(extents.iter().flatten().copied());
        let ([u0, u1, v0, v1], first, last) = (ext?, first?, last?);
        let margin = if follows_drift {
            MARGIN + 3 * drift(&extents)
        } else {
            MARGIN
        };
        let along_lo = first
            .checked_sub(AXIS_SLICES)
            .map_or(0, |p| slices[p].index);
        let along_hi = slices
            .get(last + AXIS_SLICES)
            .map_or(dims[axis.dim()] - 1, |s| s.index);
        let mut lo = [0; 3];
        let mut hi = [0; 3];
        lo[a] = u0.saturating_sub(margin);
        hi[a] = (u1 + margin).min(w - 1);
        lo[b] = v0.saturating_sub(margin);
        hi[b] = (v1 + margin).min(h - 1);
        lo[axis.dim()] = along_lo;
        hi[axis.dim()] = along_hi;
        let b = LabelBox {
            lo,
            dims: [0, 1, 2].map(|d| hi[d] - lo[d] + 1),
        };
        (b.dims != dims).then_some(b)
    }

    /// The label's traced mask inside the box (drawn slices set) and the
    /// drawn indices inside the box, shifted to the box's own.
    pub fn sparse(
        &self,
        geometry: &Geometry,
        axis: Axis,
        slices: &[DrawnSlice<'_>],
    ) -> Result<(Mask, Vec<usize>), InterpError> {
        let (a, b) = axis.in_plane();
        let w = geometry.dims[a];
        let d = axis.dim();
        // The spacing is what the methods read; the origin is left as is.
        let mut m: Mask = Volume::zeros(Geometry {
            dims: self.dims,
            ..geometry.clone()
        });
        let mut drawn = Vec::new();
        for s in slices {
            if s.index < self.lo[d] || s.index >= self.lo[d] + self.dims[d] {
                continue;
            }
            let at = s.index - self.lo[d];
            drawn.push(at);
            let (bw, bh) = (self.dims[a], self.dims[b]);
            let mut buf = vec![false; bw * bh];
            for v in 0..bh {
                let row = (self.lo[b] + v) * w + self.lo[a];
                buf[v * bw..(v + 1) * bw].copy_from_slice(&s.inside[row..row + bw]);
            }
            m.set_slice(axis, at, &buf)?;
        }
        Ok((m, drawn))
    }

    /// Whether `result` (a mask of the box) has a voxel on an in-plane side
    /// of the box where the volume goes on beyond it.
    pub fn reaches_open_side(&self, result: &Mask, axis: Axis, volume: [usize; 3]) -> bool {
        let (a, b) = axis.in_plane();
        let open = |dim: usize, at_lo: bool| {
            if at_lo {
                self.lo[dim] > 0
            } else {
                self.lo[dim] + self.dims[dim] < volume[dim]
            }
        };
        let g = result.geometry();
        let data = result.data();
        // Only the voxels on the open sides are read: a face of the box is
        // the voxels with one coordinate fixed.
        let face_reached = |dim: usize, at: usize| {
            let [nx, ny, nz] = self.dims;
            let range = |d: usize, n: usize| if d == dim { at..at + 1 } else { 0..n };
            range(2, nz).any(|k| range(1, ny).any(|j| range(0, nx).any(|i| data[g.index(i, j, k)])))
        };
        [a, b].iter().any(|&dim| {
            (open(dim, true) && face_reached(dim, 0))
                || (open(dim, false) && face_reached(dim, self.dims[dim] - 1))
        })
    }

    /// Run `method` on the box; `None` when its result reaches an open side
    /// (the caller then runs it on the whole volume).
    pub fn interpolate(
        &self,
        method: &dyn Interpolator,
        geometry: &Geometry,
        axis: Axis,
        slices: &[DrawnSlice<'_>],
    ) -> Result<Option<Mask>, InterpError> {
        let (m, drawn) = self.sparse(geometry, axis, slices)?;
        let r = method.interpolate(SparseMask::new(&m, axis, &drawn))?;
        Ok((!self.reaches_open_side(&r, axis, geometry.dims)).then_some(r))
    }

    /// Set `value` in `out` wherever the box's `mask` is inside.
    pub fn paint<T: Voxel>(&self, out: &mut Volume<T>, mask: &Mask, value: T) {
        let g = out.geometry().clone();
        let data = out.data_mut();
        let [nx, ny, nz] = self.dims;
        let src = mask.data();
        for k in 0..nz {
            for j in 0..ny {
                let row = &src[nx * (j + ny * k)..][..nx];
                let start = g.index(self.lo[0], self.lo[1] + j, self.lo[2] + k);
                for (o, &inside) in data[start..start + nx].iter_mut().zip(row) {
                    if inside {
                        *o = value;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_box_holds_the_outlines_a_margin_and_two_more_drawn_slices() {
        // 20 x 10 slices along z; a 3 x 2 outline at (5..8, 4..6) on z = 6, 9.
        let dims = [20, 10, 30];
        let mut on = vec![false; 200];
        for v in 4..6 {
            for u in 5..8 {
                on[u + 20 * v] = true;
            }
        }
        let off = vec![false; 200];
        let at = |index, inside| DrawnSlice::new(index, inside, 20);
        let slices = [
            at(0, &off[..]),
            at(3, &off),
            at(6, &on),
            at(9, &on),
            at(12, &off),
            at(15, &off),
            at(18, &off),
        ];
        let b = LabelBox::of(dims, Axis::Z, &slices, BoxReach::Outline).unwrap();
        assert_eq!(b.lo, [3, 2, 0]);
        assert_eq!(b.dims, [3 + 2 * MARGIN, 2 + 2 * MARGIN, 16]);
        assert_eq!(LabelBox::of(dims, Axis::Z, &slices, BoxReach::Whole), None);
        // The outline moves one pixel right on z = 9: a drift of 1.
        let mut moved = vec![false; 200];
        for v in 4..6 {
            for u in 6..9 {
                moved[u + 20 * v] = true;
            }
        }
        let mut drifting = slices;
        drifting[3] = at(9, &moved);
        let d = LabelBox::of(dims, Axis::Z, &drifting, BoxReach::Drift).unwrap();
        // A margin of MARGIN + 3 = 5 around u 5..=8, v 4..=5, cut at the
        // volume's sides (v runs 0..10).
        assert_eq!(d.lo, [0, 0, 0]);
        assert_eq!(d.dims, [8 + 5 + 1, 10, 16]);
        // Nothing drawn: no box; a box as large as the volume: none either.
        assert_eq!(
            LabelBox::of(
                dims,
                Axis::Z,
                &[at(0, &off), at(5, &off)],
                BoxReach::Outline
            ),
            None
        );
        let all = vec![true; 200];
        assert_eq!(
            LabelBox::of(dims, Axis::Z, &[at(0, &all), at(29, &all)], BoxReach::Drift),
            None
        );
    }
}
