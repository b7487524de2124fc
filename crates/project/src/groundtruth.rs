//! A user's ground truth of a cell: their contours rasterised into sparse masks
//! and interpolated, one label at a time, then painted in ascending label
//! order (an inner structure overwrites the one containing it).
//!
//! The tracing comes from the annotation database ([`StoredTracing`], what
//! the server and `interslice export` use) or from a contours file
//! ([`FileTracing`], what `interslice interpolate CONTOURS.json` uses); both
//! go through [`label_volume`], so one tracing gives one label volume
//! whichever way it is interpolated. Each label keeps its own drawn slices: a
//! slice drawn for the nucleus says nothing about the cell outline there.
//! A label drawn on slices of several axes (x, y and z slices) gives one 3D
//! result that keeps every drawn slice of every axis
//! ([`interslice_interp::multi_axis`]), not a union of per-axis results.
use crate::error::ProjectError;
use interslice_core::contour_file::ContourFile;
use interslice_core::{Axis, Cancel, Contour, Geometry, LabelVolume, Mask, Volume};
use interslice_interp::confidence::shape_confidence;
use interslice_interp::image::Conditioned;
use interslice_interp::labels;
use interslice_interp::{InterpError, Interpolator, SparseMask, multi_axis};
use interslice_store::{ContourQuery, Store, StoredContour};
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::sync::{Arc, Mutex};

/// Stored contours as core contours.
pub fn to_core(stored: &[StoredContour]) -> Vec<Contour> {
    stored.iter().map(|c| c.contour.clone()).collect()
}

/// What one user traced on one cell, wherever it is kept.
pub trait Tracing {
    /// Every (label, axis) with anything drawn, with its number of drawn
    /// slices (traced or drawn empty).
    fn drawn_labels(&self) -> Result<Vec<(u16, Axis, usize)>, ProjectError>;
    /// The contours of `label` on the slices across `axis`.
    fn contours(&self, label: u16, axis: Axis) -> Result<Vec<Contour>, ProjectError>;
    /// The drawn slices of `label` along `axis` (traced or drawn empty), ascending.
    fn drawn(&self, label: u16, axis: Axis) -> Result<Vec<usize>, ProjectError>;
    /// Whose tracing of what, for messages ("cell 'c1' by this user").
    fn describe(&self) -> String;
}

/// A user's tracing of a cell in the annotation database.
pub struct StoredTracing<'a> {
    /// The database.
    pub store: &'a Store,
    /// The cell id.
    pub cell: &'a str,
    /// The user.
    pub user_id: i64,
}

impl Tracing for StoredTracing<'_> {
    fn drawn_labels(&self) -> Result<Vec<(u16, Axis, usize)>, ProjectError> {
        Ok(self.store.drawn_labels(self.cell, self.user_id)?)
    }

    fn contours(&self, label: u16, axis: Axis) -> Result<Vec<Contour>, ProjectError> {
        let stored = self.store.contours(&ContourQuery {
            cell: self.cell.to_string(),
            user_id: self.user_id,
            axis: Some(axis),
            index: None,
            label: Some(label),
        })?;
        Ok(to_core(&stored))
    }

    fn drawn(&self, label: u16, axis: Axis) -> Result<Vec<usize>, ProjectError> {
        Ok(self
            .store
            .drawn(self.cell, self.user_id, label, axis)?
            .into_iter()
            .map(|d| d.index)
            .collect())
    }

    fn describe(&self) -> String {
        format!("cell '{}' by this user", self.cell)
    }
}

/// The tracing in a contours file (every contour and drawn-empty slice of
/// the file, whoever drew it).
pub struct FileTracing<'a> {
    /// The file's contents.
    pub file: &'a ContourFile,
    /// Its name, for messages.
    pub name: &'a str,
}

impl FileTracing<'_> {
    fn drawn_sets(&self) -> BTreeMap<(u16, Axis), BTreeSet<usize>> {
        let mut out: BTreeMap<(u16, Axis), BTreeSet<usize>> = BTreeMap::new();
        let contours = self.file.contours.iter().map(|c| (c.label, c.slice));
        let empty = self.file.drawn_empty.iter().map(|d| (d.label, d.slice));
        for (label, slice) in contours.chain(empty) {
            out.entry((label, slice.axis))
                .or_default()
                .insert(slice.index);
        }
        out
    }
}

impl Tracing for FileTracing<'_> {
    fn drawn_labels(&self) -> Result<Vec<(u16, Axis, usize)>, ProjectError> {
        Ok(self
            .drawn_sets()
            .into_iter()
            .map(|((label, axis), s)| (label, axis, s.len()))
            .collect())
    }

    fn contours(&self, label: u16, axis: Axis) -> Result<Vec<Contour>, ProjectError> {
        Ok(self
            .file
            .contours
            .iter()
            .filter(|c| c.label == label && c.slice.axis == axis)
            .cloned()
            .collect())
    }

    fn drawn(&self, label: u16, axis: Axis) -> Result<Vec<usize>, ProjectError> {
        Ok(self
            .drawn_sets()
            .remove(&(label, axis))
            .map(|s| s.into_iter().collect())
            .unwrap_or_default())
    }

    fn describe(&self) -> String {
        self.name.to_string()
    }
}

/// The sparse mask of one label along one axis and its drawn slices (with
/// contours or marked empty).
pub fn sparse_mask(
    tracing: &dyn Tracing,
    geometry: &Geometry,
    label: u16,
    axis: Axis,
) -> Result<(Mask, Vec<usize>), ProjectError> {
    let contours = tracing.contours(label, axis)?;
    let drawn = tracing.drawn(label, axis)?;
    let mask = interslice_core::raster::contours_to_mask(geometry, &contours, label)?;
    Ok((mask, drawn))
}

/// Which slices of one label along one axis to trace next, best first
/// ([`interslice_interp::advise`]): the server's suggestion for the tracer.
/// `image` (the cell's intensities) goes with the image-guided method.
pub fn advise_label(
    tracing: &dyn Tracing,
    geometry: &Geometry,
    label: u16,
    axis: Axis,
    count: usize,
    method: Option<&str>,
    image: Option<Conditioned>,
) -> Result<interslice_interp::advise::Advice, ProjectError> {
    let (mask, drawn) = sparse_mask(tracing, geometry, label, axis)?;
    let data = mask
        .data()
        .iter()
        .map(|&b| if b { label } else { 0 })
        .collect();
    let sparse = LabelVolume::from_vec(geometry.clone(), data)?;
    Ok(interslice_interp::advise::advise(
        &sparse, axis, &drawn, count, method, image,
    )?)
}

/// Interpolate one label of one tracing from its drawn slices along `axis`
/// and along every other axis with drawn slices for it (one 3D result,
/// [`interslice_interp::multi_axis::combine`]; an axis with a single drawn
/// slice only has it written back); returns the mask and
/// the drawn slices along `axis` (what a preview along `axis` marks as
/// drawn). `axis` itself needs two drawn slices. `cancel` is checked before
/// and after the method runs and between the stages of a combination.
pub fn interpolate_label(
    tracing: &dyn Tracing,
    geometry: &Geometry,
    label: u16,
    axis: Axis,
    method: &dyn Interpolator,
    cancel: &Cancel,
) -> Result<(Mask, Vec<usize>), ProjectError> {
    let (mask, drawn, _) =
        interpolate_label_with_confidence(tracing, geometry, label, axis, method, false, cancel)?;
    Ok((mask, drawn))
}

/// [`interpolate_label`], with the confidence per voxel of its result when
/// `with_confidence` (`None` otherwise), in `[0.5, 1]`: the method's own
/// ([`Interpolator::interpolate_with_confidence`], what `interslice
/// interpolate --confidence` writes for each label) when only `axis` has
/// drawn slices; when other axes shape the result too, the shape confidence
/// of the combined mask along `axis` ([`shape_confidence`], the trait's
/// default), which does not know that a slice drawn across `axis` makes the
/// voxels beside it sure, so it errs on the side of doubt there.
pub fn interpolate_label_with_confidence(
    tracing: &dyn Tracing,
    geometry: &Geometry,
    label: u16,
    axis: Axis,
    method: &dyn Interpolator,
    with_confidence: bool,
    cancel: &Cancel,
) -> Result<Interpolated, ProjectError> {
    let counts = label_counts(tracing, label)?;
    interpolate_axes(
        tracing,
        geometry,
        label,
        axis,
        &counts,
        method,
        with_confidence,
        cancel,
    )
}

/// The drawn-slice count of `label` per axis.
fn label_counts(tracing: &dyn Tracing, label: u16) -> Result<Vec<(Axis, usize)>, ProjectError> {
    Ok(tracing
        .drawn_labels()?
        .into_iter()
        .filter(|d| d.0 == label)
        .map(|d| (d.1, d.2))
        .collect())
}

/// A label's mask, its drawn slices along the axis asked and, when asked,
/// its confidence.
type Interpolated = (Mask, Vec<usize>, Option<Volume<f32>>);

/// [`interpolate_label`] with the label's drawn-slice counts per axis known;
/// the confidence too when `confidence` is set.
#[allow(clippy::too_many_arguments)]
fn interpolate_axes(
    tracing: &dyn Tracing,
    geometry: &Geometry,
    label: u16,
    axis: Axis,
    counts: &[(Axis, usize)],
    method: &dyn Interpolator,
    confidence: bool,
    cancel: &Cancel,
) -> Result<Interpolated, ProjectError> {
    cancel.check()?;
    let (mask, drawn) = sparse_mask(tracing, geometry, label, axis)?;
    if drawn.len() < 2 {
        return Err(ProjectError::invalid(format!(
            "label {label} has {} drawn slice(s) along {axis}; interpolation needs at least two",
            drawn.len()
        )));
    }
    // The other axes, z first (the order of the blend's sums); one with a
    // single drawn slice only has that slice written back.
    let mut sparse = vec![(axis, mask, drawn)];
    for a in [Axis::Z, Axis::Y, Axis::X] {
        if a != axis && counts.iter().any(|&(b, n)| b == a && n >= 1) {
            let (m, d) = sparse_mask(tracing, geometry, label, a)?;
            sparse.push((a, m, d));
        }
    }
    let inputs: Vec<SparseMask<'_>> = sparse
        .iter()
        .map(|(a, m, d)| SparseMask::new(m, *a, d).with_cancel(cancel))
        .collect();
    let (out, conf) = if inputs.len() == 1 {
        // On the label's box where the method allows it, as the CLI runs
        // each label of a label volume.
        labels::interpolate_label(method, inputs[0], confidence)?
    } else {
        let out = multi_axis::combine(method, &inputs).map_err(|e| match e {
            InterpError::Input(m) if inputs.len() > 1 => {
                ProjectError::invalid(format!("label {label}: {m}"))
            }
            e => e.into(),
        })?;
        cancel.check()?;
        let conf = confidence.then(|| shape_confidence(&out, &inputs[0], 1.0));
        (out, conf)
    };
    cancel.check()?;
    let (_, _, drawn) = sparse.swap_remove(0);
    Ok((out, drawn, conf))
}

/// The full label volume of a tracing: each label drawn is interpolated
/// from its drawn slices along every axis with at least two of them (one 3D
/// result per label, not a union of per-axis results) and with the single
/// drawn slices of other axes written back, then painted in ascending label
/// order. With one such axis and no other slices this is the interpolation
/// along it; with none, the error names the axis with most drawn slices
/// (ties: z, then y, then x).
pub fn label_volume(
    tracing: &dyn Tracing,
    geometry: &Geometry,
    method: &dyn Interpolator,
    only_label: Option<u16>,
    cancel: &Cancel,
) -> Result<LabelVolume, ProjectError> {
    let mut per_label: BTreeMap<u16, Vec<(Axis, usize)>> = BTreeMap::new();
    for (label, axis, n) in tracing.drawn_labels()? {
        if only_label.is_none_or(|l| l == label) {
            per_label.entry(label).or_default().push((axis, n));
        }
    }
    if per_label.is_empty() {
        return Err(ProjectError::not_found(format!(
            "nothing traced on {}{}",
            tracing.describe(),
            only_label
                .map(|l| format!(" for label {l}"))
                .unwrap_or_default()
        )));
    }
    let mut out: LabelVolume = Volume::zeros(geometry.clone());
    for (label, counts) in per_label {
        let (axis, _) = counts
            .iter()
            .copied()
            .max_by_key(|&(a, n)| (n, a))
            .expect("a label has an axis");
        let (mask, ..) = interpolate_axes(
            tracing, geometry, label, axis, &counts, method, false, cancel,
        )?;
        for (o, &m) in out.data_mut().iter_mut().zip(mask.data()) {
            if m {
                *o = label;
            }
        }
    }
    Ok(out)
}

/// A user's label volume from the database (see [`label_volume`]).
pub fn user_label_volume(
    store: &Store,
    geometry: &Geometry,
    cell: &str,
    user_id: i64,
    method: &dyn Interpolator,
    only_label: Option<u16>,
    cancel: &Cancel,
) -> Result<LabelVolume, ProjectError> {
    let tracing = StoredTracing {
        store,
        cell,
        user_id,
    };
    label_volume(&tracing, geometry, method, only_label, cancel)
}

type GtKey = (String, i64, String, Option<u16>);

/// Recently computed label volumes, valid while the user's revision of the
/// cell is unchanged (overlays ask for one slice at a time).
pub struct GtCache {
    capacity: usize,
    entries: Mutex<VecDeque<(GtKey, i64, Arc<LabelVolume>)>>,
}

impl GtCache {
    /// A cache of at most `capacity` volumes.
    pub fn new(capacity: usize) -> GtCache {
        GtCache {
            capacity: capacity.max(1),
            entries: Mutex::new(VecDeque::new()),
        }
    }

    /// The cached or newly computed label volume of a user's tracing.
    pub fn get(
        &self,
        tracing: &StoredTracing<'_>,
        geometry: &Geometry,
        method: &dyn Interpolator,
        only_label: Option<u16>,
        cancel: &Cancel,
    ) -> Result<Arc<LabelVolume>, ProjectError> {
        let rev = tracing.store.revision(tracing.cell, tracing.user_id)?;
        let key: GtKey = (
            tracing.cell.to_string(),
            tracing.user_id,
            method.name().to_string(),
            only_label,
        );
        {
            let entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
            if let Some((_, r, v)) = entries.iter().find(|(k, _, _)| *k == key)
                && *r == rev
            {
                return Ok(v.clone());
            }
        }
        let v = Arc::new(label_volume(tracing, geometry, method, only_label, cancel)?);
        let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        entries.retain(|(k, _, _)| *k != key);
        entries.push_back((key, rev, v.clone()));
        while entries.len() > self.capacity {
            entries.pop_front();
        }
        Ok(v)
    }
}
