//! The four mesh-based interpolators of the original 2014 system, surface
//! meshes of label masks, and voxelisation.
//!
//! Every mesh method builds a closed triangle surface from the drawn slices
//! ([`crate::Interpolator::surface_mesh`]), voxelises it ([`voxelize::voxelize`]: voxel centre inside
//! the mesh) and then **overwrites every drawn slice with its tracing**. The
//! surfaces do not pass exactly through the traced pixel boundaries (marching
//! cubes cuts between pixel centres, the splat inflates, Delaunay leaves
//! holes, Hoppe's surface smooths), so without that last step the drawn
//! slices would deviate from what the user traced; with it, drawn slices are
//! reproduced exactly and a drawn-empty slice stays empty, as every method
//! must guarantee. The mesh returned by `surface_mesh` is the raw surface,
//! before that correction.
//!
//! Methods, names as `--method` values:
//! - `marching-cubes` ([`MarchingCubesMethod`]): marching cubes on the stack
//!   of drawn slices, stretched back along the axis.
//! - `gaussian-splat` ([`splat::GaussianSplat`]): Gaussian splats around the
//!   contour points, iso-surface.
//! - `delaunay` ([`delaunay::DelaunayMethod`]): alpha-filtered 3D Delaunay
//!   tetrahedralisation of the contour points.
//! - `unorganized-points` ([`hoppe::UnorganizedPoints`]): Hoppe et al. 1992.
//!
//! Coordinates: meshes are in physical units in the frame of
//! [`interslice_core::mesh`] (voxel centre at `(index + 0.5) * spacing`).
//! Internally the methods work in the slice frame `(u, v, w)`, where `w`
//! runs along the drawn axis, and map to `(x, y, z)` at the end.
pub mod delaunay;
pub mod hoppe;
pub mod marching_cubes;
pub mod splat;
pub mod voxelize;

use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::edt::squared_edt_3d_f32;
use interslice_core::mesh::TriMesh;
use interslice_core::morph::Connectivity;
use interslice_core::regions::holes_2d;
use interslice_core::trace::mask_polygons;
use interslice_core::{Axis, Mask};
use marching_cubes::{Grid, marching_cubes};
use rayon::prelude::*;

pub use delaunay::DelaunayMethod;
pub use hoppe::UnorganizedPoints;
pub use splat::GaussianSplat;

/// The mesh-based interpolators, in the order of the original system.
pub fn mesh_methods() -> Vec<Box<dyn Interpolator>> {
    vec![
        Box::new(MarchingCubesMethod),
        Box::new(GaussianSplat::default()),
        Box::new(DelaunayMethod),
        Box::new(UnorganizedPoints::default()),
    ]
}

/// The closed marching-cubes surface of a whole mask (for the 3D view of any
/// result and `interslice mesh`): iso-level 0.5 between voxel centres, on the
/// mask's bounding box padded by one outside layer. Empty mask, empty mesh.
pub fn mask_surface(mask: &Mask) -> TriMesh {
    let g = mask.geometry();
    let [nx, ny, nz] = g.dims;
    let Some((lo, hi)) = bounding_box(mask) else {
        return TriMesh::new();
    };
    let size = [hi[0] - lo[0] + 3, hi[1] - lo[1] + 3, hi[2] - lo[2] + 3];
    let coords = |d: usize| -> Vec<f64> {
        (0..size[d])
            .map(|n| (lo[d] as f64 + n as f64 - 0.5) * g.spacing[d])
            .collect()
    };
    let (xs, ys, zs) = (coords(0), coords(1), coords(2));
    let mut values = vec![0u8; size[0] * size[1] * size[2]];
    let data = mask.data();
    values
        .par_chunks_mut(size[0] * size[1])
        .enumerate()
        .for_each(|(kk, plane)| {
            if kk == 0 || kk == size[2] - 1 {
                return;
            }
            let k = lo[2] + kk - 1;
            for jj in 1..size[1] - 1 {
                let j = lo[1] + jj - 1;
                let row = &data[nx * (j + ny * k)..nx * (j + ny * k) + nx];
                for ii in 1..size[0] - 1 {
                    plane[ii + size[0] * jj] = u8::from(row[lo[0] + ii - 1]);
                }
            }
        });
    debug_assert!(hi[0] < nx && hi[1] < ny && hi[2] < nz);
    marching_cubes(
        Grid {
            values: &values,
            xs: &xs,
            ys: &ys,
            zs: &zs,
        },
        0.5,
    )
}

/// Inclusive voxel bounding box `(lo, hi)` of a mask's foreground.
pub fn bounding_box(mask: &Mask) -> Option<([usize; 3], [usize; 3])> {
    let [nx, ny, _] = mask.dims();
    mask.data()
        .par_chunks(nx * ny)
        .enumerate()
        .filter_map(|(k, plane)| {
            let mut bb: Option<([usize; 3], [usize; 3])> = None;
            for (idx, _) in plane.iter().enumerate().filter(|(_, v)| **v) {
                let (i, j) = (idx % nx, idx / nx);
                bb = Some(match bb {
                    None => ([i, j, k], [i, j, k]),
                    Some((lo, hi)) => (
                        [lo[0].min(i), lo[1].min(j), k],
                        [hi[0].max(i), hi[1].max(j), k],
                    ),
                });
            }
            bb
        })
        .reduce_with(|a, b| {
            (
                [a.0[0].min(b.0[0]), a.0[1].min(b.0[1]), a.0[2].min(b.0[2])],
                [a.1[0].max(b.1[0]), a.1[1].max(b.1[1]), a.1[2].max(b.1[2])],
            )
        })
}

/// The slice frame of an input: in-plane dims and the physical spacing
/// along u, v and w (the drawn axis).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    pub axis: Axis,
    /// Slices along u, v, w.
    pub dims: [usize; 3],
    /// Physical spacing along u, v, w.
    pub spacing: [f64; 3],
}

impl Frame {
    pub fn of(input: &SparseMask<'_>) -> Frame {
        let g = input.mask.geometry();
        let (a, b) = input.axis.in_plane();
        let w = input.axis.dim();
        Frame {
            axis: input.axis,
            dims: [g.dims[a], g.dims[b], g.dims[w]],
            spacing: [g.spacing[a], g.spacing[b], g.spacing[w]],
        }
    }

    /// Physical (u, v, w) coordinates of voxel centres along frame dim `d`,
    /// for voxel indices `from..to` (indices may run outside the volume).
    pub fn centres(&self, d: usize, from: isize, to: isize) -> Vec<f64> {
        (from..to)
            .map(|n| (n as f64 + 0.5) * self.spacing[d])
            .collect()
    }

    /// Map a mesh from the (u, v, w) frame to (x, y, z), keeping triangles
    /// wound outwards (the y-axis frame is a reflection).
    pub fn to_xyz(self, mut mesh: TriMesh) -> TriMesh {
        match self.axis {
            Axis::Z => {}
            Axis::Y => {
                for p in &mut mesh.vertices {
                    *p = [p[0], p[2], p[1]];
                }
                for t in &mut mesh.triangles {
                    t.swap(1, 2);
                }
            }
            Axis::X => {
                for p in &mut mesh.vertices {
                    *p = [p[2], p[0], p[1]];
                }
            }
        }
        mesh
    }
}

/// The contours of every non-empty drawn slice, resampled to points at most
/// `step` apart (physical units, at least 4 points per contour), in the
/// physical (u, v, w) frame. Contours come from
/// [`interslice_core::trace::mask_polygons`] (pixel-edge boundaries), with
/// the slice's centre plane at `w = (index + 0.5) * spacing_w`.
pub(crate) fn contour_points(input: &SparseMask<'_>, frame: &Frame, step: f64) -> Vec<[f64; 3]> {
    drawn_contours(input, frame, step)
        .flat_map_iter(|pts| pts)
        .collect()
}

/// The contours of every drawn slice (points as in [`contour_points`]), in
/// the order of the drawn slices.
pub(crate) fn drawn_contours<'a>(
    input: &'a SparseMask<'_>,
    frame: &'a Frame,
    step: f64,
) -> impl ParallelIterator<Item = Vec<[f64; 3]>> + 'a {
    input.drawn.par_iter().flat_map_iter(move |&d| {
        let buf = input
            .mask
            .slice(input.axis, d)
            .expect("validated drawn index");
        slice_contours(&buf, d, frame, step)
            .into_iter()
            .map(|(_, pts)| pts)
    })
}

/// The contours of drawn slice `index` (mask `buf`), each as the pixel
/// `(u, v)` on the foreground side of its first edge and its resampled
/// points in the physical (u, v, w) frame.
pub(crate) fn slice_contours(
    buf: &[bool],
    index: usize,
    frame: &Frame,
    step: f64,
) -> Vec<([usize; 2], Vec<[f64; 3]>)> {
    let [su, sv, sw] = frame.spacing;
    let (width, height) = (frame.dims[0], frame.dims[1]);
    let w = (index as f64 + 0.5) * sw;
    let mut out = Vec::new();
    for poly in mask_polygons(buf, width, height) {
        let n = poly.len();
        if n < 2 {
            continue;
        }
        // Foreground is on the left of each edge (u right, v up): the pixel
        // at the edge midpoint plus half a pixel along the left normal.
        let (p0, p1) = (poly[0], poly[1]);
        let len = ((p1[0] - p0[0]).powi(2) + (p1[1] - p0[1]).powi(2))
            .sqrt()
            .max(1e-12);
        let (du, dv) = ((p1[0] - p0[0]) / len, (p1[1] - p0[1]) / len);
        let mid = [
            (p0[0] + p1[0]) / 2.0 - 0.5 * dv,
            (p0[1] + p1[1]) / 2.0 + 0.5 * du,
        ];
        let pixel = [
            (mid[0].floor().max(0.0) as usize).min(width - 1),
            (mid[1].floor().max(0.0) as usize).min(height - 1),
        ];
        let phys: Vec<[f64; 2]> = poly.iter().map(|p| [p[0] * su, p[1] * sv]).collect();
        let lens: Vec<f64> = (0..n)
            .map(|i| {
                let (a, b) = (phys[i], phys[(i + 1) % n]);
                ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
            })
            .collect();
        let perimeter: f64 = lens.iter().sum();
        let count = ((perimeter / step).ceil() as usize).max(4);
        let ds = perimeter / count as f64;
        let (mut edge, mut along) = (0usize, 0.0f64);
        let mut pts = Vec::with_capacity(count);
        for s in 0..count {
            let target = s as f64 * ds;
            while edge + 1 < n && along + lens[edge] < target {
                along += lens[edge];
                edge += 1;
            }
            let (a, b) = (phys[edge], phys[(edge + 1) % n]);
            let t = if lens[edge] > 0.0 {
                ((target - along) / lens[edge]).clamp(0.0, 1.0)
            } else {
                0.0
            };
            pts.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), w]);
        }
        out.push((pixel, pts));
    }
    out
}

/// The result of a mesh method: its surface
/// ([`Interpolator::surface_mesh`]) voxelised, drawn slices restored.
pub(crate) fn voxelise_surface(
    method: &dyn Interpolator,
    input: SparseMask<'_>,
) -> Result<Mask, InterpError> {
    // Cancellation is checked between the stages (surface, voxelisation).
    input.check_cancelled()?;
    let mesh = method
        .surface_mesh(input)?
        .expect("a mesh method builds a surface");
    input.check_cancelled()?;
    let out = finish(&input, &mesh)?;
    input.check_cancelled()?;
    Ok(out)
}

/// Turn a surface into the method's result: voxelise it on the input's
/// grid, then restore every drawn slice from the tracing (see module docs).
pub(crate) fn finish(input: &SparseMask<'_>, mesh_xyz: &TriMesh) -> Result<Mask, InterpError> {
    let mut out = voxelize::voxelize(mesh_xyz, input.mask.geometry());
    for &d in input.drawn {
        let s = input.mask.slice(input.axis, d)?;
        out.set_slice(input.axis, d, &s)?;
    }
    Ok(out)
}

/// A scalar field on a box of voxel centres in the (u, v, w) frame, with
/// one extra sample on every side (left at the outside value by callers).
pub(crate) struct FieldBox {
    /// Samples along u, v, w, padding included.
    pub size: [usize; 3],
    /// Sample positions along u, v, w.
    pub coords: [Vec<f64>; 3],
    /// Sample spacing along u, v, w.
    pub spacing: [f64; 3],
}

impl FieldBox {
    /// The voxel centres whose positions lie within `[lo - margin, hi +
    /// margin]`, clamped to the volume, plus one padding sample per side.
    pub fn around(frame: &Frame, lo: [f64; 3], hi: [f64; 3], margin: f64) -> FieldBox {
        let mut from = [0isize; 3];
        let mut size = [0usize; 3];
        for d in 0..3 {
            let s = frame.spacing[d];
            let a = (((lo[d] - margin) / s - 0.5).floor() as isize).max(0);
            let b = (((hi[d] + margin) / s - 0.5).ceil() as isize).min(frame.dims[d] as isize - 1);
            from[d] = a - 1;
            size[d] = (b - a + 1).max(1) as usize + 2;
        }
        let coords = std::array::from_fn(|d| frame.centres(d, from[d], from[d] + size[d] as isize));
        FieldBox {
            size,
            coords,
            spacing: frame.spacing,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.size[0] * self.size[1] * self.size[2]
    }

    /// True on the padding layer.
    #[inline]
    pub fn is_padding(&self, a: usize, b: usize, c: usize) -> bool {
        a == 0
            || b == 0
            || c == 0
            || a + 1 == self.size[0]
            || b + 1 == self.size[1]
            || c + 1 == self.size[2]
    }

    /// Approximate distance from every sample to the nearest of `points`:
    /// the exact distance transform (core's EDT, physical units) of the
    /// samples nearest to the points, and the bound `e` on its error (half
    /// a sample diagonal): the true distance lies within `d ± e`. Methods use
    /// it to evaluate their field exactly only where it matters.
    pub fn seed_distance(&self, points: &[[f64; 3]]) -> (Vec<f32>, f64) {
        let mut seeds = vec![false; self.len()];
        let sp = self.spacing;
        for p in points {
            let idx: [usize; 3] = std::array::from_fn(|d| {
                let x = ((p[d] - self.coords[d][0]) / sp[d]).round();
                x.clamp(0.0, (self.size[d] - 1) as f64) as usize
            });
            seeds[idx[0] + self.size[0] * (idx[1] + self.size[1] * idx[2])] = true;
        }
        let d2 = squared_edt_3d_f32(&seeds, self.size, sp);
        let d: Vec<f32> = d2.into_par_iter().map(f32::sqrt).collect();
        let e = 0.5 * (sp[0] * sp[0] + sp[1] * sp[1] + sp[2] * sp[2]).sqrt() + 1e-6;
        (d, e)
    }

    /// As [`FieldBox::evaluate`], with a cheap first guess per sample:
    /// `guess(index)` returns `Some(value)` where the caller can settle the
    /// sample without `f` (e.g. from [`FieldBox::seed_distance`]).
    pub fn evaluate_guided(
        &self,
        outside: f32,
        guess: impl Fn(usize) -> Option<f32> + Sync,
        f: impl Fn([f64; 3]) -> f32 + Sync,
    ) -> Vec<f32> {
        let [nu, nv, _] = self.size;
        let mut values = vec![outside; self.len()];
        values
            .par_chunks_mut(nu * nv)
            .enumerate()
            .for_each(|(c, plane)| {
                for b in 0..nv {
                    for a in 0..nu {
                        if self.is_padding(a, b, c) {
                            continue;
                        }
                        let i = a + nu * b;
                        plane[i] = match guess(i + nu * nv * c) {
                            Some(v) => v,
                            None => f([self.coords[0][a], self.coords[1][b], self.coords[2][c]]),
                        };
                    }
                }
            });
        values
    }

    /// Marching cubes of `values` at `iso` (inside = value > iso).
    pub fn iso_surface(&self, values: &[f32], iso: f32) -> TriMesh {
        marching_cubes(
            Grid {
                values,
                xs: &self.coords[0],
                ys: &self.coords[1],
                zs: &self.coords[2],
            },
            iso,
        )
    }

    /// In every plane of constant w (parallel to the drawn slices), mark the
    /// samples with value <= iso that cannot be reached from the plane's
    /// padding ring through such samples as inside (`fill`): the regions a
    /// field encloses within the plane are filled, which includes every
    /// cavity enclosed in 3D. Outside samples are 8-connected in the plane,
    /// the complement of the 4-connected inside that marching cubes keeps
    /// (diagonal inside corners stay apart), so the fill agrees with the
    /// surface extracted afterwards.
    pub fn fill_plane_holes(&self, values: &mut [f32], iso: f32, fill: f32) {
        let [nu, nv, _] = self.size;
        values.par_chunks_mut(nu * nv).for_each(|plane| {
            // Outside is everything not `<= iso`, NaN included.
            let outside: Vec<bool> = plane
                .iter()
                .map(|&v| v.partial_cmp(&iso).is_none_or(|o| o.is_gt()))
                .collect();
            let enclosed = holes_2d(&outside, nu, nv, Connectivity::Full, |_| true);
            for (v, e) in plane.iter_mut().zip(enclosed) {
                if e {
                    *v = fill;
                }
            }
        });
    }
}

/// Bounds `(lo, hi)` of a point set; `None` when empty.
pub(crate) fn point_bounds(points: &[[f64; 3]]) -> Option<([f64; 3], [f64; 3])> {
    let first = *points.first()?;
    Some(points.iter().fold((first, first), |(lo, hi), p| {
        (
            [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
            [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
        )
    }))
}

/// The mean physical gap between consecutive drawn slices.
pub(crate) fn mean_gap(input: &SparseMask<'_>, frame: &Frame) -> f64 {
    let d = input.drawn;
    if d.len() < 2 {
        return frame.spacing[2];
    }
    (d[d.len() - 1] - d[0]) as f64 / (d.len() - 1) as f64 * frame.spacing[2]
}

/// The largest physical gap between two consecutive drawn slices that both
/// hold foreground (0 when no such pair exists). A drawn-empty slice in
/// between ends an object, so it breaks the pair.
pub(crate) fn max_filled_gap(input: &SparseMask<'_>, frame: &Frame) -> f64 {
    let filled: Vec<bool> = input
        .drawn
        .par_iter()
        .map(|&d| {
            let s = input
                .mask
                .slice(input.axis, d)
                .expect("validated drawn index");
            s.iter().any(|&v| v)
        })
        .collect();
    (1..input.drawn.len())
        .filter(|&i| filled[i - 1] && filled[i])
        .map(|i| (input.drawn[i] - input.drawn[i - 1]) as f64 * frame.spacing[2])
        .fold(0.0, f64::max)
}

/// `marching-cubes`: the original method. Marching cubes (iso 0.5) on the
/// volume made of the drawn slices only, stacked without gaps, then every
/// vertex's slice coordinate mapped back through the drawn indices so the
/// surface stretches over the full volume; voxelised, drawn slices restored.
///
/// A pixel inside on drawn slice A and outside on the next drawn slice B
/// gives a surface crossing halfway between A and B, so skipped slices take
/// the shape of the nearer drawn slice (with diagonal facets): accuracy
/// drops quickly as more slices are skipped, as the original study found.
/// The surface is closed half a slice beyond the first and last drawn
/// slices, so nothing is added outside the drawn range.
#[derive(Debug, Clone, Copy, Default)]
pub struct MarchingCubesMethod;

impl Interpolator for MarchingCubesMethod {
    fn name(&self) -> &'static str {
        "marching-cubes"
    }
    fn description(&self) -> &'static str {
        "original: marching cubes on the stacked drawn slices, stretched back along the axis, voxelised"
    }
    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        voxelise_surface(self, input)
    }
    fn surface_mesh(&self, input: SparseMask<'_>) -> Result<Option<TriMesh>, InterpError> {
        input.validate()?;
        Ok(Some(stack_surface(&input)))
    }
}

/// The `marching-cubes` surface, in (x, y, z).
fn stack_surface(input: &SparseMask<'_>) -> TriMesh {
    let frame = Frame::of(input);
    let (w, h) = (frame.dims[0], frame.dims[1]);
    let slices = crate::slices::drawn_slices(input);
    // In-plane bounding box over all drawn slices.
    let mut lo = [usize::MAX; 2];
    let mut hi = [0usize; 2];
    for s in &slices {
        for (idx, _) in s.iter().enumerate().filter(|(_, v)| **v) {
            let (u, v) = (idx % w, idx / w);
            lo = [lo[0].min(u), lo[1].min(v)];
            hi = [hi[0].max(u), hi[1].max(v)];
        }
    }
    if lo[0] == usize::MAX {
        return TriMesh::new();
    }
    let size = [hi[0] - lo[0] + 3, hi[1] - lo[1] + 3, slices.len() + 2];
    let us = frame.centres(0, lo[0] as isize - 1, hi[0] as isize + 2);
    let vs = frame.centres(1, lo[1] as isize - 1, hi[1] as isize + 2);
    let sw = frame.spacing[2];
    let d = input.drawn;
    let mut ws = Vec::with_capacity(size[2]);
    ws.push((d[0] as f64 - 0.5) * sw);
    ws.extend(d.iter().map(|&k| (k as f64 + 0.5) * sw));
    ws.push((d[d.len() - 1] as f64 + 1.5) * sw);
    let mut values = vec![0u8; size[0] * size[1] * size[2]];
    values
        .par_chunks_mut(size[0] * size[1])
        .enumerate()
        .for_each(|(m, plane)| {
            if m == 0 || m == size[2] - 1 {
                return;
            }
            let s = &slices[m - 1];
            for b in 1..size[1] - 1 {
                for a in 1..size[0] - 1 {
                    plane[a + size[0] * b] = u8::from(s[(lo[0] + a - 1) + w * (lo[1] + b - 1)]);
                }
            }
        });
    debug_assert!(hi[1] < h);
    let mesh = marching_cubes(
        Grid {
            values: &values,
            xs: &us,
            ys: &vs,
            zs: &ws,
        },
        0.5,
    );
    frame.to_xyz(mesh)
}
