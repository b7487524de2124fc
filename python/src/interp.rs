//! `interpolate`, `advise` and `methods`.
use crate::arrays::{
    AnyArray, FromLabel, any_array, drawn_slices_u16, intensities_f32, nonzero_slices, strided,
    to_numpy, with_array,
};
use crate::metrics::spacing3;
use crate::volumes::geometry;
use crate::{error, parse_axis};
use interslice_core::{Axis, LengthUnit, Volume, Voxel};
use interslice_interp::image::Conditioned;
use interslice_interp::labels::{
    DEFAULT_MAX_LABELS, DrawnLabels, interpolate_drawn_as, interpolate_drawn_with_confidence_as,
};
use interslice_interp::{DEFAULT_METHOD, Interpolator, by_name_with_image};
use numpy::{Element, PyReadonlyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Interpolate the slices between the drawn slices of a label array, as
/// `interslice interpolate` does (the same result voxel for voxel).
///
/// `labels` is indexed `[x, y, z]` (any integer or bool dtype, 0 =
/// background); its drawn slices along `axis` (0/1/2 or "x"/"y"/"z",
/// default z) carry the tracing. `drawn` lists the drawn slice indices (a
/// listed slice without a label is known to be empty); without it, the
/// slices holding any non-zero voxel are the drawn ones. Every label is
/// interpolated on its own and painted in ascending order. `spacing` is
/// `(sx, sy, sz)`; `method` names one of `methods()` (default: the best
/// measured one; with `image`, the image-aware one). `image` is the
/// intensity array on the same grid (any numeric dtype). More than
/// `max_labels` labels on the drawn slices is an error (each label is
/// interpolated on its own: an intensity array passed as labels would run
/// for minutes). Returns a new Fortran-ordered array of the input's
/// dtype; the drawn slices are reproduced exactly. With `confidence`,
/// returns `(labels, confidence)`: the second a float32 array of the same
/// shape, how sure the method is of each voxel's label, in `[0.5, 1]`
/// (1 on drawn slices and wherever the method is sure, 0.5 on a boundary
/// it is guessing; the least of any label there): what `interslice
/// interpolate --confidence` writes. The GIL is released while the
/// interpolation runs.
#[pyfunction]
#[pyo3(signature = (labels, drawn=None, axis=None, spacing=vec![1.0, 1.0, 1.0], image=None, method=None, max_labels=DEFAULT_MAX_LABELS, confidence=false))]
#[allow(clippy::too_many_arguments)]
pub fn interpolate<'py>(
    py: Python<'py>,
    labels: &Bound<'py, PyAny>,
    drawn: Option<Vec<i64>>,
    axis: Option<&Bound<'py, PyAny>>,
    spacing: Vec<f64>,
    image: Option<&Bound<'py, PyAny>>,
    method: Option<&str>,
    max_labels: usize,
    confidence: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let a = any_array(labels, "labels")?;
    let dims = a.shape();
    let t = Tracing::of(py, &a, drawn, axis, spacing, image, method)?;
    t.check_labels(max_labels)?;
    with_array!(&a, x => interpolated_like(py, x, &t, dims, confidence))
}

/// The interpolation of `t` painted straight into an array of the element
/// type of `_like` (every label fits: they come from that array); with
/// `confidence`, a tuple of it and the confidence per voxel.
fn interpolated_like<'py, T: Element + FromLabel + Voxel>(
    py: Python<'py>,
    _like: &PyReadonlyArray3<'_, T>,
    t: &Tracing,
    dims: [usize; 3],
    confidence: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let method = t.method.as_ref();
    let value = |l| T::from_label(l).unwrap_or_default();
    if !confidence {
        let out = py
            .detach(|| interpolate_drawn_as(method, &t.planes, value))
            .map_err(error)?;
        return Ok(to_numpy(py, out.into_parts().1, dims)?.into_any());
    }
    let (out, conf) = py
        .detach(|| interpolate_drawn_with_confidence_as(method, &t.planes, value))
        .map_err(error)?;
    let labels = to_numpy(py, out.into_parts().1, dims)?;
    let conf = to_numpy(py, conf.into_parts().1, dims)?;
    Ok((labels, conf).into_pyobject(py)?.into_any())
}

/// Which undrawn slices to trace next, as `interslice advise --json` prints
/// it: `{"axis", "drawn", "suggestions": [{"slice", "gain_voxels",
/// "dice_gain", "between"}, ...], "predicted_dice", "volume_voxels"}`, the
/// `count` best suggestions first. The arguments mean what they mean for
/// `interpolate` (the advice is for the interpolation `method` and `image`
/// would give). The GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (labels, drawn=None, axis=None, spacing=vec![1.0, 1.0, 1.0], image=None, method=None, count=5, max_labels=DEFAULT_MAX_LABELS))]
#[allow(clippy::too_many_arguments)]
pub fn advise<'py>(
    py: Python<'py>,
    labels: &Bound<'py, PyAny>,
    drawn: Option<Vec<i64>>,
    axis: Option<&Bound<'py, PyAny>>,
    spacing: Vec<f64>,
    image: Option<&Bound<'py, PyAny>>,
    method: Option<&str>,
    count: usize,
    max_labels: usize,
) -> PyResult<Bound<'py, PyAny>> {
    if !(1..=1000).contains(&count) {
        return Err(error(format!("count must be 1..=1000, got {count}")));
    }
    let a = any_array(labels, "labels")?;
    let t = Tracing::of(py, &a, drawn, axis, spacing, image, method)?;
    t.check_labels(max_labels)?;
    let advice = py
        .detach(|| {
            interslice_interp::advise::advise(
                &t.planes.volume(),
                t.axis,
                &t.drawn,
                count,
                method,
                t.image.clone(),
            )
        })
        .map_err(error)?;
    crate::to_py(py, &advice)
}

/// A tracing handed in from Python: the sparse labels, the axis, the drawn
/// slices and the method (image-aware when an image is given).
struct Tracing {
    planes: DrawnLabels,
    axis: Axis,
    drawn: Vec<usize>,
    method: Box<dyn Interpolator>,
    image: Option<Conditioned>,
}

impl Tracing {
    /// An error when more than `max` labels are drawn (the CLI's
    /// `--max-labels`, in the same words).
    fn check_labels(&self, max: usize) -> PyResult<()> {
        let n = self.planes.labels().len();
        if n > max {
            return Err(error(format!(
                "labels has {n} labels on its drawn slices, more than max_labels {max} \
                 (is it an intensity image? pass max_labels={n} to interpolate every one)"
            )));
        }
        Ok(())
    }

    fn of<'py>(
        py: Python<'py>,
        a: &AnyArray<'py>,
        drawn: Option<Vec<i64>>,
        axis: Option<&Bound<'py, PyAny>>,
        spacing: Vec<f64>,
        image: Option<&Bound<'py, PyAny>>,
        method: Option<&str>,
    ) -> PyResult<Tracing> {
        let axis = match axis {
            Some(a) => parse_axis(a)?,
            None => Axis::Z,
        };
        let spacing = spacing3(spacing)?;
        let dims = a.shape();
        let g = geometry(dims, spacing, LengthUnit::Unknown)?;
        let ig = g.clone();
        let image = match image {
            Some(img) => {
                let i = any_array(img, "image")?;
                if i.shape() != dims {
                    return Err(error(format!(
                        "image and labels differ: shape {:?} vs {dims:?}",
                        i.shape()
                    )));
                }
                let data = intensities_f32(py, &i);
                Some(Conditioned::from(
                    Volume::from_vec(ig, data).map_err(error)?,
                ))
            }
            None => None,
        };
        let method = by_name_with_image(method, image.clone()).map_err(error)?;
        let count = dims[axis.dim()] as i64;
        let drawn = match drawn {
            Some(d) => Some(
                d.into_iter()
                    .map(|i| {
                        usize::try_from(i)
                            .ok()
                            .filter(|&u| (u as i64) < count)
                            .ok_or_else(|| {
                                error(format!(
                                    "drawn slice {axis}={i} is out of range (0..{count})"
                                ))
                            })
                    })
                    .collect::<PyResult<Vec<usize>>>()?,
            ),
            None => None,
        };
        let (planes, drawn) = with_array!(a, x => {
            let v = strided(x);
            py.detach(|| {
                let mut drawn = drawn.unwrap_or_else(|| nonzero_slices(&v, axis));
                drawn.sort_unstable();
                drawn.dedup();
                drawn_slices_u16(&v, g, axis, &drawn, "labels").map(|s| (s, drawn))
            })?
        });
        Ok(Tracing {
            planes,
            axis,
            drawn,
            method,
            image,
        })
    }
}

/// The interpolation methods, the default first: a list of
/// `{"name", "description", "default"}` (what `interslice interpolate
/// --list` prints).
#[pyfunction]
pub fn methods(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    interslice_interp::methods()
        .iter()
        .map(|m| {
            let d = PyDict::new(py);
            d.set_item("name", m.name())?;
            d.set_item("description", m.description())?;
            d.set_item("default", m.name() == DEFAULT_METHOD)?;
            Ok(d)
        })
        .collect()
}
