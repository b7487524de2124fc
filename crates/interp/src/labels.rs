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
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::{Axis, LabelVolume, Mask, Volume};
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
    Ok(run(method, sparse, axis, drawn, false)?.0)
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
    let (labels, conf) = run(method, sparse, axis, drawn, true)?;
    Ok((labels, conf.expect("confidence requested")))
}

/// A label's result and, when asked, its confidence.
type LabelResult = Result<(Mask, Option<Volume<f32>>), InterpError>;

fn run(
    method: &dyn Interpolator,
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
    confidence: bool,
) -> Result<(LabelVolume, Option<Volume<f32>>), InterpError> {
    let mut drawn = drawn.to_vec();
    drawn.sort_unstable();
    drawn.dedup();
    let n = sparse.slice_count(axis);
    if let Some(&bad) = drawn.iter().find(|&&d| d >= n) {
        return Err(InterpError::Input(format!(
            "drawn slice {axis}={bad} is out of range (0..{n})"
        )));
    }
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
            let m = traced_mask(sparse, axis, &drawn, l);
            let input = SparseMask {
                mask: &m,
                axis,
                drawn: &drawn,
            };
            if confidence {
                let (mask, c) = method.interpolate_with_confidence(input)?;
                Ok((mask, Some(c)))
            } else {
                Ok((method.interpolate(input)?, None))
            }
        })
        .collect();
    let mut out: LabelVolume = Volume::zeros(sparse.geometry().clone());
    let mut conf: Option<Volume<f32>> =
        confidence.then(|| Volume::filled(sparse.geometry().clone(), 1.0f32));
    for (l, r) in labels.iter().zip(results) {
        let (m, c) = r?;
        out.data_mut()
            .par_iter_mut()
            .zip(m.data().par_iter())
            .for_each(|(o, &inside)| {
                if inside {
                    *o = *l;
                }
            });
        if let (Some(all), Some(c)) = (conf.as_mut(), c) {
            all.data_mut()
                .par_iter_mut()
                .zip(c.data().par_iter())
                .for_each(|(a, &x)| *a = a.min(x));
        }
    }
    Ok((out, conf))
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
/// label's voxels plus the holes that are filled entirely by higher labels.
pub fn traced_mask(sparse: &LabelVolume, axis: Axis, drawn: &[usize], label: u16) -> Mask {
    let mut m: Mask = Volume::zeros(sparse.geometry().clone());
    let (w, h) = sparse.slice_shape(axis);
    let filled: Vec<Vec<bool>> = drawn
        .par_iter()
        .map(|&d| {
            let s = sparse.slice(axis, d).expect("validated drawn index");
            fill_nested_holes(&s, w, h, label)
        })
        .collect();
    for (&d, f) in drawn.iter().zip(&filled) {
        m.set_slice(axis, d, f).expect("slice shape matches");
    }
    m
}

/// `labels == label`, with every hole (8-connected component of the rest not
/// touching the slice border) whose pixels all carry a higher label filled in.
pub fn fill_nested_holes(labels: &[u16], w: usize, h: usize, label: u16) -> Vec<bool> {
    let mut mask: Vec<bool> = labels.iter().map(|&v| v == label).collect();
    if !labels.iter().any(|&v| v > label) {
        return mask;
    }
    // 0 = unvisited, 1 = visited.
    let mut seen = vec![false; w * h];
    let mut stack = Vec::new();
    let mut comp = Vec::new();
    for start in 0..w * h {
        if mask[start] || seen[start] {
            continue;
        }
        comp.clear();
        stack.push(start);
        seen[start] = true;
        let mut touches_border = false;
        let mut all_higher = true;
        while let Some(p) = stack.pop() {
            comp.push(p);
            let (u, v) = (p % w, p / w);
            if u == 0 || v == 0 || u + 1 == w || v + 1 == h {
                touches_border = true;
            }
            if labels[p] <= label {
                all_higher = false;
            }
            for dv in -1i64..=1 {
                for du in -1i64..=1 {
                    let (nu, nv) = (u as i64 + du, v as i64 + dv);
                    if nu < 0 || nv < 0 || nu >= w as i64 || nv >= h as i64 {
                        continue;
                    }
                    let q = nu as usize + w * nv as usize;
                    if !mask[q] && !seen[q] {
                        seen[q] = true;
                        stack.push(q);
                    }
                }
            }
        }
        if !touches_border && all_higher {
            for &p in &comp {
                mask[p] = true;
            }
        }
    }
    mask
}
