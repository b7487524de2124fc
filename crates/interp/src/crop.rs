//! The box one label's interpolation runs in.
//!
//! A structure usually fills a small part of its volume (a nucleus in a 256³
//! cell, a lesion in a CT), yet a method given the whole volume computes
//! distance maps and blends over every slice. The shape methods
//! ([`Interpolator::bounded_by_tracing`]) cannot put a voxel outside
//! - the in-plane bounding box of the label's drawn outlines (signed-distance
//!   blends are positive outside every outline, copies and aligned shapes stay
//!   between them), nor
//! - past the drawn slice after the last drawn slice that shows the label,
//!   nor before the one before the first (a gap between two drawn slices
//!   where the label is absent stays empty: the invariant of every method),
//!
//! so the runner hands them that box plus a [`MARGIN`] of background and
//! [`AXIS_SLICES`] more drawn slices along the axis, and
//! pastes the result back. The claim is checked, not trusted: a result that
//! reaches the box's in-plane sides (where the volume goes on) is computed
//! again on the whole volume. Tests compare both ways voxel for voxel.
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::{Axis, Geometry, Mask, Volume, Voxel};

/// Background voxels kept around the drawn outlines, in-plane.
pub const MARGIN: usize = 2;

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

/// One drawn slice of a label: its index and its whole-structure mask
/// (row-major `width * height`, as [`Volume::slice`] gives).
pub struct DrawnSlice<'a> {
    /// Index along the axis.
    pub index: usize,
    /// Pixels inside the traced outline.
    pub inside: &'a [bool],
}

impl LabelBox {
    /// The box of a label drawn on `slices` (sorted by index) of a volume of
    /// `dims` along `axis`, or `None` when the label is on no drawn slice or
    /// the box is the whole volume (nothing to gain).
    pub fn of(dims: [usize; 3], axis: Axis, slices: &[DrawnSlice<'_>]) -> Option<LabelBox> {
        let (a, b) = axis.in_plane();
        let (w, h) = (dims[a], dims[b]);
        // In-plane extent of every outline: [u_lo, u_hi] x [v_lo, v_hi].
        let mut ext: Option<[usize; 4]> = None;
        let mut first = None;
        let mut last = None;
        for (n, s) in slices.iter().enumerate() {
            let mut any = false;
            for (p, _) in s.inside.iter().enumerate().filter(|(_, x)| **x) {
                let (u, v) = (p % w, p / w);
                any = true;
                let e = ext.get_or_insert([u, u, v, v]);
                *e = [e[0].min(u), e[1].max(u), e[2].min(v), e[3].max(v)];
            }
            if any {
                first.get_or_insert(n);
                last = Some(n);
            }
        }
        let ([u0, u1, v0, v1], first, last) = (ext?, first?, last?);
        let along_lo = first
            .checked_sub(AXIS_SLICES)
            .map_or(0, |p| slices[p].index);
        let along_hi = slices
            .get(last + AXIS_SLICES)
            .map_or(dims[axis.dim()] - 1, |s| s.index);
        let mut lo = [0; 3];
        let mut hi = [0; 3];
        lo[a] = u0.saturating_sub(MARGIN);
        hi[a] = (u1 + MARGIN).min(w - 1);
        lo[b] = v0.saturating_sub(MARGIN);
        hi[b] = (v1 + MARGIN).min(h - 1);
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
        let [nx, ny, nz] = self.dims;
        (0..nz).any(|k| {
            (0..ny).any(|j| {
                (0..nx).any(|i| {
                    let p = [i, j, k];
                    data[g.index(i, j, k)]
                        && [a, b].iter().any(|&dim| {
                            (p[dim] == 0 && open(dim, true))
                                || (p[dim] + 1 == self.dims[dim] && open(dim, false))
                        })
                })
            })
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
        let at = |index, inside| DrawnSlice { index, inside };
        let slices = [
            at(0, &off[..]),
            at(3, &off),
            at(6, &on),
            at(9, &on),
            at(12, &off),
            at(15, &off),
            at(18, &off),
        ];
        let b = LabelBox::of(dims, Axis::Z, &slices).unwrap();
        assert_eq!(b.lo, [3, 2, 0]);
        assert_eq!(b.dims, [3 + 2 * MARGIN, 2 + 2 * MARGIN, 16]);
        // Nothing drawn: no box; a box as large as the volume: none either.
        assert_eq!(
            LabelBox::of(dims, Axis::Z, &[at(0, &off), at(5, &off)]),
            None
        );
        let all = vec![true; 200];
        assert_eq!(
            LabelBox::of(dims, Axis::Z, &[at(0, &all), at(29, &all)]),
            None
        );
    }
}
