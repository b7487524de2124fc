//! Several labels at once: each label is interpolated on its own (labels in
//! parallel) and the results are painted in ascending label order, so an inner
//! structure (higher label) overwrites the one that contains it.
//!
//! A label volume is a painted partition, so the cell's voxels on a drawn
//! slice are the cell *minus* its nucleus. The outline the person traced is
//! recovered before interpolating: holes of a label's mask that are filled
//! entirely by higher labels (the nucleus inside the cell) belong to the
//! label's own mask. Holes holding background stay holes. Painting in
//! ascending order then reproduces every drawn slice exactly.
//!
//! A method that reads no further than its tracing's surroundings
//! ([`Interpolator::box_reach`]) runs on the label's box only
//! ([`crate::crop`]).
use crate::crop::{DrawnSlice, LabelBox};
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::morph::Connectivity;
use interslice_core::regions::whole_structure;
use interslice_core::{Axis, Geometry, LabelVolume, Mask, Volume, Voxel};
use rayon::prelude::*;

/// Interpolate every label of `sparse` from its drawn slices along `axis`.
///
/// `drawn` lists the drawn slice indices (any order, duplicates allowed); a
/// drawn slice without a label is a known-empty slice for that label. Errors
/// for fewer than two drawn slices or an index out of range.
pub fn interpolate_labels(
    method: &dyn Interpolator,
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
) -> Result<LabelVolume, InterpError> {
    Ok(run(method, sparse, axis, drawn, false, |l| l)?.0)
}

/// [`interpolate_labels`] painting `value(label)` into a volume of another
/// voxel type, so a caller holding labels in a narrower or wider type (a
/// numpy array of uint8, a mask) gets its result without converting the
/// whole volume afterwards.
pub fn interpolate_labels_as<T: Voxel>(
    method: &dyn Interpolator,
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
    value: impl Fn(u16) -> T,
) -> Result<Volume<T>, InterpError> {
    Ok(run(method, sparse, axis, drawn, false, value)?.0)
}

/// [`interpolate_labels`] with the confidence per voxel: the least
/// confidence of any label there (each label's from
/// [`Interpolator::interpolate_with_confidence`]), 1 where no label is unsure.
pub fn interpolate_labels_with_confidence(
    method: &dyn Interpolator,
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
) -> Result<(LabelVolume, Volume<f32>), InterpError> {
    let (labels, conf) = run(method, sparse, axis, drawn, true, |l| l)?;
    Ok((labels, conf.expect("confidence requested")))
}

/// A label's result: on its box ([`crate::crop`]) or on the whole volume.
enum Piece {
    Boxed(LabelBox, Mask),
    Whole(Mask),
}

/// A label's result and, when asked, its confidence.
type LabelResult = Result<(Piece, Option<Volume<f32>>), InterpError>;

fn run<T: Voxel>(
    method: &dyn Interpolator,
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
    confidence: bool,
    value: impl Fn(u16) -> T,
) -> Result<(Volume<T>, Option<Volume<f32>>), InterpError> {
    let drawn = sorted_drawn(sparse, axis, drawn)?;
    if drawn.len() < 2 {
        return Err(InterpError::Input(format!(
            "interpolation needs at least two drawn slices along {axis}, got {}",
            drawn.len()
        )));
    }
    let labels: Vec<u16> = drawn_labels(sparse, axis, &drawn);
    let results: Vec<LabelResult> = labels
        .par_iter()
        .map(|&l| {
            let filled = traced_slices(sparse, axis, &drawn, l);
            if !confidence {
                let slices: Vec<DrawnSlice<'_>> = drawn
                    .iter()
                    .zip(&filled)
                    .map(|(&index, inside)| DrawnSlice { index, inside })
                    .collect();
                let dims = sparse.geometry().dims;
                if let Some(b) = LabelBox::of(dims, axis, &slices, method.box_reach())
                    && let Some(m) = b.interpolate(method, sparse.geometry(), axis, &slices)?
                {
                    return Ok((Piece::Boxed(b, m), None));
                }
            }
            let m = mask_of_slices(sparse, axis, &drawn, &filled);
            let input = SparseMask::new(&m, axis, &drawn);
            if confidence {
                let (mask, c) = method.interpolate_with_confidence(input)?;
                Ok((Piece::Whole(mask), Some(c)))
            } else {
                Ok((Piece::Whole(method.interpolate(input)?), None))
            }
        })
        .collect();
    let mut out: Volume<T> = Volume::zeros(sparse.geometry().clone());
    let mut conf: Option<Volume<f32>> =
        confidence.then(|| Volume::filled(sparse.geometry().clone(), 1.0f32));
    for (&l, r) in labels.iter().zip(results) {
        let (piece, c) = r?;
        let v = value(l);
        match piece {
            Piece::Boxed(b, m) => b.paint(&mut out, &m, v),
            Piece::Whole(m) => out
                .data_mut()
                .par_iter_mut()
                .zip(m.data().par_iter())
                .for_each(|(o, &inside)| {
                    if inside {
                        *o = v;
                    }
                }),
        }
        if let (Some(all), Some(c)) = (conf.as_mut(), c) {
            all.data_mut()
                .par_iter_mut()
                .zip(c.data().par_iter())
                .for_each(|(a, &x)| *a = a.min(x));
        }
    }
    Ok((out, conf))
}

/// The drawn slices sorted and de-duplicated; an error names the first one
/// outside the volume along `axis`.
pub fn sorted_drawn(
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
) -> Result<Vec<usize>, InterpError> {
    let mut drawn = drawn.to_vec();
    drawn.sort_unstable();
    drawn.dedup();
    let n = sparse.slice_count(axis);
    if let Some(&bad) = drawn.iter().find(|&&d| d >= n) {
        return Err(InterpError::Input(format!(
            "drawn slice {axis}={bad} is out of range (0..{n})"
        )));
    }
    Ok(drawn)
}

/// Labels present on the drawn slices, ascending (each is interpolated on
/// its own, so their number is the cost: callers bound it before
/// interpolating a volume that may be an intensity image). `drawn` must be
/// valid indices along `axis`.
pub fn drawn_labels(sparse: &LabelVolume, axis: Axis, drawn: &[usize]) -> Vec<u16> {
    let mut seen = vec![false; 65536];
    for &d in drawn {
        for v in sparse.slice(axis, d).expect("validated drawn index") {
            seen[v as usize] = true;
        }
    }
    (1..65536).filter(|&l| seen[l]).map(|l| l as u16).collect()
}

/// The traced mask of `label` on the drawn slices (other slices empty): the
/// whole structure of the label on each, as a 2D image with 8-connected
/// holes ([`interslice_core::regions::whole_structure`]).
pub fn traced_mask(sparse: &LabelVolume, axis: Axis, drawn: &[usize], label: u16) -> Mask {
    mask_of_slices(
        sparse,
        axis,
        drawn,
        &traced_slices(sparse, axis, drawn, label),
    )
}

/// The whole structure of `label` on each drawn slice, row-major as
/// [`Volume::slice`] gives it.
fn traced_slices(sparse: &LabelVolume, axis: Axis, drawn: &[usize], label: u16) -> Vec<Vec<bool>> {
    let (w, h) = sparse.slice_shape(axis);
    drawn
        .par_iter()
        .map(|&d| {
            let s = sparse.slice(axis, d).expect("validated drawn index");
            let g = Geometry::new([w, h, 1], [1.0; 3], sparse.geometry().unit)
                .expect("slice dims of a valid volume");
            let slice = Volume::from_vec(g, s).expect("slice size");
            whole_structure(&slice, label, Connectivity::Full)
                .into_parts()
                .1
        })
        .collect()
}

/// A mask of `sparse`'s grid holding `filled` on the drawn slices.
fn mask_of_slices(sparse: &LabelVolume, axis: Axis, drawn: &[usize], filled: &[Vec<bool>]) -> Mask {
    let mut m: Mask = Volume::zeros(sparse.geometry().clone());
    for (&d, f) in drawn.iter().zip(filled) {
        m.set_slice(axis, d, f).expect("slice shape matches");
    }
    m
}
