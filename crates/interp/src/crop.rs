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
//! `shape-aligned` and so the default) reads as far as they move. It gets a
//! box sized by how far the outlines' centroid moves ([`LabelBox::tries`]),
//! and is told it runs on a box ([`SparseMask::in_box`]): where it would
//! read or paint past the box's sides it stops with
//! [`InterpError::OutsideBox`], and the runner tries a larger box, then the
//! whole volume. A result that reaches the box's in-plane sides (where the
//! volume goes on) is computed again as well. The image-aware method, whose
//! shape prior follows drift and which reads the image around that prior,
//! gets the drift's box grown by what it reads ([`BoxReach::Image`]) and
//! the box's part of the image ([`crate::Interpolator::for_box`]). Tests
//! compare both ways.
use crate::image::fuse::{band, tau};
use crate::image::walk;
use crate::method::WithConfidence;
use crate::slices::{Plane, centroid};
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::{Axis, Cancel, Geometry, Mask, Volume, Voxel};
use rayon::prelude::*;

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
    /// A shape prior that follows drift ([`BoxReach::Drift`]) and the
    /// intensities around it: the image-aware method, whose fusion reads
    /// the image in a band around the prior and whose walk reads it
    /// [`crate::image::walk::MARGIN`] past the drawn outlines
    /// (`image_margin`). It runs on the box's part of the image
    /// ([`crate::Interpolator::for_box`]).
    Image,
}

impl BoxReach {
    /// Whether the confidence of a method that reads this far can run on a
    /// box grown by [`LabelBox::grown_for_confidence`], whose reach is that
    /// of the shape methods' confidence. The image-aware method's
    /// confidence is fitted per label (its scale, and the walk's, which
    /// never reaches 1) after the box is chosen: it runs on the whole
    /// volume.
    pub fn confidence_on_box(self) -> bool {
        matches!(self, BoxReach::Outline | BoxReach::Drift)
    }
}

/// Pixels the image-aware method reads past its shape prior
/// ([`BoxReach::Image`]): the fusion's band at the middle of the widest gap
/// between the drawn `slices` ([`crate::image::fuse::band`], at most 40
/// pixels), and two more, the neighbour the band's smoothing reads and the
/// pixel the blur reads beside that; or twice the walk's margin past the
/// drawn outlines (its box, and the ring around it its confidence's scale
/// is fitted on, `image::walk::Walked::fit_region`), whichever is more;
/// plus one.
fn image_margin(geometry: &Geometry, axis: Axis, slices: &[DrawnSlice<'_>]) -> usize {
    let plane = Plane::along(geometry, axis);
    let widest = slices
        .windows(2)
        .map(|w| w[1].index - w[0].index)
        .max()
        .unwrap_or(1);
    let b = f64::from(band(&plane, widest as f64 / 2.0));
    let px = plane.spacing[0].min(plane.spacing[1]);
    ((b / px).ceil() as usize + 2).max(2 * walk::MARGIN) + 1
}

/// The confidence taken as 1 outside a label's box
/// ([`LabelBox::grown_for_confidence`]): the whole volume's confidence there
/// lies between this and 1.
pub const SURE: f32 = 0.9999;

/// Just above the logit of [`SURE`], `ln(SURE / (1 − SURE))` = 9.2102.
const SURE_LOGIT: f64 = 9.22;

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

/// The largest step, in whole pixels (rounded up), of the outlines'
/// centroid along u or v between two consecutive drawn slices that show the
/// label; slices `w` pixels wide.
pub fn centroid_drift(slices: &[DrawnSlice<'_>], w: usize) -> usize {
    let centroids: Vec<[f64; 2]> = slices
        .iter()
        .filter_map(|s| centroid(s.inside, w, s.extent?))
        .collect();
    centroids
        .windows(2)
        .map(|p| (p[0][0] - p[1][0]).abs().max((p[0][1] - p[1][1]).abs()))
        .fold(0.0f64, f64::max)
        .ceil() as usize
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

    /// The drawn slices of one label's `input`, whose `planes` were read by
    /// [`drawn_planes`].
    pub fn of(input: &SparseMask<'_>, planes: &'a [Vec<bool>]) -> Vec<DrawnSlice<'a>> {
        let width = input.mask.dims()[input.axis.in_plane().0];
        input
            .drawn
            .iter()
            .zip(planes)
            .map(|(&d, p)| DrawnSlice::new(d, p, width))
            .collect()
    }
}

/// The drawn slices of `input` along its axis, read once (in parallel), for
/// [`DrawnSlice::of`].
pub fn drawn_planes(input: &SparseMask<'_>) -> Result<Vec<Vec<bool>>, InterpError> {
    Ok(input
        .drawn
        .par_iter()
        .map(|&d| input.mask.slice(input.axis, d))
        .collect::<Result<_, _>>()?)
}

impl LabelBox {
    /// The box that is the whole volume of `geometry` (a result computed on
    /// the whole volume, painted as a box's).
    pub fn whole(geometry: &Geometry) -> LabelBox {
        LabelBox {
            lo: [0; 3],
            dims: geometry.dims,
        }
    }

    /// The boxes to run a label drawn on `slices` (sorted by index) of a
    /// volume of `dims` along `axis` in, for a method that reads as far as
    /// `reach`, smallest first; empty when the label is on no drawn slice,
    /// the method reads the whole volume, or the box would be the whole
    /// volume (nothing to gain).
    ///
    /// A method that follows drift ([`BoxReach::Drift`]) first gets
    /// [`MARGIN`] + 3 (the ring its crops keep) + three times the largest
    /// step of the outlines' centroid between consecutive drawn slices: an
    /// object that grows or shrinks without moving (a nucleus towards its
    /// poles) then runs in a box barely larger than its outlines. Objects
    /// whose pieces move apart while the centroid stays can need more; such
    /// a run ends in [`InterpError::OutsideBox`], and the next box, three
    /// times the largest step of any side of the outlines' extent ([`drift`]),
    /// is tried before the whole volume.
    pub fn tries(
        geometry: &Geometry,
        axis: Axis,
        slices: &[DrawnSlice<'_>],
        reach: BoxReach,
    ) -> Vec<LabelBox> {
        let dims = geometry.dims;
        let extents: Vec<Option<[usize; 4]>> = slices.iter().map(|s| s.extent).collect();
        let drifting = || {
            let w = dims[axis.in_plane().0];
            let moved = MARGIN + 3 + 3 * centroid_drift(slices, w);
            let sides = MARGIN + 3 * drift(&extents);
            if sides > moved {
                vec![moved, sides]
            } else {
                vec![moved]
            }
        };
        let margins = match reach {
            BoxReach::Whole => return Vec::new(),
            BoxReach::Outline => vec![MARGIN],
            BoxReach::Drift => drifting(),
            BoxReach::Image => {
                let extra = image_margin(geometry, axis, slices);
                drifting().into_iter().map(|m| m + extra).collect()
            }
        };
        margins
            .into_iter()
            .map_while(|m| Self::with_margin(dims, axis, slices, &extents, m))
            .collect()
    }

    /// The box of the outlines grown by `margin` in-plane and by
    /// [`AXIS_SLICES`] drawn slices along the axis; `None` when nothing is
    /// drawn or the box is the whole volume.
    fn with_margin(
        dims: [usize; 3],
        axis: Axis,
        slices: &[DrawnSlice<'_>],
        extents: &[Option<[usize; 4]>],
        margin: usize,
    ) -> Option<LabelBox> {
        let (a, b) = axis.in_plane();
        let (w, h) = (dims[a], dims[b]);
        let first = extents.iter().position(Option::is_some);
        let last = extents.iter().rposition(Option::is_some);
        let ext = joint_extent(extents.iter().flatten().copied());
        let ([u0, u1, v0, v1], first, last) = (ext?, first?, last?);
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

    /// Run `method` on the box (with its confidence when `confidence`),
    /// stopped once `cancel` is; `None` when it would reach past the box
    /// ([`InterpError::OutsideBox`]) or its result reaches an open side (the
    /// caller then tries a larger box or the whole volume).
    pub fn interpolate(
        &self,
        method: &dyn Interpolator,
        (geometry, axis): (&Geometry, Axis),
        slices: &[DrawnSlice<'_>],
        confidence: bool,
        cancel: Option<&Cancel>,
    ) -> Result<Option<WithConfidence>, InterpError> {
        let (m, drawn) = self.sparse(geometry, axis, slices)?;
        let cut = method.for_box(self);
        let method = cut.as_deref().unwrap_or(method);
        let mut input = SparseMask::new(&m, axis, &drawn).inside_box();
        input.cancel = cancel;
        let run = if confidence {
            method
                .interpolate_with_confidence(input)
                .map(|(m, c)| (m, Some(c)))
        } else {
            method.interpolate(input).map(|m| (m, None))
        };
        let r = match run {
            Err(InterpError::OutsideBox) => return Ok(None),
            r => r?,
        };
        Ok((!self.reaches_open_side(&r.0, axis, geometry.dims)).then_some(r))
    }

    /// The box grown in-plane far enough for a shape method's confidence
    /// ([`crate::confidence::shape_confidence`]) on the slices `drawn`
    /// (along `axis`, in the whole volume) to reach [`SURE`] at its sides:
    /// `σ(c |φ| / τ(δ))` with `c ≥ 1` reaches it `SURE_LOGIT · τ(δ)` from
    /// the result's boundary or a drawn outline, all of which lie inside
    /// the box, and `δ` is at most the widest gap less one slice. Outside
    /// the grown box the confidence is taken as 1. `None` when the grown
    /// box is the whole volume.
    pub fn grown_for_confidence(
        &self,
        geometry: &Geometry,
        axis: Axis,
        drawn: &[usize],
    ) -> Option<LabelBox> {
        let plane = Plane::along(geometry, axis);
        let widest = drawn.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(1);
        self.grown_until_sure(geometry, axis, f64::from(tau(&plane, (widest - 1) as f64)))
    }

    /// The box grown in-plane by `SURE_LOGIT · scale` (physical units): how
    /// far from every boundary and outline inside it a confidence
    /// `σ(|φ| / scale)` (or surer) reaches [`SURE`]. `None` when the grown
    /// box is the whole volume.
    pub fn grown_until_sure(
        &self,
        geometry: &Geometry,
        axis: Axis,
        scale: f64,
    ) -> Option<LabelBox> {
        let (a, b) = axis.in_plane();
        let plane = Plane::along(geometry, axis);
        let pixel = plane.spacing[0].min(plane.spacing[1]);
        let extra = (SURE_LOGIT * scale / pixel).ceil() as usize;
        let mut grown = *self;
        for d in [a, b] {
            let hi = (self.lo[d] + self.dims[d] + extra).min(geometry.dims[d]);
            grown.lo[d] = self.lo[d].saturating_sub(extra);
            grown.dims[d] = hi - grown.lo[d];
        }
        (grown.dims != geometry.dims).then_some(grown)
    }

    /// The box's part of `volume` (its geometry's origin left as is, as in
    /// [`LabelBox::sparse`]).
    pub fn cut<T: Voxel>(&self, volume: &Volume<T>) -> Volume<T> {
        let [gx, gy, _] = volume.dims();
        let [nx, ny, nz] = self.dims;
        let src = volume.data();
        let data: Vec<T> = (0..nz)
            .into_par_iter()
            .flat_map_iter(|k| {
                (0..ny).flat_map(move |j| {
                    let start = self.lo[0] + gx * (self.lo[1] + j + gy * (self.lo[2] + k));
                    src[start..start + nx].iter().copied()
                })
            })
            .collect();
        let geometry = Geometry {
            dims: self.dims,
            ..volume.geometry().clone()
        };
        Volume::from_vec(geometry, data).expect("one value per voxel of the box")
    }

    /// A box's result (`mask`, and its confidence when asked) as the whole
    /// volume's: background and a confidence of 1 outside the box.
    pub fn onto_volume(&self, geometry: &Geometry, (mask, conf): WithConfidence) -> WithConfidence {
        let mut out: Mask = crate::labels::zeros_in_parallel(geometry.clone());
        self.paint(&mut out, &mask, true);
        let conf = conf.map(|c| {
            let mut all = Volume::filled(geometry.clone(), 1.0f32);
            self.lower(&mut all, &c);
            all
        });
        (out, conf)
    }

    /// Lower `out` to the box's confidence `conf` where it is less (a
    /// voxel's confidence is the least of any label's there).
    pub fn lower(&self, out: &mut Volume<f32>, conf: &Volume<f32>) {
        self.rows_into(out, conf.data(), |o, row| {
            for (o, &c) in o.iter_mut().zip(row) {
                *o = o.min(c);
            }
        });
    }

    /// Set `value` in `out` wherever the box's `mask` is inside.
    pub fn paint<T: Voxel>(&self, out: &mut Volume<T>, mask: &Mask, value: T) {
        self.rows_into(out, mask.data(), |o, row| paint_row(o, row, value));
    }

    /// `write(out_row, box_row)` for every row of the box (`src`, the
    /// box's values) and the row of `out` it lies on, plane by plane
    /// (across the box's last dimension) in parallel.
    fn rows_into<T: Voxel, S: Sync>(
        &self,
        out: &mut Volume<T>,
        src: &[S],
        write: impl Fn(&mut [T], &[S]) + Sync,
    ) {
        let [gx, gy, _] = out.dims();
        let [nx, ny, nz] = self.dims;
        let planes = &mut out.data_mut()[gx * gy * self.lo[2]..gx * gy * (self.lo[2] + nz)];
        planes
            .par_chunks_mut(gx * gy)
            .zip(src.par_chunks(nx * ny))
            .for_each(|(plane, box_plane)| {
                for (j, row) in box_plane.chunks(nx).enumerate() {
                    let start = self.lo[0] + gx * (self.lo[1] + j);
                    write(&mut plane[start..start + nx], row);
                }
            });
    }
}

/// Set `value` in `out` wherever `inside` is. A function of its own: slices
/// handed to a function are known not to overlap, which lets the compiler
/// run the loop on vector lanes; taken from the tuple a parallel iterator
/// passes, they were not, and the loop ran one voxel at a time.
#[inline]
fn paint_row<T: Voxel>(out: &mut [T], inside: &[bool], value: T) {
    for (o, &inside) in out.iter_mut().zip(inside) {
        // A select of two values, not a branch.
        let was = *o;
        *o = if inside { value } else { was };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_box_holds_the_outlines_a_margin_and_two_more_drawn_slices() {
        // 20 x 10 slices along z; a 3 x 2 outline at (5..8, 4..6) on z = 6, 9.
        let dims = [20, 10, 30];
        let g = Geometry::new(dims, [1.0; 3], Default::default()).unwrap();
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
        let b = LabelBox::tries(&g, Axis::Z, &slices, BoxReach::Outline);
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].lo, [3, 2, 0]);
        assert_eq!(b[0].dims, [3 + 2 * MARGIN, 2 + 2 * MARGIN, 16]);
        assert_eq!(LabelBox::tries(&g, Axis::Z, &slices, BoxReach::Whole), []);
        // The outline moves one pixel right on z = 9: a drift of 1.
        let mut moved = vec![false; 200];
        for v in 4..6 {
            for u in 6..9 {
                moved[u + 20 * v] = true;
            }
        }
        let mut drifting = slices;
        drifting[3] = at(9, &moved);
        let d = LabelBox::tries(&g, Axis::Z, &drifting, BoxReach::Drift);
        // The centroid moves by 1/2 (rounded up to 1): a margin of
        // MARGIN + 3 + 3 = 8 around u 5..=8, v 4..=5, cut at the volume's
        // sides (v runs 0..10); the sides' step of 1 asks for less, so there
        // is no second box.
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].lo, [0, 0, 0]);
        assert_eq!(d[0].dims, [8 + 8 + 1, 10, 16]);
        // Nothing drawn: no box; a box as large as the volume: none either.
        assert_eq!(
            LabelBox::tries(&g, Axis::Z, &[at(0, &off), at(5, &off)], BoxReach::Outline),
            []
        );
        let all = vec![true; 200];
        assert_eq!(
            LabelBox::tries(&g, Axis::Z, &[at(0, &all), at(29, &all)], BoxReach::Drift),
            []
        );
    }
}
