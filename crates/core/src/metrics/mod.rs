//! Segmentation metrics of a segmentation against a ground truth: voxel overlap
//! (confusion matrix, Dice, Jaccard, ...), physical volumes, and exact distances
//! between border voxels (Hausdorff, HD95, ASSD, NSD).
//!
//! Conventions follow the medpy/MONAI border-voxel definition (see
//! `docs/metrics.md` for every definition and how other libraries differ):
//!
//! * border voxels are foreground voxels with a 6-neighbour outside the mask, the
//!   outside of the image counting as background;
//! * distances are exact Euclidean distances between voxel centres in the
//!   volume's physical units;
//! * percentiles interpolate linearly like numpy;
//! * a ratio whose denominator is 0 is `None` (JSON `null`), and every distance is
//!   `None` when either mask is empty.
//!
//! Everything runs directly on the label arrays (no masks are allocated) and in
//! parallel with rayon.
use crate::{CoreError, Geometry, LabelVolume, Mask};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub mod border;
mod disc;
pub mod overlap;
pub mod stats;
pub mod surface;

pub use border::{BoundingBox, EqualTo, MaskView, NonZero};
pub use overlap::{Confusion, LabelHistograms, confusion_of, confusion_where};

/// The default NSD tolerance: 1.0 physical unit.
pub const DEFAULT_TOLERANCE: f64 = 1.0;

/// Every metric of one label. Serialised with the keys of the `evaluate --json`
/// contract; `None` is `null`. Distances are in `unit`, volumes in `unit`³.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// True positives (voxels).
    pub tp: u64,
    /// False positives (voxels).
    pub fp: u64,
    /// False negatives (voxels).
    #[serde(rename = "fn")]
    pub fn_: u64,
    /// True negatives (voxels).
    pub tn: u64,
    /// 2TP / (2TP + FP + FN).
    pub dice: Option<f64>,
    /// TP / (TP + FP + FN).
    pub jaccard: Option<f64>,
    /// TP / (TP + FN).
    pub sensitivity: Option<f64>,
    /// TN / (TN + FP).
    pub specificity: Option<f64>,
    /// TP / (TP + FP).
    pub precision: Option<f64>,
    /// 1 − |FN − FP| / (2TP + FP + FN).
    pub volume_similarity: Option<f64>,
    /// Physical volume of the ground truth (voxels × sx·sy·sz).
    pub volume_gt: f64,
    /// Physical volume of the segmentation.
    pub volume_seg: f64,
    /// Hausdorff distance between the border voxels.
    pub hd: Option<f64>,
    /// Max of the two directed 95th percentiles.
    pub hd95: Option<f64>,
    /// 95th percentile of both directions pooled.
    pub hd95_pooled: Option<f64>,
    /// Mean of both directions' distances pooled.
    pub assd: Option<f64>,
    /// Mean of the two directed means.
    pub masd: Option<f64>,
    /// Share of border voxels (both masks) within `tolerance` of the other border.
    pub nsd: Option<f64>,
    /// The NSD tolerance used, in `unit`.
    pub tolerance: f64,
    /// Length unit of distances ("µm", "mm", ...); volumes are in this unit cubed.
    pub unit: String,
    /// Border voxels of the ground truth.
    pub border_gt: u64,
    /// Border voxels of the segmentation.
    pub border_seg: u64,
    /// Largest ground truth → segmentation border distance.
    pub hd_gt_to_seg: Option<f64>,
    /// Largest segmentation → ground truth border distance.
    pub hd_seg_to_gt: Option<f64>,
    /// 95th percentile of the ground truth → segmentation distances.
    pub hd95_gt_to_seg: Option<f64>,
    /// 95th percentile of the segmentation → ground truth distances.
    pub hd95_seg_to_gt: Option<f64>,
    /// Mean ground truth → segmentation distance.
    pub mean_gt_to_seg: Option<f64>,
    /// Mean segmentation → ground truth distance.
    pub mean_seg_to_gt: Option<f64>,
}

impl Metrics {
    /// The metrics of the confusion matrix `c`, with no border voxels and every
    /// distance `None` until [`surface::add_distances`] fills them in.
    fn from_confusion(c: Confusion, geometry: &Geometry, tolerance: f64) -> Metrics {
        let vox = geometry.voxel_volume();
        Metrics {
            tp: c.tp,
            fp: c.fp,
            fn_: c.fn_,
            tn: c.tn,
            dice: c.dice(),
            jaccard: c.jaccard(),
            sensitivity: c.sensitivity(),
            specificity: c.specificity(),
            precision: c.precision(),
            volume_similarity: c.volume_similarity(),
            volume_gt: c.gt_voxels() as f64 * vox,
            volume_seg: c.seg_voxels() as f64 * vox,
            hd: None,
            hd95: None,
            hd95_pooled: None,
            assd: None,
            masd: None,
            nsd: None,
            tolerance,
            unit: geometry.unit.symbol().to_string(),
            border_gt: 0,
            border_seg: 0,
            hd_gt_to_seg: None,
            hd_seg_to_gt: None,
            hd95_gt_to_seg: None,
            hd95_seg_to_gt: None,
            mean_gt_to_seg: None,
            mean_seg_to_gt: None,
        }
    }

    /// The confusion matrix.
    pub fn confusion(&self) -> Confusion {
        Confusion {
            tp: self.tp,
            fp: self.fp,
            fn_: self.fn_,
            tn: self.tn,
        }
    }
}

fn check_tolerance(tolerance: f64) -> Result<(), CoreError> {
    if tolerance.is_finite() && tolerance >= 0.0 {
        Ok(())
    } else {
        Err(CoreError::Invalid(format!(
            "tolerance must be a finite number >= 0, got {tolerance}"
        )))
    }
}

/// The metrics of one label as `evaluate --label N --json` prints them: the
/// label first, then every metric (keys in a fixed order).
#[derive(Debug, Clone, Serialize)]
pub struct LabelReport<'a> {
    /// The evaluated label.
    pub label: u16,
    /// Its metrics.
    #[serde(flatten)]
    pub metrics: &'a Metrics,
}

/// Every label as `evaluate --json` prints them without `--label`: labels in
/// ascending order, then their union.
#[derive(Debug, Clone, Serialize)]
pub struct AllReport<'a> {
    /// Metrics of each label present in either volume.
    pub labels: BTreeMap<u16, &'a Metrics>,
    /// Metrics of the union of all labels.
    pub foreground: &'a Metrics,
}

/// Err unless both arrays hold exactly the voxels of `geometry`.
fn check_data(geometry: &Geometry, gt: usize, seg: usize) -> Result<(), CoreError> {
    geometry.validate()?;
    for got in [gt, seg] {
        if got != geometry.len() {
            return Err(CoreError::DataLength {
                dims: geometry.dims,
                expected: geometry.len(),
                got,
            });
        }
    }
    Ok(())
}

/// Metrics of the voxels of `seg` equal to `label` against those of `gt`.
/// Errs when the two volumes are not on the same grid or `tolerance` (the NSD
/// tolerance, physical units) is negative or not finite.
pub fn evaluate_label(
    gt: &LabelVolume,
    seg: &LabelVolume,
    label: u16,
    tolerance: f64,
) -> Result<Metrics, CoreError> {
    gt.geometry().ensure_same_grid(seg.geometry())?;
    evaluate_label_data(gt.geometry(), gt.data(), seg.data(), label, tolerance)
}

/// [`evaluate_label`] on borrowed arrays of any voxel type (x-fastest, both
/// on `geometry`): the in-memory entry point for callers that hold their
/// arrays elsewhere (the Python bindings evaluate numpy arrays in place).
pub fn evaluate_label_data<T: Copy + PartialEq + Sync>(
    geometry: &Geometry,
    gt: &[T],
    seg: &[T],
    label: T,
    tolerance: f64,
) -> Result<Metrics, CoreError> {
    check_data(geometry, gt.len(), seg.len())?;
    check_tolerance(tolerance)?;
    let c = confusion_of(gt, seg, label);
    Ok(evaluate_views(geometry, gt, seg, label, c, tolerance))
}

/// Metrics of two binary masks.
pub fn evaluate_masks(gt: &Mask, seg: &Mask, tolerance: f64) -> Result<Metrics, CoreError> {
    gt.geometry().ensure_same_grid(seg.geometry())?;
    evaluate_label_data(gt.geometry(), gt.data(), seg.data(), true, tolerance)
}

/// Metrics of every non-zero label present in either volume. The voxel counts of
/// all labels come from one pass; the distances of each label are computed one
/// label after the other (each in parallel), which bounds memory at 512³.
pub fn evaluate_all(
    gt: &LabelVolume,
    seg: &LabelVolume,
    tolerance: f64,
) -> Result<BTreeMap<u16, Metrics>, CoreError> {
    gt.geometry().ensure_same_grid(seg.geometry())?;
    evaluate_all_data(gt.geometry(), gt.data(), seg.data(), tolerance)
}

/// [`evaluate_all`] on borrowed label arrays on `geometry`.
pub fn evaluate_all_data(
    geometry: &Geometry,
    gt: &[u16],
    seg: &[u16],
    tolerance: f64,
) -> Result<BTreeMap<u16, Metrics>, CoreError> {
    check_data(geometry, gt.len(), seg.len())?;
    check_tolerance(tolerance)?;
    let h = LabelHistograms::count(gt, seg);
    Ok(h.labels()
        .into_iter()
        .map(|l| {
            let m = evaluate_views(geometry, gt, seg, l, h.confusion(l), tolerance);
            (l, m)
        })
        .collect())
}

/// [`evaluate_all`] and [`evaluate_foreground`] as `interslice evaluate`
/// reports them without `--label`.
pub fn evaluate_all_and_foreground(
    gt: &LabelVolume,
    seg: &LabelVolume,
    tolerance: f64,
) -> Result<(BTreeMap<u16, Metrics>, Metrics), CoreError> {
    gt.geometry().ensure_same_grid(seg.geometry())?;
    evaluate_all_and_foreground_data(gt.geometry(), gt.data(), seg.data(), tolerance)
}

/// [`evaluate_all_data`] and [`evaluate_foreground_data`] together. With a
/// single label in either volume the union of all labels is that label, so
/// its metrics are the foreground's too and the distances (most of the
/// work) are computed once.
pub fn evaluate_all_and_foreground_data(
    geometry: &Geometry,
    gt: &[u16],
    seg: &[u16],
    tolerance: f64,
) -> Result<(BTreeMap<u16, Metrics>, Metrics), CoreError> {
    let all = evaluate_all_data(geometry, gt, seg, tolerance)?;
    let fg = match (all.len(), all.values().next()) {
        (1, Some(m)) => m.clone(),
        _ => evaluate_foreground_data(geometry, gt, seg, tolerance)?,
    };
    Ok((all, fg))
}

/// Metrics of the union of all labels: every non-zero voxel is foreground in
/// both volumes (cell + nucleus + nucleoli as one object). This is the
/// "over all labels" aggregate of `interslice evaluate`.
pub fn evaluate_foreground(
    gt: &LabelVolume,
    seg: &LabelVolume,
    tolerance: f64,
) -> Result<Metrics, CoreError> {
    gt.geometry().ensure_same_grid(seg.geometry())?;
    evaluate_foreground_data(gt.geometry(), gt.data(), seg.data(), tolerance)
}

/// [`evaluate_foreground`] on borrowed arrays of any voxel type on `geometry`.
pub fn evaluate_foreground_data<T: Copy + PartialEq + Default + Sync>(
    geometry: &Geometry,
    gt: &[T],
    seg: &[T],
    tolerance: f64,
) -> Result<Metrics, CoreError> {
    check_data(geometry, gt.len(), seg.len())?;
    check_tolerance(tolerance)?;
    let zero = T::default();
    let c = confusion_where(gt, seg, |x| x != zero);
    let dims = geometry.dims;
    let g = NonZero { data: gt, dims };
    let s = NonZero { data: seg, dims };
    Ok(evaluate_mask_views(geometry, &g, &s, c, tolerance))
}

/// Only the confusion matrix of `label` (Dice, Jaccard, ... via its methods):
/// one pass over both volumes, for callers that evaluate many segmentations.
pub fn overlap_only(
    gt: &LabelVolume,
    seg: &LabelVolume,
    label: u16,
) -> Result<Confusion, CoreError> {
    gt.geometry().ensure_same_grid(seg.geometry())?;
    Ok(confusion_of(gt.data(), seg.data(), label))
}

/// Only the confusion matrix of two binary masks.
pub fn overlap_masks(gt: &Mask, seg: &Mask) -> Result<Confusion, CoreError> {
    gt.geometry().ensure_same_grid(seg.geometry())?;
    Ok(confusion_of(gt.data(), seg.data(), true))
}

fn evaluate_views<T: Copy + PartialEq + Sync>(
    geometry: &Geometry,
    gt: &[T],
    seg: &[T],
    value: T,
    c: Confusion,
    tolerance: f64,
) -> Metrics {
    let dims = geometry.dims;
    let g = EqualTo {
        data: gt,
        dims,
        value,
    };
    let s = EqualTo {
        data: seg,
        dims,
        value,
    };
    evaluate_mask_views(geometry, &g, &s, c, tolerance)
}

/// The metrics of two mask views whose confusion matrix `c` is known.
fn evaluate_mask_views<G: MaskView, S: MaskView>(
    geometry: &Geometry,
    g: &G,
    s: &S,
    c: Confusion,
    tolerance: f64,
) -> Metrics {
    let bb = match (c.gt_voxels() > 0, c.seg_voxels() > 0) {
        (false, false) => None,
        (true, false) => border::bounding_box(g),
        (false, true) => border::bounding_box(s),
        (true, true) => {
            let (a, b) = rayon::join(|| border::bounding_box(g), || border::bounding_box(s));
            a.zip(b).map(|(a, b)| a.union(b))
        }
    };
    let mut m = Metrics::from_confusion(c, geometry, tolerance);
    surface::add_distances(&mut m, g, s, bb, geometry.spacing);
    m
}

#[cfg(test)]
mod tests;
