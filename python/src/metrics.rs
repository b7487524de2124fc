//! `evaluate`, `overlap` and `staple` on numpy arrays.
use crate::arrays::{
    AnyArray, FromLabel, Order, Voxels, any_array, memory_order, to_numpy, to_u16, voxels,
};
use crate::volumes::{geometry, parse_unit};
use crate::{error, to_py};
use interslice_core::metrics::{
    AllReport, Confusion, LabelReport, Metrics, confusion_of, evaluate_all_and_foreground_data,
    evaluate_label_data,
};
use interslice_core::staple::{MAX_RATERS, StapleParams};
use interslice_core::{Geometry, LengthUnit, Mask, Volume};
use numpy::Element;
use numpy::PyReadonlyArray3;
use pyo3::exceptions::PyUserWarning;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::Serialize;

/// Both arrays' voxels in one order (the first array's memory order when it
/// is contiguous) and the geometry of that order.
struct Pair<'a, T: Clone> {
    gt: Voxels<'a, T>,
    seg: Voxels<'a, T>,
    geometry: Geometry,
}

fn pair<'a, T: Element + Copy>(
    g: &'a PyReadonlyArray3<'_, T>,
    s: &'a PyReadonlyArray3<'_, T>,
    spacing: [f64; 3],
    unit: LengthUnit,
) -> PyResult<Pair<'a, T>> {
    let order = memory_order(g).or(memory_order(s)).unwrap_or(Order::XFast);
    let gt = voxels(g, Some(order));
    let seg = voxels(s, Some(order));
    let sp = match order {
        Order::XFast => spacing,
        Order::Reversed => [spacing[2], spacing[1], spacing[0]],
    };
    let geometry = geometry(gt.dims, sp, unit)?;
    Ok(Pair { gt, seg, geometry })
}

/// An array's voxels as u16 labels, x-fastest (a copy, made without the GIL).
pub(crate) fn labels_u16(py: Python<'_>, a: &AnyArray<'_>, what: &str) -> PyResult<Vec<u16>> {
    crate::arrays::with_array!(a, x => {
        let v = voxels(x, Some(Order::XFast));
        py.detach(|| to_u16(&v.data, what))
    })
}

/// Both arrays as u16 labels, x-fastest (copies).
fn u16_pair(
    py: Python<'_>,
    a: &AnyArray<'_>,
    b: &AnyArray<'_>,
    spacing: [f64; 3],
    unit: LengthUnit,
) -> PyResult<(Vec<u16>, Vec<u16>, Geometry)> {
    let ga = labels_u16(py, a, "gt")?;
    let sb = labels_u16(py, b, "seg")?;
    Ok((ga, sb, geometry(a.shape(), spacing, unit)?))
}

fn check_shapes(a: &AnyArray<'_>, b: &AnyArray<'_>) -> PyResult<()> {
    if a.shape() != b.shape() {
        return Err(error(format!(
            "gt and seg differ: shape {:?} vs {:?}",
            a.shape(),
            b.shape()
        )));
    }
    Ok(())
}

/// The metrics of one label on a pair of arrays, without the GIL.
fn label_metrics(
    py: Python<'_>,
    a: &AnyArray<'_>,
    b: &AnyArray<'_>,
    label: u16,
    spacing: [f64; 3],
    unit: LengthUnit,
    tolerance: f64,
) -> PyResult<Metrics> {
    macro_rules! same {
        ($g:expr, $s:expr, $t:ty) => {{
            if let Some(value) = <$t>::from_label(label) {
                let p = pair($g, $s, spacing, unit)?;
                return py
                    .detach(|| {
                        evaluate_label_data(&p.geometry, &p.gt.data, &p.seg.data, value, tolerance)
                    })
                    .map_err(error);
            }
        }};
    }
    match (a, b) {
        (AnyArray::Bool(g), AnyArray::Bool(s)) => same!(g, s, bool),
        (AnyArray::U8(g), AnyArray::U8(s)) => same!(g, s, u8),
        (AnyArray::I8(g), AnyArray::I8(s)) => same!(g, s, i8),
        (AnyArray::U16(g), AnyArray::U16(s)) => same!(g, s, u16),
        (AnyArray::I16(g), AnyArray::I16(s)) => same!(g, s, i16),
        (AnyArray::U32(g), AnyArray::U32(s)) => same!(g, s, u32),
        (AnyArray::I32(g), AnyArray::I32(s)) => same!(g, s, i32),
        (AnyArray::U64(g), AnyArray::U64(s)) => same!(g, s, u64),
        (AnyArray::I64(g), AnyArray::I64(s)) => same!(g, s, i64),
        (AnyArray::F32(g), AnyArray::F32(s)) => same!(g, s, f32),
        (AnyArray::F64(g), AnyArray::F64(s)) => same!(g, s, f64),
        _ => {}
    }
    // Different element types (or a label the type cannot hold): as u16 labels.
    let (g, s, geo) = u16_pair(py, a, b, spacing, unit)?;
    py.detach(|| evaluate_label_data(&geo, &g, &s, label, tolerance))
        .map_err(error)
}

/// Parse a spacing sequence of 3 numbers.
pub(crate) fn spacing3(spacing: Vec<f64>) -> PyResult<[f64; 3]> {
    <[f64; 3]>::try_from(spacing.as_slice()).map_err(|_| {
        error(format!(
            "spacing must have 3 values (sx, sy, sz), got {}",
            spacing.len()
        ))
    })
}

/// Metrics of a segmentation against a ground truth, as `interslice evaluate
/// GT SEG --json` prints them (the same keys, the same values).
///
/// `gt` and `seg` are label arrays of one shape indexed `[x, y, z]` (any
/// integer or bool dtype), `spacing` is `(sx, sy, sz)` in `unit` (distances
/// are in that unit, volumes in its cube). With `label=N` the voxels equal
/// to N are foreground (for 0/1 masks N = 1) and the result is one dict
/// `{"label": N, "tp": ..., "dice": ..., "hd95": ..., ...}`; without it,
/// `{"labels": {"1": {...}, ...}, "foreground": {...}}` for every label
/// present in either array and their union. `tolerance` is the NSD tolerance.
/// Ratios with a zero denominator and distances with an empty border are None.
///
/// Arrays in Fortran or C order are read in place (no copy); the GIL is
/// released while the metrics run (do not modify the arrays meanwhile).
#[pyfunction]
#[pyo3(signature = (gt, seg, spacing=vec![1.0, 1.0, 1.0], label=None, tolerance=1.0, unit=None))]
pub fn evaluate<'py>(
    py: Python<'py>,
    gt: &Bound<'py, PyAny>,
    seg: &Bound<'py, PyAny>,
    spacing: Vec<f64>,
    label: Option<u16>,
    tolerance: f64,
    unit: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let spacing = spacing3(spacing)?;
    let unit = parse_unit(unit)?;
    let a = any_array(gt, "gt")?;
    let b = any_array(seg, "seg")?;
    check_shapes(&a, &b)?;
    if let Some(label) = label {
        let m = label_metrics(py, &a, &b, label, spacing, unit, tolerance)?;
        if m.tp + m.fp + m.fn_ == 0 {
            PyErr::warn(
                py,
                &py.get_type::<PyUserWarning>(),
                &std::ffi::CString::new(format!(
                    "label {label} is in neither array; its metrics are those of two empty masks"
                ))?,
                1,
            )?;
        }
        return to_py(py, &LabelReport { label, metrics: &m });
    }
    let (all, fg) = if let (AnyArray::U16(g), AnyArray::U16(s)) = (&a, &b) {
        let p = pair(g, s, spacing, unit)?;
        py.detach(|| {
            evaluate_all_and_foreground_data(&p.geometry, &p.gt.data, &p.seg.data, tolerance)
        })
    } else {
        let (g, s, geo) = u16_pair(py, &a, &b, spacing, unit)?;
        py.detach(|| evaluate_all_and_foreground_data(&geo, &g, &s, tolerance))
    }
    .map_err(error)?;
    to_py(
        py,
        &AllReport {
            labels: all.iter().map(|(l, m)| (*l, m)).collect(),
            foreground: &fg,
        },
    )
}

/// The overlap metrics of [`overlap`].
#[derive(Serialize)]
struct Overlap {
    label: u16,
    tp: u64,
    fp: u64,
    #[serde(rename = "fn")]
    fn_: u64,
    tn: u64,
    dice: Option<f64>,
    jaccard: Option<f64>,
    sensitivity: Option<f64>,
    specificity: Option<f64>,
    precision: Option<f64>,
    volume_similarity: Option<f64>,
    volume_gt: f64,
    volume_seg: f64,
    unit: &'static str,
}

/// Only the overlap metrics of one label (one pass over both arrays, no
/// distances): `tp`, `fp`, `fn`, `tn`, `dice`, `jaccard`, `sensitivity`,
/// `specificity`, `precision`, `volume_similarity`, `volume_gt`,
/// `volume_seg`, with the values `evaluate` gives for them. For scoring
/// many segmentations fast; arrays are read in place, the GIL released.
#[pyfunction]
#[pyo3(signature = (gt, seg, label=1, spacing=vec![1.0, 1.0, 1.0], unit=None))]
pub fn overlap<'py>(
    py: Python<'py>,
    gt: &Bound<'py, PyAny>,
    seg: &Bound<'py, PyAny>,
    label: u16,
    spacing: Vec<f64>,
    unit: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let spacing = spacing3(spacing)?;
    let unit = parse_unit(unit)?;
    let a = any_array(gt, "gt")?;
    let b = any_array(seg, "seg")?;
    check_shapes(&a, &b)?;
    let g0 = geometry(a.shape(), spacing, unit)?;
    macro_rules! same {
        ($g:expr, $s:expr, $t:ty) => {{
            if let Some(value) = <$t>::from_label(label) {
                let p = pair($g, $s, spacing, unit)?;
                Some(py.detach(|| confusion_of(&p.gt.data, &p.seg.data, value)))
            } else {
                None
            }
        }};
    }
    let c: Option<Confusion> = match (&a, &b) {
        (AnyArray::Bool(g), AnyArray::Bool(s)) => same!(g, s, bool),
        (AnyArray::U8(g), AnyArray::U8(s)) => same!(g, s, u8),
        (AnyArray::U16(g), AnyArray::U16(s)) => same!(g, s, u16),
        (AnyArray::I16(g), AnyArray::I16(s)) => same!(g, s, i16),
        (AnyArray::I32(g), AnyArray::I32(s)) => same!(g, s, i32),
        (AnyArray::I64(g), AnyArray::I64(s)) => same!(g, s, i64),
        _ => None,
    };
    let c = match c {
        Some(c) => c,
        None => {
            let (g, s, _) = u16_pair(py, &a, &b, spacing, unit)?;
            py.detach(|| confusion_of(&g, &s, label))
        }
    };
    let vox = g0.voxel_volume();
    to_py(
        py,
        &Overlap {
            label,
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
            unit: unit.symbol(),
        },
    )
}

/// NaN (no foreground or no background in the estimate) as None.
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

#[derive(Serialize)]
struct RaterStats {
    rater: usize,
    sensitivity: Option<f64>,
    specificity: Option<f64>,
}

#[derive(Serialize)]
struct StapleStats {
    label: Option<u16>,
    prior: f64,
    iterations: usize,
    converged: bool,
    consensus_voxels: u64,
    raters: Vec<RaterStats>,
}

/// STAPLE consensus (Warfield, Zou & Wells 2004, as ITK's filter) of 2..=20
/// masks of one shape: `(consensus, stats)`.
///
/// A mask's foreground is every non-zero voxel, or the voxels equal to
/// `label` when it is given. `consensus` is a uint8 0/1 array `[x, y, z]`;
/// `stats` is `{"label", "prior", "iterations", "converged",
/// "consensus_voxels", "raters": [{"rater": index, "sensitivity",
/// "specificity"}, ...]}` (the keys of `interslice staple --json`, raters by
/// their index in `masks`).
#[pyfunction]
#[pyo3(signature = (masks, label=None, max_iterations=10_000))]
pub fn staple<'py>(
    py: Python<'py>,
    masks: Vec<Bound<'py, PyAny>>,
    label: Option<u16>,
    max_iterations: usize,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    if masks.len() < 2 || masks.len() > MAX_RATERS {
        return Err(error(format!(
            "STAPLE needs 2 to {MAX_RATERS} masks, got {}",
            masks.len()
        )));
    }
    let arrays: Vec<AnyArray<'py>> = masks
        .iter()
        .enumerate()
        .map(|(i, m)| any_array(m, &format!("masks[{i}]")))
        .collect::<PyResult<_>>()?;
    let dims = arrays[0].shape();
    if let Some((i, a)) = arrays.iter().enumerate().find(|(_, a)| a.shape() != dims) {
        return Err(error(format!(
            "masks[0] and masks[{i}] differ: shape {dims:?} vs {:?}",
            a.shape()
        )));
    }
    let g = geometry(dims, [1.0; 3], LengthUnit::Unknown)?;
    let params = StapleParams {
        max_iterations: max_iterations.max(1),
        ..Default::default()
    };
    let labels: Vec<Vec<u16>> = arrays
        .iter()
        .enumerate()
        .map(|(i, a)| labels_u16(py, a, &format!("masks[{i}]")))
        .collect::<PyResult<_>>()?;
    drop(arrays);
    let (consensus, stats) = py.detach(|| -> PyResult<(Vec<u8>, StapleStats)> {
        let mut vols: Vec<Mask> = Vec::with_capacity(labels.len());
        for l in &labels {
            let m: Vec<bool> = match label {
                Some(want) => l.iter().map(|&v| v == want).collect(),
                None => l.iter().map(|&v| v != 0).collect(),
            };
            vols.push(Volume::from_vec(g.clone(), m).map_err(error)?);
        }
        let refs: Vec<&Mask> = vols.iter().collect();
        // A Python call runs to its end (no cancellation from Python yet).
        let s = interslice_core::staple::staple(&refs, params, &interslice_core::Cancel::new())
            .map_err(error)?;
        let consensus: Vec<u8> = s.consensus.data().iter().map(|&b| u8::from(b)).collect();
        let stats = StapleStats {
            label,
            prior: s.prior,
            iterations: s.iterations,
            converged: s.converged,
            consensus_voxels: consensus.iter().map(|&b| u64::from(b)).sum(),
            raters: (0..refs.len())
                .map(|j| RaterStats {
                    rater: j,
                    sensitivity: finite(s.sensitivity[j]),
                    specificity: finite(s.specificity[j]),
                })
                .collect(),
        };
        Ok((consensus, stats))
    })?;
    let stats_py = to_py(py, &stats)?;
    let _: &Bound<'_, PyDict> = stats_py.cast()?;
    Ok((to_numpy(py, consensus, dims)?.into_any(), stats_py))
}
