//! `read`, `write` and `phantom`: volumes with their geometry as
//! `(array, meta)`, meta being `{"spacing", "unit", "origin", "direction"}`.
use crate::arrays::{AnyArray, Order, any_array, to_numpy, voxels};
use crate::{error, to_py};
use interslice_core::geometry::IDENTITY_DIRECTION;
use interslice_core::phantom::{PhantomParams, generate};
use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;

/// The meta dict of a geometry.
fn meta<'py>(py: Python<'py>, g: &Geometry) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("spacing", PyTuple::new(py, g.spacing)?)?;
    d.set_item("unit", g.unit.symbol())?;
    d.set_item("origin", PyTuple::new(py, g.origin)?)?;
    let rows: Vec<Bound<'py, PyTuple>> = g
        .direction
        .iter()
        .map(|r| PyTuple::new(py, r))
        .collect::<PyResult<_>>()?;
    d.set_item("direction", PyTuple::new(py, rows)?)?;
    Ok(d)
}

/// Three finite numbers from a sequence.
fn triple(v: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; 3]> {
    let v: Vec<f64> = v
        .extract()
        .map_err(|_| error(format!("{what} must be a sequence of 3 numbers")))?;
    <[f64; 3]>::try_from(v.as_slice())
        .map_err(|_| error(format!("{what} must have 3 values, got {}", v.len())))
}

/// A unit from its name ("µm", "um", "mm", "m", "unknown").
pub(crate) fn parse_unit(unit: Option<&str>) -> PyResult<LengthUnit> {
    match unit {
        None => Ok(LengthUnit::Unknown),
        Some(u) => LengthUnit::parse(u).ok_or_else(|| {
            error(format!(
                "unknown unit '{u}' (expected µm, um, mm, m or unknown)"
            ))
        }),
    }
}

/// Dims, spacing and unit as a validated geometry (origin 0, identity direction).
pub(crate) fn geometry(
    dims: [usize; 3],
    spacing: [f64; 3],
    unit: LengthUnit,
) -> PyResult<Geometry> {
    Geometry::new(dims, spacing, unit).map_err(error)
}

/// The geometry a meta dict describes for an array of `dims`.
fn geometry_of_meta(dims: [usize; 3], meta: Option<&Bound<'_, PyAny>>) -> PyResult<Geometry> {
    let mut g = geometry(dims, [1.0; 3], LengthUnit::Unknown)?;
    let Some(meta) = meta.filter(|m| !m.is_none()) else {
        return Ok(g);
    };
    let get = |key: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
        match meta.get_item(key) {
            Ok(v) if !v.is_none() => Ok(Some(v)),
            Ok(_) => Ok(None),
            Err(e) if e.is_instance_of::<pyo3::exceptions::PyKeyError>(meta.py()) => Ok(None),
            Err(e) => Err(e),
        }
    };
    if let Some(s) = get("spacing")? {
        g.spacing = triple(&s, "meta['spacing']")?;
    }
    if let Some(u) = get("unit")? {
        g.unit = parse_unit(Some(&u.extract::<String>()?))?;
    }
    if let Some(o) = get("origin")? {
        g.origin = triple(&o, "meta['origin']")?;
    }
    if let Some(d) = get("direction")? {
        let rows: Vec<Bound<'_, PyAny>> = d
            .try_iter()
            .map_err(|_| error("meta['direction'] must be 3 rows of 3 numbers"))?
            .collect::<PyResult<_>>()?;
        if rows.len() != 3 {
            return Err(error("meta['direction'] must be 3 rows of 3 numbers"));
        }
        let mut m = IDENTITY_DIRECTION;
        for (r, row) in m.iter_mut().zip(&rows) {
            *r = triple(row, "a row of meta['direction']")?;
        }
        if m.iter().flatten().any(|x| !x.is_finite()) {
            return Err(error("meta['direction'] must hold finite numbers"));
        }
        g.direction = m;
    }
    g.validate().map_err(error)?;
    Ok(g)
}

/// Read a volume file: `(array, meta)`.
///
/// Every format interslice reads: NIfTI-1 (`.nii`, `.nii.gz`), NRRD (`.nrrd`,
/// `.nhdr`, `.seg.nrrd`), MetaImage (`.mha`, `.mhd`), ImageJ TIFF stacks
/// (`.tif`) and folders of PNG/TIFF slices. The array is indexed `[x, y, z]`
/// (nibabel's order; SimpleITK's `GetArrayFromImage` gives `[z, y, x]`, its
/// `.T`) and is Fortran-ordered, so `array[:, :, k]` is slice z=k. Its dtype
/// is the file's (uint8, uint16, int16 or float32); values are never rescaled.
/// `meta` is `{"spacing": (sx, sy, sz), "unit": "µm", "origin": (ox, oy, oz),
/// "direction": ((...), (...), (...))}`, origin and direction as SimpleITK's
/// `GetOrigin()` and `GetDirection()` (LPS, columns are the axes).
#[pyfunction]
pub fn read<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let v = py
        .detach(|| interslice_io::read_volume(&path))
        .map_err(error)?;
    let m = meta(py, v.geometry())?;
    let dims = v.geometry().dims;
    let arr = match v {
        AnyVolume::U8(v) => to_numpy(py, v.into_parts().1, dims)?.into_any(),
        AnyVolume::U16(v) => to_numpy(py, v.into_parts().1, dims)?.into_any(),
        AnyVolume::I16(v) => to_numpy(py, v.into_parts().1, dims)?.into_any(),
        AnyVolume::F32(v) => to_numpy(py, v.into_parts().1, dims)?.into_any(),
    };
    Ok((arr, m))
}

/// Write `array` (indexed `[x, y, z]`) to a volume file; the format follows
/// the name, as for `read`. `meta` (optional, as `read` returns it; missing
/// keys mean spacing 1, unknown unit, origin 0, identity direction) gives the
/// geometry. dtypes: uint8, uint16, int16, float32 (bool is written as
/// uint8); PNG slice folders hold only uint8 and uint16. The write is atomic
/// (a temporary file renamed over the target).
#[pyfunction]
#[pyo3(signature = (path, array, meta=None))]
pub fn write(
    py: Python<'_>,
    path: PathBuf,
    array: &Bound<'_, PyAny>,
    meta: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let a = any_array(array, "array")?;
    let g = geometry_of_meta(a.shape(), meta)?;
    macro_rules! owned {
        ($a:expr) => {
            voxels($a, Some(Order::XFast)).data.into_owned()
        };
    }
    let v = match &a {
        AnyArray::Bool(b) => {
            let data: Vec<u8> = voxels(b, Some(Order::XFast))
                .data
                .iter()
                .map(|&x| u8::from(x))
                .collect();
            AnyVolume::U8(Volume::from_vec(g, data).map_err(error)?)
        }
        AnyArray::U8(b) => AnyVolume::U8(Volume::from_vec(g, owned!(b)).map_err(error)?),
        AnyArray::U16(b) => AnyVolume::U16(Volume::from_vec(g, owned!(b)).map_err(error)?),
        AnyArray::I16(b) => AnyVolume::I16(Volume::from_vec(g, owned!(b)).map_err(error)?),
        AnyArray::F32(b) => AnyVolume::F32(Volume::from_vec(g, owned!(b)).map_err(error)?),
        other => {
            return Err(error(format!(
                "cannot write {} arrays (interslice stores uint8, uint16, int16 and float32; \
                 convert with array.astype(...))",
                other.dtype_name()
            )));
        }
    };
    py.detach(|| interslice_io::write_volume(&path, &v))
        .map_err(error)
}

/// The digital phantom of a stained cell (as `interslice phantom`):
/// `(image, labels, meta)`. `image` is uint8 or uint16 (`bits`), `labels`
/// uint8 (0 background, 1 cell, 2 nucleus, 3.. nucleoli, a painted
/// partition), both `[x, y, z]` of `size`³ voxels of 0.35 µm. `meta` also
/// holds `"structures"`: name, label, voxels and volume (µm³) of each.
/// The same seed gives the same arrays.
#[pyfunction]
#[pyo3(signature = (size=128, seed=1, bits=8, noise=0.02))]
pub fn phantom(
    py: Python<'_>,
    size: usize,
    seed: u64,
    bits: u8,
    noise: f64,
) -> PyResult<(Bound<'_, PyAny>, Bound<'_, PyAny>, Bound<'_, PyDict>)> {
    let params = PhantomParams {
        size,
        seed,
        bits,
        noise,
    };
    params.validate().map_err(error)?;
    let p = py.detach(|| generate(&params)).map_err(error)?;
    let m = meta(py, p.labels.geometry())?;
    m.set_item("structures", to_py(py, &p.structures)?)?;
    let dims = p.labels.geometry().dims;
    let image = match p.intensity {
        AnyVolume::U8(v) => to_numpy(py, v.into_parts().1, dims)?.into_any(),
        AnyVolume::U16(v) => to_numpy(py, v.into_parts().1, dims)?.into_any(),
        AnyVolume::I16(v) => to_numpy(py, v.into_parts().1, dims)?.into_any(),
        AnyVolume::F32(v) => to_numpy(py, v.into_parts().1, dims)?.into_any(),
    };
    let (_, labels) = p.labels.into_parts();
    let labels = if labels.iter().all(|&l| l <= u16::from(u8::MAX)) {
        to_numpy(py, labels.iter().map(|&l| l as u8).collect(), dims)?.into_any()
    } else {
        to_numpy(py, labels, dims)?.into_any()
    };
    Ok((image, labels, m))
}
