//! numpy arrays in and out.
//!
//! The core stores a volume x-fastest (`i + nx * (j + ny * k)`). A numpy
//! array indexed `[x, y, z]` in Fortran order (what nibabel returns, and what
//! `interslice.read` returns) has exactly that layout, so it is used in place.
//! A C-ordered `[x, y, z]` array has the layout of an x-fastest volume with
//! the axes reversed; metrics do not depend on the order of the axes (given
//! the spacing in the same order), so `evaluate` uses those in place too.
//! Anything else (a strided view) is copied once.
use crate::error;
use interslice_core::{Axis, Geometry};
use interslice_interp::labels::DrawnLabels;
use numpy::ndarray::{Array3, ShapeBuilder};
use numpy::{
    Element, IntoPyArray, PyArray3, PyArrayMethods, PyReadonlyArray3, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use std::borrow::Cow;

/// A 3-D numpy array of one of the voxel types interslice accepts.
pub(crate) enum AnyArray<'py> {
    Bool(PyReadonlyArray3<'py, bool>),
    U8(PyReadonlyArray3<'py, u8>),
    I8(PyReadonlyArray3<'py, i8>),
    U16(PyReadonlyArray3<'py, u16>),
    I16(PyReadonlyArray3<'py, i16>),
    U32(PyReadonlyArray3<'py, u32>),
    I32(PyReadonlyArray3<'py, i32>),
    U64(PyReadonlyArray3<'py, u64>),
    I64(PyReadonlyArray3<'py, i64>),
    F32(PyReadonlyArray3<'py, f32>),
    F64(PyReadonlyArray3<'py, f64>),
}

/// Run `$body` with `$a` bound to the typed array inside an [`AnyArray`].
macro_rules! with_array {
    ($any:expr, $a:ident => $body:expr) => {
        match $any {
            $crate::arrays::AnyArray::Bool($a) => $body,
            $crate::arrays::AnyArray::U8($a) => $body,
            $crate::arrays::AnyArray::I8($a) => $body,
            $crate::arrays::AnyArray::U16($a) => $body,
            $crate::arrays::AnyArray::I16($a) => $body,
            $crate::arrays::AnyArray::U32($a) => $body,
            $crate::arrays::AnyArray::I32($a) => $body,
            $crate::arrays::AnyArray::U64($a) => $body,
            $crate::arrays::AnyArray::I64($a) => $body,
            $crate::arrays::AnyArray::F32($a) => $body,
            $crate::arrays::AnyArray::F64($a) => $body,
        }
    };
}
pub(crate) use with_array;

impl AnyArray<'_> {
    /// numpy's name of the element type.
    pub(crate) fn dtype_name(&self) -> &'static str {
        match self {
            AnyArray::Bool(_) => "bool",
            AnyArray::U8(_) => "uint8",
            AnyArray::I8(_) => "int8",
            AnyArray::U16(_) => "uint16",
            AnyArray::I16(_) => "int16",
            AnyArray::U32(_) => "uint32",
            AnyArray::I32(_) => "int32",
            AnyArray::U64(_) => "uint64",
            AnyArray::I64(_) => "int64",
            AnyArray::F32(_) => "float32",
            AnyArray::F64(_) => "float64",
        }
    }

    /// The shape, `(nx, ny, nz)`.
    pub(crate) fn shape(&self) -> [usize; 3] {
        with_array!(self, a => { let s = a.shape(); [s[0], s[1], s[2]] })
    }
}

/// Borrow `obj` as a 3-D array; `what` names it in errors ("gt", "labels").
pub(crate) fn any_array<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<AnyArray<'py>> {
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        return Err(error(format!(
            "{what} must be a numpy array, got {}",
            obj.get_type().name()?
        )));
    };
    if untyped.ndim() != 3 {
        return Err(error(format!(
            "{what} must be a 3-D array indexed [x, y, z], got shape {:?}",
            untyped.shape()
        )));
    }
    macro_rules! try_type {
        ($($t:ty => $v:ident),*) => {$(
            if let Ok(a) = obj.cast::<PyArray3<$t>>() {
                return Ok(AnyArray::$v(a.try_readonly().map_err(error)?));
            }
        )*};
    }
    try_type!(bool => Bool, u8 => U8, i8 => I8, u16 => U16, i16 => I16, u32 => U32,
        i32 => I32, u64 => U64, i64 => I64, f32 => F32, f64 => F64);
    Err(error(format!(
        "{what} has an unsupported element type {} (expected bool, integers or float32/float64)",
        untyped.dtype()
    )))
}

/// How a borrowed array's voxels are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Order {
    /// x-fastest with dims `(nx, ny, nz)`: a Fortran-ordered `[x, y, z]` array.
    XFast,
    /// x-fastest with dims `(nz, ny, nx)`: a C-ordered `[x, y, z]` array.
    Reversed,
}

/// The voxels of an array in one [`Order`], borrowed when its memory already
/// is in that order, else copied.
pub(crate) struct Voxels<'a, T: Clone> {
    pub data: Cow<'a, [T]>,
    /// Dims of `data` read x-fastest (reversed for [`Order::Reversed`]).
    pub dims: [usize; 3],
}

/// The order an array's memory is in, when it is contiguous.
pub(crate) fn memory_order<T: Element>(a: &PyReadonlyArray3<'_, T>) -> Option<Order> {
    if a.is_fortran_contiguous() {
        Some(Order::XFast)
    } else if a.is_c_contiguous() {
        Some(Order::Reversed)
    } else {
        None
    }
}

/// The voxels of `a` in `want` order, or in place in whichever order its
/// memory has when `want` is `None`.
pub(crate) fn voxels<'a, T: Element + Copy>(
    a: &'a PyReadonlyArray3<'_, T>,
    want: Option<Order>,
) -> Voxels<'a, T> {
    let s = a.shape();
    let shape = [s[0], s[1], s[2]];
    let have = memory_order(a);
    let order = want.or(have).unwrap_or(Order::XFast);
    let dims = match order {
        Order::XFast => shape,
        Order::Reversed => [shape[2], shape[1], shape[0]],
    };
    if have == Some(order)
        && let Ok(slice) = a.as_slice()
    {
        return Voxels {
            data: Cow::Borrowed(slice),
            dims,
        };
    }
    let view = a.as_array();
    let data: Vec<T> = match order {
        // The transposed view iterates (z, y, x) with x fastest.
        Order::XFast => view.t().iter().copied().collect(),
        Order::Reversed => view.iter().copied().collect(),
    };
    Voxels {
        data: Cow::Owned(data),
        dims,
    }
}

/// A voxel type read as an intensity (what the image-aware methods use).
pub(crate) trait Intensity: Copy {
    fn to_f32(self) -> f32;
}
macro_rules! intensity {
    ($($t:ty),*) => {$(impl Intensity for $t {
        #[inline]
        fn to_f32(self) -> f32 { self as f32 }
    })*};
}
intensity!(u8, i8, u16, i16, u32, i32, u64, i64, f32, f64);
impl Intensity for bool {
    #[inline]
    fn to_f32(self) -> f32 {
        f32::from(u8::from(self))
    }
}

/// The voxels of an intensity array as f32, x-fastest (the GIL released
/// while converting).
pub(crate) fn intensities_f32(py: Python<'_>, a: &AnyArray<'_>) -> Vec<f32> {
    with_array!(a, x => {
        let v = voxels(x, Some(Order::XFast));
        py.detach(|| v.data.iter().map(|&e| e.to_f32()).collect())
    })
}

/// A voxel type that may hold a label (an integer 0..=65535).
pub(crate) trait LabelValue: Copy {
    /// The label, or `None` when the value is not one.
    fn label(self) -> Option<u16>;
}
macro_rules! label_int {
    ($($t:ty),*) => {$(impl LabelValue for $t {
        #[inline]
        fn label(self) -> Option<u16> { u16::try_from(self).ok() }
    })*};
}
label_int!(u8, i8, u16, i16, u32, i32, u64, i64);
impl LabelValue for bool {
    #[inline]
    fn label(self) -> Option<u16> {
        Some(u16::from(self))
    }
}
macro_rules! label_float {
    ($($t:ty),*) => {$(impl LabelValue for $t {
        #[inline]
        fn label(self) -> Option<u16> {
            (self.is_finite() && (0.0..=65535.0).contains(&self) && self.fract() == 0.0)
                .then_some(self as u16)
        }
    })*};
}
label_float!(f32, f64);

/// Label values as u16 (a copy); errs on the first value that is not a label.
pub(crate) fn to_u16<T: LabelValue + Sync>(data: &[T], what: &str) -> PyResult<Vec<u16>> {
    use rayon::prelude::*;
    // Checked first, then converted by an indexed map: collecting into an
    // `Option<Vec>` cannot write in place and was most of a call's time.
    if data.par_iter().any(|v| v.label().is_none()) {
        return Err(error(format!(
            "{what} must hold integer labels 0..=65535 (0 = background)"
        )));
    }
    Ok(data.par_iter().map(|v| v.label().unwrap_or(0)).collect())
}

/// The voxels of an array in place, with the strides of its `x`, `y`, `z`
/// indices: no copy when the array is contiguous in either order (a strided
/// view is copied once, x-fastest).
pub(crate) struct Strided<'a, T: Clone> {
    pub data: Cow<'a, [T]>,
    /// The shape `(nx, ny, nz)`.
    pub dims: [usize; 3],
    /// Elements between neighbours along x, y and z.
    pub strides: [usize; 3],
}

/// `a`'s voxels with their strides (see [`Strided`]).
pub(crate) fn strided<'a, T: Element + Copy>(a: &'a PyReadonlyArray3<'_, T>) -> Strided<'a, T> {
    let s = a.shape();
    let dims = [s[0], s[1], s[2]];
    let order = memory_order(a);
    if let (Some(order), Ok(slice)) = (order, a.as_slice()) {
        let strides = match order {
            Order::XFast => [1, dims[0], dims[0] * dims[1]],
            Order::Reversed => [dims[1] * dims[2], dims[2], 1],
        };
        return Strided {
            data: Cow::Borrowed(slice),
            dims,
            strides,
        };
    }
    Strided {
        data: voxels(a, Some(Order::XFast)).data,
        dims,
        strides: [1, dims[0], dims[0] * dims[1]],
    }
}

impl<T: LabelValue + Clone> Strided<'_, T> {
    /// Slice `index` along `axis` as labels, row-major in the pixel order of
    /// [`interslice_core::Volume::slice`]; `None` if a value is not a label.
    fn labels_of_slice(&self, axis: Axis, index: usize) -> Option<Vec<u16>> {
        let (a, b) = axis.in_plane();
        let base = self.strides[axis.dim()] * index;
        let (su, sv) = (self.strides[a], self.strides[b]);
        let (w, h) = (self.dims[a], self.dims[b]);
        let mut out = vec![0u16; w * h];
        let mut all = true;
        for v in 0..h {
            let row = &mut out[w * v..w * (v + 1)];
            let start = base + v * sv;
            if su == 1 {
                // A contiguous row (a Fortran-ordered array read along z):
                // a loop the compiler vectorises.
                for (o, x) in row.iter_mut().zip(&self.data[start..start + w]) {
                    let l = x.label();
                    all &= l.is_some();
                    *o = l.unwrap_or(0);
                }
                continue;
            }
            for (u, o) in row.iter_mut().enumerate() {
                match self.data[start + u * su].label() {
                    Some(l) => *o = l,
                    None => all = false,
                }
            }
        }
        all.then_some(out)
    }

    /// The slices `drawn` along `axis`, as [`Strided::labels_of_slice`]
    /// gives each; `None` if a value is not a label.
    ///
    /// When `axis` is the array's fastest (a C-ordered `[x, y, z]` array read
    /// along z), a pixel's values along it are contiguous and slice-by-slice
    /// reading would fetch a cache line per value: every drawn slice is then
    /// read in one pass over the pixels instead.
    fn labels_of_slices(&self, axis: Axis, drawn: &[usize]) -> Option<Vec<Vec<u16>>>
    where
        T: Sync,
    {
        use rayon::prelude::*;
        if self.strides[axis.dim()] != 1 || drawn.len() < 2 {
            return drawn
                .par_iter()
                .map(|&index| self.labels_of_slice(axis, index))
                .collect();
        }
        let (a, b) = axis.in_plane();
        let (su, sv) = (self.strides[a], self.strides[b]);
        let (w, h) = (self.dims[a], self.dims[b]);
        let n = drawn.len();
        // Per row v of the plane, that row of every drawn slice.
        let rows: Option<Vec<Vec<u16>>> = (0..h)
            .into_par_iter()
            .map(|v| {
                let mut rows = vec![0u16; n * w];
                for u in 0..w {
                    let line = &self.data[u * su + v * sv..];
                    for (k, &d) in drawn.iter().enumerate() {
                        rows[k * w + u] = line[d].label()?;
                    }
                }
                Some(rows)
            })
            .collect();
        let rows = rows?;
        let mut out = vec![vec![0u16; w * h]; n];
        for (v, r) in rows.iter().enumerate() {
            for (k, plane) in out.iter_mut().enumerate() {
                plane[w * v..w * (v + 1)].copy_from_slice(&r[k * w..(k + 1) * w]);
            }
        }
        Some(out)
    }
}

/// The slices `drawn` (sorted, unique, along `axis`) of `a` on the grid `g`,
/// as u16 labels: interpolation reads the drawn slices only, so no volume
/// of the array's size is built (converting the whole array was most of a
/// call's time on large volumes). Errs on the first value of a drawn slice
/// that is not a label.
pub(crate) fn drawn_slices_u16<T: LabelValue + Clone + Sync>(
    a: &Strided<'_, T>,
    g: Geometry,
    axis: Axis,
    drawn: &[usize],
    what: &str,
) -> PyResult<DrawnLabels> {
    let slices = a.labels_of_slices(axis, drawn).ok_or_else(|| {
        error(format!(
            "{what} must hold integer labels 0..=65535 (0 = background)"
        ))
    })?;
    DrawnLabels::of_planes(g, axis, drawn, slices).map_err(error)
}

/// The slices along `axis` of `a` holding any non-zero value, ascending.
pub(crate) fn nonzero_slices<T: LabelValue + Clone + Sync>(
    a: &Strided<'_, T>,
    axis: Axis,
) -> Vec<usize> {
    use rayon::prelude::*;
    (0..a.dims[axis.dim()])
        .into_par_iter()
        .filter(|&index| {
            a.labels_of_slice(axis, index)
                .is_none_or(|s| s.iter().any(|&l| l != 0))
        })
        .collect()
}

/// A Fortran-ordered `[x, y, z]` numpy array owning `data` (x-fastest), no copy.
pub(crate) fn to_numpy<T: Element>(
    py: Python<'_>,
    data: Vec<T>,
    dims: [usize; 3],
) -> PyResult<Bound<'_, PyArray3<T>>> {
    let a = Array3::from_shape_vec((dims[0], dims[1], dims[2]).f(), data).map_err(error)?;
    Ok(a.into_pyarray(py))
}

/// A label value as the element type of an array (`None` when the type
/// cannot hold it, so no voxel can equal it).
pub(crate) trait FromLabel: Sized {
    fn from_label(l: u16) -> Option<Self>;
}
macro_rules! from_label_int {
    ($($t:ty),*) => {$(impl FromLabel for $t {
        fn from_label(l: u16) -> Option<Self> { <$t>::try_from(l).ok() }
    })*};
}
from_label_int!(u8, i8, u16, i16, u32, i32, u64, i64);
impl FromLabel for bool {
    fn from_label(l: u16) -> Option<Self> {
        match l {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        }
    }
}
impl FromLabel for f32 {
    fn from_label(l: u16) -> Option<Self> {
        Some(f32::from(l))
    }
}
impl FromLabel for f64 {
    fn from_label(l: u16) -> Option<Self> {
        Some(f64::from(l))
    }
}
