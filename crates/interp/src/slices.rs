//! Slice plumbing shared by the slice-wise methods: reading the drawn slices
//! and assembling a volume from per-slice results without holding the volume
//! twice along the fast axis.
use crate::{InterpError, SparseMask};
use interslice_core::{Axis, Geometry, Mask, Volume};
use rayon::prelude::*;

/// The in-slice shape `(width, height)` and physical spacing `[su, sv]` of
/// slices along the input's axis, and the spacing between slices.
#[derive(Debug, Clone, Copy)]
pub struct Plane {
    /// Pixels along u.
    pub width: usize,
    /// Pixels along v.
    pub height: usize,
    /// Physical pixel size along u and v.
    pub spacing: [f64; 2],
    /// Physical distance between consecutive slices.
    pub slice_spacing: f64,
}

impl Plane {
    /// The equivalent radius `sqrt(area / π)` of `pixels` pixels of this
    /// plane, in physical units: how large an outline is, whatever its shape.
    pub fn equivalent_radius(&self, pixels: f64) -> f64 {
        (pixels * self.spacing[0] * self.spacing[1] / std::f64::consts::PI).sqrt()
    }

    /// The plane of slices along `input.axis`.
    pub fn of(input: &SparseMask<'_>) -> Plane {
        Plane::along(input.mask.geometry(), input.axis)
    }

    /// The plane of slices of a volume of `geometry` along `axis`.
    pub fn along(geometry: &Geometry, axis: Axis) -> Plane {
        let (a, b) = axis.in_plane();
        Plane {
            width: geometry.dims[a],
            height: geometry.dims[b],
            spacing: [geometry.spacing[a], geometry.spacing[b]],
            slice_spacing: geometry.spacing[axis.dim()],
        }
    }

    /// Pixels per slice.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// True for a plane without pixels (never for a validated geometry).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The drawn slices of the input as row-major buffers, read in parallel.
pub fn drawn_slices(input: &SparseMask<'_>) -> Vec<Vec<bool>> {
    input
        .drawn
        .par_iter()
        .map(|&d| {
            input
                .mask
                .slice(input.axis, d)
                .expect("validated drawn index")
        })
        .collect()
}

/// Build the output mask: drawn slices copied from the input, every other
/// slice from `produce(index)` (`None` = empty). Slices are produced in
/// parallel; along z they are written in place, along x and y collected first
/// and then scattered in parallel over z-planes.
pub fn assemble(
    input: &SparseMask<'_>,
    produce: impl Fn(usize) -> Option<Vec<bool>> + Sync,
) -> Result<Mask, InterpError> {
    // Once cancelled, no further slice is produced and the run ends in
    // `Err(Cancelled)`: a dropped request stops within one slice's work.
    // Slices the caller does not read (`SparseMask::only`) are left empty.
    let produce = |s: usize| {
        if input.is_cancelled() || !input.wants(s) {
            None
        } else {
            produce(s)
        }
    };
    let geometry = input.mask.geometry().clone();
    let axis = input.axis;
    let n = input.mask.slice_count(axis);
    let mut is_drawn = vec![false; n];
    for &d in input.drawn {
        is_drawn[d] = true;
    }
    let [nx, ny, _] = geometry.dims;
    let src = input.mask.data();
    let mut out: Mask = Volume::zeros(geometry);
    match axis {
        Axis::Z => {
            let plane = nx * ny;
            out.data_mut()
                .par_chunks_mut(plane)
                .enumerate()
                .for_each(|(k, chunk)| {
                    if is_drawn[k] {
                        chunk.copy_from_slice(&src[k * plane..(k + 1) * plane]);
                    } else if let Some(s) = produce(k) {
                        chunk.copy_from_slice(&s);
                    }
                });
        }
        Axis::X | Axis::Y => {
            let slices: Vec<Option<Vec<bool>>> = (0..n)
                .into_par_iter()
                .map(|s| if is_drawn[s] { None } else { produce(s) })
                .collect();
            out.data_mut()
                .par_chunks_mut(nx * ny)
                .enumerate()
                .for_each(|(k, chunk)| {
                    let base = k * nx * ny;
                    for j in 0..ny {
                        for i in 0..nx {
                            let idx = i + nx * j;
                            let (s, u, v) = axis.split([i, j, k]);
                            chunk[idx] = if is_drawn[s] {
                                src[base + idx]
                            } else {
                                match &slices[s] {
                                    Some(buf) => {
                                        let w = if axis == Axis::X { ny } else { nx };
                                        buf[u + w * v]
                                    }
                                    None => false,
                                }
                            };
                        }
                    }
                });
        }
    }
    input.check_cancelled()?;
    Ok(out)
}

/// For slice `s`, the pair of consecutive drawn positions `(i, i + 1)` in
/// `drawn` with `drawn[i] < s < drawn[i + 1]`, or `None` outside the drawn
/// range (or on a drawn slice).
pub fn bracket(drawn: &[usize], s: usize) -> Option<usize> {
    let p = drawn.partition_point(|&d| d < s);
    if p == 0 || p >= drawn.len() || drawn[p] == s {
        return None;
    }
    Some(p - 1)
}

/// The median of the gaps between consecutive `drawn` slices (the upper
/// one of an even count); `None` for fewer than two.
pub fn median_gap(drawn: &[usize]) -> Option<usize> {
    let mut gaps: Vec<usize> = drawn.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    gaps.get(gaps.len() / 2).copied()
}

/// Whether each drawn slice of `input` shows the structure.
pub fn showing(input: &SparseMask<'_>) -> Result<Vec<bool>, InterpError> {
    input
        .drawn
        .iter()
        .map(|&d| shows_on(input.mask, input.axis, d))
        .collect()
}

/// Whether `mask` holds any voxel on slice `s` along `axis` (read in place,
/// not copied); an error for a slice out of range.
pub fn shows_on(mask: &Mask, axis: Axis, s: usize) -> Result<bool, InterpError> {
    Ok(mask.view(axis, s)?.iter().any(|x| x))
}

/// The centroid `[u, v]` of the pixels inside a row-major slice `width`
/// pixels wide, read within its extent `[u0, u1, v0, v1]` (inclusive);
/// `None` where nothing there is inside.
pub fn centroid(inside: &[bool], width: usize, [u0, u1, v0, v1]: [usize; 4]) -> Option<[f64; 2]> {
    let (mut n, mut su, mut sv) = (0usize, 0usize, 0usize);
    for v in v0..=v1 {
        for (u, &x) in inside[v * width + u0..=v * width + u1].iter().enumerate() {
            if x {
                n += 1;
                su += u0 + u;
                sv += v;
            }
        }
    }
    (n > 0).then(|| [su as f64 / n as f64, sv as f64 / n as f64])
}

/// Slices from skipped slice `s` to the nearest drawn slice (`δ`, what
/// the confidence and the image fusion scale with), or `None` where
/// [`bracket`] is.
pub fn to_nearest_drawn(drawn: &[usize], s: usize) -> Option<f64> {
    let g = bracket(drawn, s)?;
    Some((s - drawn[g]).min(drawn[g + 1] - s) as f64)
}
