//! `Volume<T>`: a 3D array with its geometry, stored x-fastest.
use crate::{Axis, CoreError, Geometry};
use rayon::prelude::*;

/// Voxel types a volume can hold.
pub trait Voxel: Copy + Default + Send + Sync + PartialEq + std::fmt::Debug + 'static {
    /// The value as f64 (for statistics and interpolation).
    fn to_f64(self) -> f64;
}
macro_rules! voxel {
    ($($t:ty),*) => {$(impl Voxel for $t { #[inline] fn to_f64(self) -> f64 { self as f64 } })*};
}
voxel!(u8, i8, u16, i16, u32, i32, u64, i64, f32, f64);
impl Voxel for bool {
    #[inline]
    fn to_f64(self) -> f64 {
        if self { 1.0 } else { 0.0 }
    }
}

/// A 3D array of voxels with its geometry; `index = i + nx * (j + ny * k)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Volume<T> {
    geometry: Geometry,
    data: Vec<T>,
}

/// A label volume: 0 is background, labels are 1..=65535.
pub type LabelVolume = Volume<u16>;
/// A binary mask.
pub type Mask = Volume<bool>;

impl<T: Voxel> Volume<T> {
    /// A volume from data in x-fastest order; errs if the length does not match.
    pub fn from_vec(geometry: Geometry, data: Vec<T>) -> Result<Self, CoreError> {
        geometry.validate()?;
        if data.len() != geometry.len() {
            return Err(CoreError::DataLength {
                dims: geometry.dims,
                expected: geometry.len(),
                got: data.len(),
            });
        }
        Ok(Volume { geometry, data })
    }

    /// A volume filled with `value`.
    pub fn filled(geometry: Geometry, value: T) -> Self {
        let n = geometry.len();
        Volume {
            geometry,
            data: vec![value; n],
        }
    }

    /// A volume of zeros (`T::default()`).
    pub fn zeros(geometry: Geometry) -> Self {
        Self::filled(geometry, T::default())
    }

    /// The geometry.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// Replace the geometry's spacing/unit/origin/direction; dims must not change.
    pub fn set_geometry(&mut self, geometry: Geometry) -> Result<(), CoreError> {
        geometry.validate()?;
        if geometry.dims != self.geometry.dims {
            return Err(CoreError::GeometryMismatch(format!(
                "cannot change dims {:?} to {:?}",
                self.geometry.dims, geometry.dims
            )));
        }
        self.geometry = geometry;
        Ok(())
    }

    /// Dims `(nx, ny, nz)`.
    pub fn dims(&self) -> [usize; 3] {
        self.geometry.dims
    }

    /// Voxels in x-fastest order.
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// Mutable voxels in x-fastest order.
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Consume into geometry and data.
    pub fn into_parts(self) -> (Geometry, Vec<T>) {
        (self.geometry, self.data)
    }

    /// Voxel (i, j, k). Panics if out of range (a programming error).
    #[inline]
    pub fn get(&self, i: usize, j: usize, k: usize) -> T {
        self.data[self.geometry.index(i, j, k)]
    }

    /// Set voxel (i, j, k).
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, k: usize, value: T) {
        let idx = self.geometry.index(i, j, k);
        self.data[idx] = value;
    }

    /// Number of slices along `axis`.
    pub fn slice_count(&self, axis: Axis) -> usize {
        self.geometry.dims[axis.dim()]
    }

    /// Width and height (u, v extents) of slices along `axis`.
    pub fn slice_shape(&self, axis: Axis) -> (usize, usize) {
        let (a, b) = axis.in_plane();
        (self.geometry.dims[a], self.geometry.dims[b])
    }

    fn check_slice(&self, axis: Axis, index: usize) -> Result<(), CoreError> {
        let len = self.slice_count(axis);
        if index >= len {
            return Err(CoreError::SliceOutOfRange { axis, index, len });
        }
        Ok(())
    }

    /// A borrowed view of slice `(axis, index)`: no copy, `O(1)` to make;
    /// pixel `(u, v)` is read straight from the volume's storage.
    pub fn view(&self, axis: Axis, index: usize) -> Result<SliceView<'_, T>, CoreError> {
        self.check_slice(axis, index)?;
        let [nx, ny, _] = self.geometry.dims;
        let stride = [1, nx, nx * ny];
        let (a, b) = axis.in_plane();
        let (width, height) = self.slice_shape(axis);
        Ok(SliceView {
            data: &self.data,
            base: stride[axis.dim()] * index,
            stride_u: stride[a],
            stride_v: stride[b],
            width,
            height,
        })
    }

    /// Copy slice `(axis, index)` into a row-major `width * height` buffer
    /// (`buf[u + width * v]`).
    pub fn slice(&self, axis: Axis, index: usize) -> Result<Vec<T>, CoreError> {
        self.check_slice(axis, index)?;
        let [nx, ny, _] = self.geometry.dims;
        let (w, h) = self.slice_shape(axis);
        let mut out = Vec::with_capacity(w * h);
        match axis {
            Axis::Z => out.extend_from_slice(&self.data[nx * ny * index..nx * ny * (index + 1)]),
            Axis::Y => {
                for k in 0..h {
                    let start = self.geometry.index(0, index, k);
                    out.extend_from_slice(&self.data[start..start + nx]);
                }
            }
            Axis::X => {
                for k in 0..h {
                    for j in 0..w {
                        out.push(self.data[self.geometry.index(index, j, k)]);
                    }
                }
            }
        }
        Ok(out)
    }

    /// Write a row-major `width * height` buffer into slice `(axis, index)`.
    pub fn set_slice(&mut self, axis: Axis, index: usize, buf: &[T]) -> Result<(), CoreError> {
        self.check_slice(axis, index)?;
        let (w, h) = self.slice_shape(axis);
        if buf.len() != w * h {
            return Err(CoreError::Invalid(format!(
                "slice buffer has {} pixels, slice {axis}={index} has {}",
                buf.len(),
                w * h
            )));
        }
        for v in 0..h {
            for u in 0..w {
                let [i, j, k] = axis.voxel(index, u, v);
                let idx = self.geometry.index(i, j, k);
                self.data[idx] = buf[u + w * v];
            }
        }
        Ok(())
    }

    /// Map every voxel (in parallel) into a new volume of the same geometry.
    pub fn map<U: Voxel>(&self, f: impl Fn(T) -> U + Sync) -> Volume<U> {
        Volume {
            geometry: self.geometry.clone(),
            data: self.data.par_iter().map(|&v| f(v)).collect(),
        }
    }

    /// Minimum and maximum value (by `to_f64`).
    pub fn min_max(&self) -> (f64, f64) {
        self.data
            .par_iter()
            .fold(
                || (f64::INFINITY, f64::NEG_INFINITY),
                |(lo, hi), &v| {
                    let x = v.to_f64();
                    (lo.min(x), hi.max(x))
                },
            )
            .reduce(
                || (f64::INFINITY, f64::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            )
    }
}

impl LabelVolume {
    /// The mask of voxels equal to `label`.
    pub fn mask_of(&self, label: u16) -> Mask {
        self.map(|v| v == label)
    }

    /// Labels present (non-zero), sorted, with their voxel counts.
    pub fn label_counts(&self) -> Vec<(u16, u64)> {
        let counts = self
            .data
            .par_chunks(1 << 16)
            .fold(
                || vec![0u64; 65536],
                |mut acc, chunk| {
                    for &v in chunk {
                        acc[v as usize] += 1;
                    }
                    acc
                },
            )
            .reduce(
                || vec![0u64; 65536],
                |mut a, b| {
                    for (x, y) in a.iter_mut().zip(b) {
                        *x += y;
                    }
                    a
                },
            );
        counts
            .into_iter()
            .enumerate()
            .skip(1)
            .filter(|&(_, c)| c > 0)
            .map(|(l, c)| (l as u16, c))
            .collect()
    }
}

/// A volume of any voxel type that files bring.
#[derive(Debug, Clone, PartialEq)]
pub enum AnyVolume {
    /// Unsigned 8-bit.
    U8(Volume<u8>),
    /// Unsigned 16-bit.
    U16(Volume<u16>),
    /// Signed 16-bit (CT).
    I16(Volume<i16>),
    /// 32-bit float.
    F32(Volume<f32>),
}

impl AnyVolume {
    /// The geometry.
    pub fn geometry(&self) -> &Geometry {
        match self {
            AnyVolume::U8(v) => v.geometry(),
            AnyVolume::U16(v) => v.geometry(),
            AnyVolume::I16(v) => v.geometry(),
            AnyVolume::F32(v) => v.geometry(),
        }
    }

    /// Name of the voxel type ("u8", "u16", "i16", "f32").
    pub fn type_name(&self) -> &'static str {
        match self {
            AnyVolume::U8(_) => "u8",
            AnyVolume::U16(_) => "u16",
            AnyVolume::I16(_) => "i16",
            AnyVolume::F32(_) => "f32",
        }
    }

    /// Minimum and maximum value.
    pub fn min_max(&self) -> (f64, f64) {
        match self {
            AnyVolume::U8(v) => v.min_max(),
            AnyVolume::U16(v) => v.min_max(),
            AnyVolume::I16(v) => v.min_max(),
            AnyVolume::F32(v) => v.min_max(),
        }
    }

    /// Interpret as a label volume. Errs for negative, fractional or
    /// non-finite values (a label must be an integer 0..=65535).
    pub fn to_labels(&self) -> Result<LabelVolume, CoreError> {
        match self {
            AnyVolume::U8(v) => Ok(v.map(u16::from)),
            AnyVolume::U16(v) => Ok(v.clone()),
            AnyVolume::I16(v) => {
                if v.data().par_iter().any(|&x| x < 0) {
                    return Err(CoreError::Invalid(
                        "label volume has negative values".into(),
                    ));
                }
                Ok(v.map(|x| x as u16))
            }
            AnyVolume::F32(v) => {
                if v.data()
                    .par_iter()
                    .any(|&x| !(x.is_finite() && (0.0..=65535.0).contains(&x) && x.fract() == 0.0))
                {
                    return Err(CoreError::Invalid(
                        "label volume has values that are not integers in 0..=65535".into(),
                    ));
                }
                Ok(v.map(|x| x as u16))
            }
        }
    }
}

/// A borrowed 2D view of one slice of a [`Volume`] (see [`Volume::view`]).
#[derive(Debug, Clone, Copy)]
pub struct SliceView<'a, T> {
    data: &'a [T],
    base: usize,
    stride_u: usize,
    stride_v: usize,
    width: usize,
    height: usize,
}

impl<T: Copy> SliceView<'_, T> {
    /// Extent along u.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Extent along v.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Pixel `(u, v)`; panics when out of the slice, like slice indexing.
    #[inline]
    pub fn get(&self, u: usize, v: usize) -> T {
        assert!(
            u < self.width && v < self.height,
            "pixel ({u}, {v}) outside the slice"
        );
        self.data[self.base + u * self.stride_u + v * self.stride_v]
    }

    /// Pixels in row-major order (`u` fastest).
    pub fn iter(&self) -> impl Iterator<Item = T> + '_ {
        (0..self.height).flat_map(move |v| (0..self.width).map(move |u| self.get(u, v)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LengthUnit;

    fn vol() -> Volume<u16> {
        let g = Geometry::new([3, 4, 5], [1.0, 2.0, 3.0], LengthUnit::Millimetre).unwrap();
        let data: Vec<u16> = (0..60).collect();
        Volume::from_vec(g, data).unwrap()
    }

    #[test]
    fn index_is_x_fastest() {
        let v = vol();
        assert_eq!(v.get(1, 0, 0), 1);
        assert_eq!(v.get(0, 1, 0), 3);
        assert_eq!(v.get(0, 0, 1), 12);
        assert_eq!(v.geometry().ijk(12 + 3 + 2), [2, 1, 1]);
    }

    #[test]
    fn slices_round_trip_on_every_axis() {
        let v = vol();
        for axis in Axis::ALL {
            for idx in 0..v.slice_count(axis) {
                let s = v.slice(axis, idx).unwrap();
                let view = v.view(axis, idx).unwrap();
                assert_eq!(view.iter().collect::<Vec<_>>(), s);
                let (w, h) = v.slice_shape(axis);
                assert_eq!((view.width(), view.height()), (w, h));
                assert_eq!(s.len(), w * h);
                for vv in 0..h {
                    for u in 0..w {
                        let [i, j, k] = axis.voxel(idx, u, vv);
                        assert_eq!(s[u + w * vv], v.get(i, j, k));
                    }
                }
                let mut z = Volume::<u16>::zeros(v.geometry().clone());
                z.set_slice(axis, idx, &s).unwrap();
                assert_eq!(z.slice(axis, idx).unwrap(), s);
            }
        }
        assert!(v.slice(Axis::Z, 5).is_err());
    }

    #[test]
    fn wrong_length_is_an_error() {
        let g = Geometry::new([2, 2, 2], [1.0; 3], LengthUnit::Micrometre).unwrap();
        assert!(Volume::<u8>::from_vec(g, vec![0; 7]).is_err());
    }

    #[test]
    fn label_counts_and_masks() {
        let g = Geometry::new([2, 2, 1], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let v = Volume::from_vec(g, vec![0u16, 2, 2, 7]).unwrap();
        assert_eq!(v.label_counts(), vec![(2, 2), (7, 1)]);
        assert_eq!(v.mask_of(2).data(), &[false, true, true, false]);
    }
}
