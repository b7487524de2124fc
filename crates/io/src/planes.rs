//! Stacks of 2D gray images (TIFF pages, PNG/TIFF slice files) assembled
//! into a volume, with checks that every plane has the same size and type.
use crate::IoError;
use interslice_core::geometry::IDENTITY_DIRECTION;
use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};
use std::path::Path;

/// The pixels of one 2D image, row-major.
pub enum Plane {
    /// 8-bit.
    U8(Vec<u8>),
    /// 16-bit.
    U16(Vec<u16>),
    /// signed 16-bit.
    I16(Vec<i16>),
    /// 32-bit float.
    F32(Vec<f32>),
}

impl Plane {
    /// Number of pixels.
    pub fn len(&self) -> usize {
        match self {
            Plane::U8(v) => v.len(),
            Plane::U16(v) => v.len(),
            Plane::I16(v) => v.len(),
            Plane::F32(v) => v.len(),
        }
    }

    fn type_name(&self) -> &'static str {
        match self {
            Plane::U8(_) => "8-bit",
            Plane::U16(_) => "16-bit",
            Plane::I16(_) => "signed 16-bit",
            Plane::F32(_) => "32-bit float",
        }
    }
}

/// Accumulates planes of one size and type into x-fastest volume data.
#[derive(Default)]
pub struct Stack {
    size: Option<(usize, usize)>,
    data: Option<Plane>,
    count: usize,
}

impl Stack {
    /// Number of planes pushed.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Add a plane of `width` x `height` read from `path` (named in errors).
    pub fn push(
        &mut self,
        path: &Path,
        width: usize,
        height: usize,
        plane: Plane,
    ) -> Result<(), IoError> {
        match self.size {
            Some(s) if s != (width, height) => {
                return Err(IoError::invalid(
                    path,
                    format!(
                        "slice {} is {width} x {height} but the first is {} x {} (all slices must have one size)",
                        self.count, s.0, s.1
                    ),
                ));
            }
            _ => self.size = Some((width, height)),
        }
        let mismatch = |a: &Plane, b: &Plane| {
            IoError::invalid(
                path,
                format!(
                    "slice {} is {} but the first is {} (all slices must have one type)",
                    self.count,
                    b.type_name(),
                    a.type_name()
                ),
            )
        };
        // Growing the stack may fail for lack of memory: an error, not an abort.
        let oom = |_| IoError::unsupported(path, "not enough memory for the slices");
        match (&mut self.data, plane) {
            (None, p) => self.data = Some(p),
            (Some(Plane::U8(d)), Plane::U8(p)) => {
                d.try_reserve(p.len()).map_err(oom)?;
                d.extend_from_slice(&p)
            }
            (Some(Plane::U16(d)), Plane::U16(p)) => {
                d.try_reserve(p.len()).map_err(oom)?;
                d.extend_from_slice(&p)
            }
            (Some(Plane::I16(d)), Plane::I16(p)) => {
                d.try_reserve(p.len()).map_err(oom)?;
                d.extend_from_slice(&p)
            }
            (Some(Plane::F32(d)), Plane::F32(p)) => {
                d.try_reserve(p.len()).map_err(oom)?;
                d.extend_from_slice(&p)
            }
            (Some(a), b) => return Err(mismatch(a, &b)),
        }
        self.count += 1;
        Ok(())
    }

    /// The volume, with the given spacing, unit, origin and direction.
    pub fn finish(self, path: &Path, mut geometry: Geometry) -> Result<AnyVolume, IoError> {
        let ((w, h), data) = match (self.size, self.data) {
            (Some(s), Some(d)) => (s, d),
            _ => return Err(IoError::invalid(path, "no images found")),
        };
        geometry.dims = [w, h, self.count];
        let bad = |e: interslice_core::CoreError| IoError::invalid(path, e.to_string());
        Ok(match data {
            Plane::U8(d) => AnyVolume::U8(Volume::from_vec(geometry, d).map_err(bad)?),
            Plane::U16(d) => AnyVolume::U16(Volume::from_vec(geometry, d).map_err(bad)?),
            Plane::I16(d) => AnyVolume::I16(Volume::from_vec(geometry, d).map_err(bad)?),
            Plane::F32(d) => AnyVolume::F32(Volume::from_vec(geometry, d).map_err(bad)?),
        })
    }
}

/// `N` comma-separated numbers (as in `spacing=1,1,2`); `None` for any
/// other count or a non-number.
pub(crate) fn parse_list<const N: usize>(s: &str) -> Option<[f64; N]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse().ok())
        .collect::<Option<_>>()?;
    v.try_into().ok()
}

/// The geometry of a plane file before its metadata is read: dims 1, unit
/// spacing of unknown unit, origin 0, identity direction.
pub(crate) fn unknown_geometry() -> Geometry {
    Geometry {
        dims: [1; 3],
        spacing: [1.0; 3],
        unit: LengthUnit::Unknown,
        origin: [0.0; 3],
        direction: IDENTITY_DIRECTION,
    }
}

/// A length unit name as ImageJ and others write it, with the factor that
/// converts a length in that unit into the returned [`LengthUnit`]
/// (nm → µm × 0.001, cm → mm × 10, inch → mm × 25.4).
pub fn unit_with_scale(s: &str) -> (LengthUnit, f64) {
    let t = s.trim().trim_matches('"').to_ascii_lowercase();
    match t.as_str() {
        "nm" | "nanometer" | "nanometre" | "nanometers" => (LengthUnit::Micrometre, 1e-3),
        "cm" | "centimeter" | "centimetre" => (LengthUnit::Millimetre, 10.0),
        "inch" | "in" | "inches" => (LengthUnit::Millimetre, 25.4),
        _ => (LengthUnit::parse(&t).unwrap_or(LengthUnit::Unknown), 1.0),
    }
}

/// A positive spacing as a TIFF rational `numerator / denominator` of
/// pixels per unit, exact for decimal spacings with up to 9 digits after
/// the point (so 0.35 reads back as exactly 0.35).
pub fn resolution_rational(spacing: f64) -> (u32, u32) {
    for k in (0..=9).rev() {
        let num = 10f64.powi(k);
        let den = (spacing * num).round();
        if den >= 1.0 && den <= f64::from(u32::MAX) {
            return (num as u32, den as u32);
        }
    }
    // Spacing above u32::MAX units: clamp (never reached for real data).
    (1, u32::MAX)
}
