//! Exports of a cell: a user's interpolated label volume in a volume format,
//! a stored interpolation result, or the user's contours in the contours file
//! format. The server's `GET /api/cells/{cell}/export` and `interslice
//! export` both answer with these bytes.
use crate::cells::id_of_name;
use crate::error::ProjectError;
use crate::groundtruth::{GtCache, StoredTracing, label_volume, to_core};
use interslice_core::{Cancel, Geometry, LabelVolume, Mask};
use interslice_interp::Interpolator;
use interslice_store::{ContourQuery, ResultMeta, Role, Store, User};
use std::sync::Arc;

/// The bytes of an export: a label volume file or the contours JSON, and
/// the file name (`<cell>-<user>.<ext>`). With a `cache` the label volume
/// comes from it (the one the server's evaluations and overlays use, valid
/// while the tracing is unchanged), else it is computed.
#[allow(clippy::too_many_arguments)]
pub fn export_bytes(
    store: &Store,
    cache: Option<&GtCache>,
    cell: &str,
    geometry: &Geometry,
    user: &User,
    format: &str,
    m: &dyn Interpolator,
    label: Option<u16>,
    cancel: &Cancel,
) -> Result<(Vec<u8>, String), ProjectError> {
    let base = format!("{cell}-{}", id_of_name(&user.name));
    if format == "contours" {
        let text = contours_json(store, cell, geometry, user)?;
        return Ok((text.into_bytes(), format!("{base}.contours.json")));
    }
    let ext = volume_extension(format)?;
    let tracing = StoredTracing {
        store,
        cell,
        user_id: user.id,
    };
    let labels = match cache {
        Some(c) => c.get(&tracing, geometry, m, label, cancel)?,
        None => Arc::new(label_volume(&tracing, geometry, m, label, cancel)?),
    };
    let name = format!("{base}.{ext}");
    let bytes = label_file_bytes(store, &labels, &name)?;
    Ok((bytes, name))
}

/// A stored result of `cell` that `me` may read (their own, or anyone's for
/// a reviewer).
pub fn readable_result(
    store: &Store,
    me: &User,
    cell: &str,
    id: &str,
) -> Result<(ResultMeta, Mask), ProjectError> {
    let n: i64 = id
        .parse()
        .map_err(|_| ProjectError::not_found(format!("no result '{id}'")))?;
    let (meta, mask) = store
        .result(n)?
        .filter(|(m, _)| m.cell == cell)
        .ok_or_else(|| ProjectError::not_found(format!("no result {n} on cell '{cell}'")))?;
    if meta.user_id != me.id && me.role != Role::Reviewer {
        return Err(ProjectError::forbidden("this result is another user's"));
    }
    Ok((meta, mask))
}

/// A stored interpolation result as a label volume file (its label's value
/// inside the mask).
pub fn result_bytes(
    store: &Store,
    me: &User,
    cell: &str,
    id: &str,
    format: &str,
) -> Result<(Vec<u8>, String), ProjectError> {
    let ext = volume_extension(format)?;
    let (meta, mask) = readable_result(store, me, cell, id)?;
    let data = mask
        .data()
        .iter()
        .map(|&b| if b { meta.label } else { 0 })
        .collect();
    let labels = LabelVolume::from_vec(mask.geometry().clone(), data)?;
    let name = format!("{cell}-result-{}.{ext}", meta.id);
    Ok((label_file_bytes(store, &labels, &name)?, name))
}

/// The extension of a label volume export format, or invalid.
pub fn volume_extension(format: &str) -> Result<&str, ProjectError> {
    match format {
        "nii.gz" | "nii" | "nrrd" | "seg.nrrd" | "tiff" | "tif" | "mha" => Ok(format),
        other => Err(ProjectError::invalid(format!(
            "unknown export format '{other}' (nii.gz, nii, nrrd, seg.nrrd, mha, tiff or contours)"
        ))),
    }
}

/// The bytes of `labels` as the file `name`, made in memory. A `.seg.nrrd`
/// carries the project's components as its segment table.
pub fn label_file_bytes(
    store: &Store,
    labels: &LabelVolume,
    name: &str,
) -> Result<Vec<u8>, ProjectError> {
    if interslice_io::segmentation::is_seg_nrrd(std::path::Path::new(name)) {
        let components = store.components()?;
        Ok(interslice_io::segmentation::seg_nrrd_bytes(
            name,
            labels,
            &components,
        )?)
    } else {
        Ok(interslice_io::write_labels_bytes(name, labels)?)
    }
}

/// The user's contours of a cell in the contours file format.
pub fn contours_json(
    store: &Store,
    cell: &str,
    geometry: &Geometry,
    user: &User,
) -> Result<String, ProjectError> {
    use interslice_core::contour_file::{ContourFile, DrawnEmpty, LabelInfo};
    let stored = store.contours(&ContourQuery {
        cell: cell.to_string(),
        user_id: user.id,
        ..Default::default()
    })?;
    let mut empty = Vec::new();
    for (label, axis, _) in store.drawn_labels(cell, user.id)? {
        for d in store.drawn(cell, user.id, label, axis)? {
            if d.empty {
                empty.push(DrawnEmpty {
                    slice: interslice_core::SliceRef {
                        axis,
                        index: d.index,
                    },
                    label,
                    author: user.name.clone(),
                });
            }
        }
    }
    let file = ContourFile {
        geometry: geometry.clone(),
        labels: store
            .labels()?
            .into_iter()
            .map(|l| LabelInfo {
                id: l.id,
                name: l.name,
                color: l.color,
            })
            .collect(),
        contours: to_core(&stored),
        drawn_empty: empty,
    };
    Ok(interslice_core::contour_file::write(&file)?)
}
