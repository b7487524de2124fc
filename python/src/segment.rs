//! `threshold`: automated segmentation of an intensity array.
use crate::arrays::{AnyArray, Order, any_array, to_numpy, voxels};
use crate::metrics::spacing3;
use crate::volumes::{geometry, parse_unit};
use crate::{error, to_py};
use interslice_core::morph::Connectivity;
use interslice_core::segment::{SegmentMethod, SegmentParams, segment_detailed};
use interslice_core::{AnyVolume, Volume};
use pyo3::prelude::*;

/// Threshold an intensity array, as `interslice segment` does: `(labels,
/// summary)`.
///
/// `image` is indexed `[x, y, z]`, dtype uint8, uint16, int16 or float32
/// (8/16-bit data get one histogram bin per grey level, float32 256 bins).
/// `method` is "otsu", "rosin", "kmeans" or "multi-otsu"; `classes` counts
/// background (2 for otsu/rosin, default 3 for multi-otsu); a voxel `v` gets
/// the number of thresholds `t` with `v > t`. Optionally Gaussian smoothing
/// first (`smooth` = σ in the units of `spacing`), only the largest connected
/// component (`connectivity` 6 or 26), holes filled. `labels` is uint8 (or
/// uint16 beyond 255 labels); `summary` has the keys of `segment --json`
/// (`thresholds`, `binning`, `labels` with voxels and volumes, ...).
#[pyfunction]
#[pyo3(signature = (image, method="otsu", classes=None, smooth=0.0, largest_component=false,
    connectivity=6, fill_holes=false, spacing=vec![1.0, 1.0, 1.0], unit=None))]
#[allow(clippy::too_many_arguments)]
pub fn threshold<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    method: &str,
    classes: Option<usize>,
    smooth: f64,
    largest_component: bool,
    connectivity: u8,
    fill_holes: bool,
    spacing: Vec<f64>,
    unit: Option<&str>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let method = SegmentMethod::parse(method).map_err(error)?;
    let connectivity = Connectivity::parse(&connectivity.to_string()).map_err(error)?;
    if connectivity == Connectivity::Full && !largest_component {
        return Err(error(
            "connectivity only matters with largest_component=True",
        ));
    }
    let p = SegmentParams {
        method,
        classes: classes.unwrap_or(match method {
            SegmentMethod::MultiOtsu => 3,
            _ => 2,
        }),
        smooth_sigma: smooth,
        largest_component,
        connectivity,
        fill_holes,
    };
    p.validate().map_err(error)?;
    let a = any_array(image, "image")?;
    let dims = a.shape();
    let g = geometry(dims, spacing3(spacing)?, parse_unit(unit)?)?;
    macro_rules! vol {
        ($x:expr, $v:ident) => {
            AnyVolume::$v(
                Volume::from_vec(g, voxels($x, Some(Order::XFast)).data.into_owned())
                    .map_err(error)?,
            )
        };
    }
    let v = match &a {
        AnyArray::U8(x) => vol!(x, U8),
        AnyArray::U16(x) => vol!(x, U16),
        AnyArray::I16(x) => vol!(x, I16),
        AnyArray::F32(x) => vol!(x, F32),
        other => {
            return Err(error(format!(
                "image must be uint8, uint16, int16 or float32, got {}",
                other.dtype_name()
            )));
        }
    };
    let seg = py
        .detach(|| segment_detailed(&v, &p, &interslice_core::Cancel::new()))
        .map_err(error)?;
    let summary = to_py(py, &seg.summary(&p))?;
    let (_, labels) = seg.labels.into_parts();
    let labels = if labels.iter().all(|&l| l <= u16::from(u8::MAX)) {
        to_numpy(py, labels.iter().map(|&l| l as u8).collect(), dims)?.into_any()
    } else {
        to_numpy(py, labels, dims)?.into_any()
    };
    Ok((labels, summary))
}
