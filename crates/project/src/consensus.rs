//! The STAPLE consensus of a cell traced by several users: each user's
//! interpolated structure of each label, combined by STAPLE (Warfield, Zou &
//! Wells 2004, `interslice_core::staple`) into one label volume with every
//! user's estimated sensitivity and specificity.
//!
//! A structure is what a user traced for a label, whole: the cell including
//! the nucleus inside it, the nucleus including its nucleoli (each label is
//! interpolated on its own, see [`crate::groundtruth::label_volume`]). STAPLE
//! runs once per label over the users who traced it on at least two slices,
//! and the consensus paints the labels in ascending order, so inner
//! structures overwrite outer ones as in every label volume here.
//!
//! Used by `interslice variability` and by the export of `user=consensus`
//! (`GET /api/cells/{cell}/export?user=consensus`), so both give the same volume.
use crate::error::ProjectError;
use crate::groundtruth::user_label_volume;
use interslice_core::staple::{Staple, StapleParams, staple};
use interslice_core::{Cancel, Geometry, LabelVolume, Mask, Volume};
use interslice_interp::Interpolator;
use interslice_store::{Role, Store, User};

/// The users' masks of one label.
#[derive(Debug, Clone)]
pub struct LabelRaters {
    /// Label id.
    pub label: u16,
    /// The users who traced it on at least two slices, by name order.
    pub users: Vec<String>,
    /// Each user's interpolated structure (same order as `users`).
    pub masks: Vec<Mask>,
}

/// The STAPLE estimate of one label.
#[derive(Debug, Clone)]
pub struct LabelConsensus {
    /// Label id.
    pub label: u16,
    /// The raters, in the order of `staple.sensitivity`.
    pub users: Vec<String>,
    /// Sensitivities, specificities, prior, consensus mask.
    pub staple: Staple,
}

/// A cell's consensus: the painted label volume and the estimate of each label.
#[derive(Debug, Clone)]
pub struct Consensus {
    /// The consensus label volume.
    pub labels: LabelVolume,
    /// Labels traced by at least two users, ascending.
    pub per_label: Vec<LabelConsensus>,
}

/// Every user's interpolated structure of every label of `cell` (or only
/// `only_label`), grouped by label. Users who drew a label on fewer than two
/// slices along every axis cannot be interpolated for it and are left out.
pub fn rater_masks(
    store: &Store,
    geometry: &Geometry,
    cell: &str,
    method: &dyn Interpolator,
    only_label: Option<u16>,
    cancel: &Cancel,
) -> Result<Vec<LabelRaters>, ProjectError> {
    let mut out: Vec<LabelRaters> = Vec::new();
    for user in store.tracers_of(cell)? {
        let mut labels: Vec<u16> = store
            .drawn_labels(cell, user.id)?
            .into_iter()
            .filter(|&(l, _, n)| n >= 2 && only_label.is_none_or(|o| o == l))
            .map(|(l, _, _)| l)
            .collect();
        labels.dedup();
        for l in labels {
            let v = user_label_volume(store, geometry, cell, user.id, method, Some(l), cancel)?;
            let mask = v.mask_of(l);
            match out.iter_mut().find(|r| r.label == l) {
                Some(r) => {
                    r.users.push(user.name.clone());
                    r.masks.push(mask);
                }
                None => out.push(LabelRaters {
                    label: l,
                    users: vec![user.name.clone()],
                    masks: vec![mask],
                }),
            }
        }
    }
    out.sort_by_key(|r| r.label);
    Ok(out)
}

/// STAPLE of every label with at least two raters, painted in ascending order.
pub fn consensus_of(
    geometry: &Geometry,
    raters: &[LabelRaters],
    params: StapleParams,
    cancel: &Cancel,
) -> Result<Consensus, ProjectError> {
    let mut labels: LabelVolume = Volume::zeros(geometry.clone());
    let mut per_label = Vec::new();
    for r in raters.iter().filter(|r| r.masks.len() >= 2) {
        let refs: Vec<&Mask> = r.masks.iter().collect();
        let s = staple(&refs, params, cancel)?;
        for (o, &c) in labels.data_mut().iter_mut().zip(s.consensus.data()) {
            if c {
                *o = r.label;
            }
        }
        per_label.push(LabelConsensus {
            label: r.label,
            users: r.users.clone(),
            staple: s,
        });
    }
    Ok(Consensus { labels, per_label })
}

/// The consensus label volume of a cell for `user=consensus` exports (see
/// [`rater_masks`]); not found when no label was traced by two users. It
/// combines everyone's tracings, so only reviewers may read it.
pub fn consensus_for(
    store: &Store,
    me: &User,
    geometry: &Geometry,
    cell: &str,
    method: &dyn Interpolator,
    only_label: Option<u16>,
    cancel: &Cancel,
) -> Result<LabelVolume, ProjectError> {
    if me.role != Role::Reviewer {
        return Err(ProjectError::forbidden(
            "only reviewers may read the consensus of everyone's tracings",
        ));
    }
    let raters = rater_masks(store, geometry, cell, method, only_label, cancel)?;
    let c = consensus_of(geometry, &raters, StapleParams::default(), cancel)?;
    if c.per_label.is_empty() {
        return Err(ProjectError::not_found(format!(
            "no label of cell '{cell}' was traced by two users{}",
            only_label
                .map(|l| format!(" (label {l})"))
                .unwrap_or_default()
        )));
    }
    Ok(c.labels)
}

/// The file of a `user=consensus` export: the consensus label volume in
/// `format` (nii.gz, nii, nrrd, mha, tiff) and its file name
/// `<cell>-consensus.<ext>`. Contours have no consensus (STAPLE works on
/// volumes), so `format=contours` is invalid.
#[allow(clippy::too_many_arguments)]
pub fn export_bytes(
    store: &Store,
    me: &User,
    cell: &str,
    geometry: &Geometry,
    format: &str,
    method: &dyn Interpolator,
    only_label: Option<u16>,
    cancel: &Cancel,
) -> Result<(Vec<u8>, String), ProjectError> {
    let ext = match format {
        "nii.gz" | "nii" | "nrrd" | "tiff" | "tif" | "mha" => format,
        "contours" => {
            return Err(ProjectError::invalid(
                "the consensus is a label volume; export it as nii.gz, nii, nrrd, mha or tiff",
            ));
        }
        other => {
            return Err(ProjectError::invalid(format!(
                "unknown export format '{other}' (nii.gz, nii, nrrd, mha or tiff)"
            )));
        }
    };
    let labels = consensus_for(store, me, geometry, cell, method, only_label, cancel)?;
    let name = format!("{cell}-consensus.{ext}");
    let bytes = crate::export::label_file_bytes(store, &labels, &name)?;
    Ok((bytes, name))
}
