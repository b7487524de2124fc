//! One label traced on slices of several orientations (x, y and z slices of
//! the same volume) combined into one 3D mask.
//!
//! Every slice-wise method interpolates along one axis only. With slices of
//! two or three orientations, a union of the per-axis results would grow the
//! object wherever any axis guesses too wide, and an intersection would cut
//! it wherever any axis guesses too narrow (and outside the range of one axis
//! everything would go). Instead the per-axis results are blended as
//! *shapes*:
//!
//! 1. each axis with at least two drawn slices is interpolated on its own
//!    with the chosen method (which reproduces its drawn slices exactly);
//! 2. each result becomes a signed distance field in physical units
//!    (negative inside; the exact anisotropic EDT of `core::edt`, `f32`);
//! 3. the fields are averaged per voxel with the weight
//!    `w_a = 1 / (d_a / h + 1)²`, where `d_a` is the physical distance along
//!    axis `a` from the voxel to the nearest drawn slice of `a` and `h` the
//!    finest voxel spacing; an axis whose drawn range does not hold the voxel
//!    (no drawn slice on one side) has weight 0, because its method produces
//!    nothing there: it does not know, rather than knowing "outside";
//! 4. the object is where the average is negative;
//! 5. every drawn slice of every axis is written back exactly, also those of
//!    an axis with a single drawn slice (which takes no part in steps 1–4:
//!    one slice does not say how the object goes on along its axis). Where two
//!    drawn slices cross, their masks agree on the crossing line (checked
//!    first by [`check_crossings`]); the few voxels tolerated to differ there
//!    are inside only when both slices say inside.
//!
//! Why this and not a surface fitted through all contours at once (MITK's
//! surface interpolation of contours of arbitrary orientation, a radial basis
//! function through points on the contours and normals): an RBF system grows
//! with the number of contour points (dense solves of thousands of points, a
//! fit that must be regularised and can bulge between sparse contours), does
//! not reproduce the drawn slices voxel for voxel without the same final
//! stamping, and would drop the leave-one-out choice of method per label that
//! the slice-wise default makes. The blend reuses that choice along every
//! axis, costs one interpolation and two EDTs per axis, runs in parallel and
//! holds at most one `f32` field besides the accumulator. The inverse-square
//! weight makes the blend follow the nearest drawn slice of any orientation,
//! so the result is continuous with the slices stamped in step 5 (with
//! `1 / (d + 1)` a far axis still pulls a voxel next to a drawn slice away
//! from it, and the stamping leaves a step there).
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::edt::squared_edt_3d_f32;
use interslice_core::{Axis, Mask, Volume};
use rayon::prelude::*;

/// The number of voxels in a row along which two crossing drawn slices may
/// disagree (a contour drawn on x and one drawn on z rasterise a boundary up
/// to one voxel apart); a longer run of disagreement is a contradiction.
pub const CROSSING_TOLERANCE: usize = 1;

/// The combined mask of one label traced along several axes (at most one
/// input per axis, all on the same grid; the first with at least two drawn
/// slices, the others with one or more; see the module documentation for the
/// method and why).
///
/// An axis with a single drawn slice gives no interpolation along it: its
/// slice is checked against the others' crossings and written back, and
/// nothing else. With one input of two or more drawn slices the result is
/// `method.interpolate(input)`, bit for bit, plus those slices.
/// Contradicting crossings are a one-line [`InterpError::Input`] naming the
/// two slices. The first input's cancellation token is checked between the
/// stages (one axis's interpolation, each transform, the stamping).
pub fn combine(method: &dyn Interpolator, inputs: &[SparseMask<'_>]) -> Result<Mask, InterpError> {
    let Some(first) = inputs.first() else {
        return Err(InterpError::Input("no drawn slices to interpolate".into()));
    };
    if inputs.len() == 1 {
        return method.interpolate(*first);
    }
    let geometry = first.mask.geometry().clone();
    first.validate()?;
    for (n, input) in inputs.iter().enumerate() {
        if input.drawn.len() >= 2 {
            input.validate()?;
        } else {
            validate_single(input)?;
        }
        if input.mask.geometry().dims != geometry.dims {
            return Err(InterpError::Input(
                "the masks of the axes are not on one grid".into(),
            ));
        }
        if inputs[..n].iter().any(|o| o.axis == input.axis) {
            return Err(InterpError::Input(format!(
                "axis {} is given twice",
                input.axis
            )));
        }
    }
    check_crossings(inputs)?;
    let blended: Vec<&SparseMask<'_>> = inputs.iter().filter(|i| i.drawn.len() >= 2).collect();
    if blended.len() == 1 {
        first.check_cancelled()?;
        let mut out = method.interpolate(*first)?;
        first.check_cancelled()?;
        stamp(&mut out, inputs);
        return Ok(out);
    }
    let dims = geometry.dims;
    let spacing = geometry.spacing;
    let h = spacing.iter().copied().fold(f64::INFINITY, f64::min);
    // Far outside: farther than any voxel can be from any object; an empty or
    // full per-axis result (infinite distances) is clamped to it so that the
    // weighted sum stays finite.
    let far = (0..3)
        .map(|d| dims[d] as f64 * spacing[d])
        .fold(0.0, f64::hypot) as f32
        + 1.0;
    let weights: Vec<Vec<f32>> = inputs.iter().map(|i| axis_weights(i, h)).collect();
    let mut acc = vec![0.0f32; geometry.len()];
    for (input, w) in inputs.iter().zip(&weights) {
        if input.drawn.len() < 2 {
            continue;
        }
        first.check_cancelled()?;
        let result = method.interpolate(*input)?;
        first.check_cancelled()?;
        // Outside distances, then inside distances: one f32 field at a time.
        let outside = squared_edt_3d_f32(result.data(), dims, spacing);
        add_weighted(
            &mut acc,
            &outside,
            result.data(),
            false,
            w,
            input.axis,
            dims,
            far,
        );
        drop(outside);
        first.check_cancelled()?;
        let background: Vec<bool> = result.data().par_iter().map(|&m| !m).collect();
        let inside = squared_edt_3d_f32(&background, dims, spacing);
        drop(background);
        add_weighted(
            &mut acc,
            &inside,
            result.data(),
            true,
            w,
            input.axis,
            dims,
            far,
        );
    }
    first.check_cancelled()?;
    let [nx, ny, _] = dims;
    let mut out: Mask = Volume::zeros(geometry);
    out.data_mut()
        .par_chunks_mut(nx * ny)
        .zip(acc.par_chunks(nx * ny))
        .enumerate()
        .for_each(|(k, (plane, acc))| {
            for j in 0..ny {
                for i in 0..nx {
                    let v = [i, j, k];
                    let idx = i + nx * j;
                    let mut stamped: Option<bool> = None;
                    let mut total = 0.0f32;
                    for (input, w) in inputs.iter().zip(&weights) {
                        let s = v[input.axis.dim()];
                        total += w[s];
                        if input.drawn.binary_search(&s).is_ok() {
                            let m = input.mask.data()[idx + k * nx * ny];
                            stamped = Some(stamped.unwrap_or(true) && m);
                        }
                    }
                    plane[idx] = stamped.unwrap_or(total > 0.0 && acc[idx] < 0.0);
                }
            }
        });
    first.check_cancelled()?;
    Ok(out)
}

/// The checks of [`SparseMask::validate`] for an input of one drawn slice.
fn validate_single(input: &SparseMask<'_>) -> Result<(), InterpError> {
    let n = input.mask.slice_count(input.axis);
    match input.drawn {
        [d] if *d < n => Ok(()),
        [d] => Err(InterpError::Input(format!(
            "drawn slice {}={d} is out of range (0..{n})",
            input.axis
        ))),
        _ => Err(InterpError::Input(format!(
            "no drawn slice along {}",
            input.axis
        ))),
    }
}

/// Write every drawn slice of every input into `out`; where drawn slices
/// cross, inside only where all of them say inside (as the blend does).
fn stamp(out: &mut Mask, inputs: &[SparseMask<'_>]) {
    let g = out.geometry().clone();
    let [nx, ny, nz] = g.dims;
    let data = out.data_mut();
    for input in inputs {
        for &d in input.drawn {
            for (i, j, k) in slice_voxels(input.axis, d, [nx, ny, nz]) {
                let idx = g.index(i, j, k);
                let all = inputs.iter().all(|o| {
                    let v = [i, j, k][o.axis.dim()];
                    o.drawn.binary_search(&v).is_err() || o.mask.data()[idx]
                });
                data[idx] = all;
            }
        }
    }
}

/// The voxels of slice `index` along `axis` of a volume of `dims`.
fn slice_voxels(
    axis: Axis,
    index: usize,
    dims: [usize; 3],
) -> impl Iterator<Item = (usize, usize, usize)> {
    let (a, b) = axis.in_plane();
    (0..dims[b]).flat_map(move |v| {
        (0..dims[a]).map(move |u| {
            let [i, j, k] = axis.voxel(index, u, v);
            (i, j, k)
        })
    })
}

/// The blending weight of every slice along the input's axis: `1 / (d/h + 1)²`
/// inside the drawn range (`d` the physical distance to the nearest drawn
/// slice), 0 outside it.
fn axis_weights(input: &SparseMask<'_>, h: f64) -> Vec<f32> {
    let n = input.mask.slice_count(input.axis);
    let step = input.mask.geometry().spacing[input.axis.dim()];
    let (lo, hi) = (input.drawn[0], input.drawn[input.drawn.len() - 1]);
    (0..n)
        .map(|s| {
            if s < lo || s > hi {
                return 0.0;
            }
            let p = input.drawn.partition_point(|&d| d < s);
            let next = input.drawn.get(p).map_or(usize::MAX, |&d| d - s);
            let prev = p.checked_sub(1).map_or(usize::MAX, |q| s - input.drawn[q]);
            let d = next.min(prev) as f64 * step / h;
            (1.0 / ((d + 1.0) * (d + 1.0))) as f32
        })
        .collect()
}

/// Add `w · (±√squared)` to the accumulator at the voxels where `mask` is
/// `inside` (negative distances inside, positive outside).
#[allow(clippy::too_many_arguments)]
fn add_weighted(
    acc: &mut [f32],
    squared: &[f32],
    mask: &[bool],
    inside: bool,
    w: &[f32],
    axis: Axis,
    dims: [usize; 3],
    far: f32,
) {
    let [nx, ny, _] = dims;
    let sign = if inside { -1.0 } else { 1.0 };
    acc.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, plane)| {
            let base = k * nx * ny;
            for j in 0..ny {
                for i in 0..nx {
                    let idx = i + nx * j;
                    if mask[base + idx] != inside {
                        continue;
                    }
                    let weight = w[[i, j, k][axis.dim()]];
                    if weight > 0.0 {
                        plane[idx] += weight * sign * squared[base + idx].sqrt().min(far);
                    }
                }
            }
        });
}

/// Check that drawn slices of different axes agree where they cross: along
/// each crossing line (a row of voxels along the third axis), no run of more
/// than [`CROSSING_TOLERANCE`] voxels where one slice says inside and the
/// other outside (or drawn empty). The first contradiction is a one-line
/// error naming both slices, the run and what to do.
pub fn check_crossings(inputs: &[SparseMask<'_>]) -> Result<(), InterpError> {
    for (n, a) in inputs.iter().enumerate() {
        for b in &inputs[n + 1..] {
            let c = third_axis(a.axis, b.axis);
            let len = a.mask.slice_count(c);
            for &i in a.drawn {
                for &j in b.drawn {
                    let mut run: Option<(usize, bool)> = None;
                    for t in 0..=len {
                        let differ = (t < len).then(|| {
                            let mut v = [0usize; 3];
                            v[a.axis.dim()] = i;
                            v[b.axis.dim()] = j;
                            v[c.dim()] = t;
                            let pa = a.mask.get(v[0], v[1], v[2]);
                            (pa != b.mask.get(v[0], v[1], v[2])).then_some(pa)
                        });
                        match (run, differ.flatten()) {
                            (None, Some(pa)) => run = Some((t, pa)),
                            (Some((start, pa)), d) if d != Some(pa) => {
                                if t - start > CROSSING_TOLERANCE {
                                    return Err(contradiction(a, i, b, j, c, start, t - 1, pa));
                                }
                                run = d.map(|pa| (t, pa));
                            }
                            _ => {}
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// The axis that is neither `a` nor `b`.
fn third_axis(a: Axis, b: Axis) -> Axis {
    [Axis::X, Axis::Y, Axis::Z]
        .into_iter()
        .find(|&c| c != a && c != b)
        .expect("two distinct axes")
}

/// The message of a contradiction between slice `a = i` and slice `b = j`
/// over `c = start..=end`, where `a_inside` says which of them says inside.
#[allow(clippy::too_many_arguments)]
fn contradiction(
    a: &SparseMask<'_>,
    i: usize,
    b: &SparseMask<'_>,
    j: usize,
    c: Axis,
    start: usize,
    end: usize,
    a_inside: bool,
) -> InterpError {
    let ((ia, si), (ib, sb)) = if a_inside {
        ((a, i), (b, j))
    } else {
        ((b, j), (a, i))
    };
    let empty = !ib
        .mask
        .slice(ib.axis, sb)
        .map(|s| s.contains(&true))
        .unwrap_or(true);
    InterpError::Input(format!(
        "drawn slices {}={si} and {}={sb} contradict where they cross: {}={si} is inside \
         and {}={sb} {} over {} voxels ({c}={start}..{end}); redraw one of them so that \
         both agree along the line where they cross",
        ia.axis,
        ib.axis,
        ia.axis,
        ib.axis,
        if empty {
            "is drawn empty"
        } else {
            "is outside"
        },
        end - start + 1,
    ))
}
