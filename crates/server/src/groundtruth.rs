//! A user's ground truth of a cell: their contours rasterised into sparse masks
//! and interpolated, one label at a time, then painted in ascending label
//! order (an inner structure overwrites the one containing it).
use crate::error::ApiError;
use interslice_core::{Axis, Cancel, Contour, Geometry, LabelVolume, Mask, SliceRef, Volume};
use interslice_interp::{Interpolator, SparseMask};
use interslice_store::{ContourQuery, Store, StoredContour};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

/// Stored contours as core contours.
pub fn to_core(stored: &[StoredContour]) -> Vec<Contour> {
    stored
        .iter()
        .map(|c| Contour {
            slice: SliceRef {
                axis: c.axis,
                index: c.index,
            },
            label: c.label,
            points: c.points.clone(),
            author: c.author.clone(),
            created: c.created.clone(),
            pressure: c.pressure.clone(),
            times_ms: c.times_ms.clone(),
            tool: Some(c.tool.clone()),
        })
        .collect()
}

/// The sparse mask of one label along one axis and its drawn slices (with
/// contours or marked empty).
pub fn sparse_mask(
    store: &Store,
    geometry: &Geometry,
    cell: &str,
    user_id: i64,
    label: u16,
    axis: Axis,
) -> Result<(Mask, Vec<usize>), ApiError> {
    let stored = store.contours(&ContourQuery {
        cell: cell.to_string(),
        user_id,
        axis: Some(axis),
        index: None,
        label: Some(label),
    })?;
    let drawn: Vec<usize> = store
        .drawn(cell, user_id, label, axis)?
        .into_iter()
        .map(|d| d.index)
        .collect();
    let mask = interslice_core::raster::contours_to_mask(geometry, &to_core(&stored), label)?;
    Ok((mask, drawn))
}

/// Interpolate one label of one user along one axis; `cancel` is checked
/// before and after the method runs (one label is the unit of work).
#[allow(clippy::too_many_arguments)]
pub fn interpolate_label(
    store: &Store,
    geometry: &Geometry,
    cell: &str,
    user_id: i64,
    label: u16,
    axis: Axis,
    method: &dyn Interpolator,
    cancel: &Cancel,
) -> Result<(Mask, Vec<usize>), ApiError> {
    cancel.check()?;
    let (mask, drawn) = sparse_mask(store, geometry, cell, user_id, label, axis)?;
    if drawn.len() < 2 {
        return Err(ApiError::bad_request(format!(
            "label {label} has {} drawn slice(s) along {axis}; interpolation needs at least two",
            drawn.len()
        )));
    }
    let out = method.interpolate(SparseMask::new(&mask, axis, &drawn).with_cancel(cancel))?;
    cancel.check()?;
    Ok((out, drawn))
}

/// The user's full label volume: each label they drew is interpolated along
/// the axis with most drawn slices for it (ties: z, then y, then x), then
/// painted in ascending label order.
pub fn label_volume(
    store: &Store,
    geometry: &Geometry,
    cell: &str,
    user_id: i64,
    method: &dyn Interpolator,
    only_label: Option<u16>,
    cancel: &Cancel,
) -> Result<LabelVolume, ApiError> {
    let drawn = store.drawn_labels(cell, user_id)?;
    let mut best: Vec<(u16, Axis, usize)> = Vec::new();
    for (label, axis, n) in drawn {
        if only_label.is_some_and(|l| l != label) {
            continue;
        }
        match best.iter_mut().find(|b| b.0 == label) {
            Some(b) if n > b.2 || (n == b.2 && axis > b.1) => *b = (label, axis, n),
            Some(_) => {}
            None => best.push((label, axis, n)),
        }
    }
    if best.is_empty() {
        return Err(ApiError::not_found(format!(
            "nothing traced on cell '{cell}' by this user{}",
            only_label
                .map(|l| format!(" for label {l}"))
                .unwrap_or_default()
        )));
    }
    best.sort_by_key(|b| b.0);
    let mut out: LabelVolume = Volume::zeros(geometry.clone());
    for (label, axis, _) in best {
        let (mask, _) =
            interpolate_label(store, geometry, cell, user_id, label, axis, method, cancel)?;
        for (o, &m) in out.data_mut().iter_mut().zip(mask.data()) {
            if m {
                *o = label;
            }
        }
    }
    Ok(out)
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

    /// The cached or newly computed label volume of a user.
    #[allow(clippy::too_many_arguments)]
    pub fn get(
        &self,
        store: &Store,
        geometry: &Geometry,
        cell: &str,
        user_id: i64,
        method: &dyn Interpolator,
        only_label: Option<u16>,
        cancel: &Cancel,
    ) -> Result<Arc<LabelVolume>, ApiError> {
        let rev = store.revision(cell, user_id)?;
        let key: GtKey = (
            cell.to_string(),
            user_id,
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
        let v = Arc::new(label_volume(
            store, geometry, cell, user_id, method, only_label, cancel,
        )?);
        let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        entries.retain(|(k, _, _)| *k != key);
        entries.push_back((key, rev, v.clone()));
        while entries.len() > self.capacity {
            entries.pop_front();
        }
        Ok(v)
    }
}
