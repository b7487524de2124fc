//! Physical geometry of a volume: dims, spacing, unit, origin and direction.
use crate::CoreError;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The length unit of spacing and origin. Cell CT is in µm, clinical data in mm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum LengthUnit {
    /// Micrometres (µm).
    Micrometre,
    /// Millimetres (mm); the default of NIfTI, NRRD and MetaImage files without a unit.
    #[default]
    Millimetre,
    /// Metres.
    Metre,
    /// Unknown unit (written as "unknown"; numbers are reported as they are).
    Unknown,
}

impl LengthUnit {
    /// Short symbol ("µm", "mm", "m", "unit").
    pub fn symbol(self) -> &'static str {
        match self {
            LengthUnit::Micrometre => "µm",
            LengthUnit::Millimetre => "mm",
            LengthUnit::Metre => "m",
            LengthUnit::Unknown => "unit",
        }
    }

    /// ASCII name for file headers ("um", "mm", "m", "unknown"): every tool
    /// reads it, and [`LengthUnit::parse`] reads it back.
    pub fn ascii(self) -> &'static str {
        match self {
            LengthUnit::Micrometre => "um",
            LengthUnit::Millimetre => "mm",
            LengthUnit::Metre => "m",
            LengthUnit::Unknown => "unknown",
        }
    }

    /// Parse a unit name as written by common tools ("um", "µm", "micron", "mm", ...).
    pub fn parse(s: &str) -> Option<LengthUnit> {
        match s.trim().to_ascii_lowercase().as_str() {
            "um" | "µm" | "μm" | "micron" | "microns" | "micrometer" | "micrometre"
            | "\\u00b5m" => Some(LengthUnit::Micrometre),
            "mm" | "millimeter" | "millimetre" => Some(LengthUnit::Millimetre),
            "m" | "meter" | "metre" => Some(LengthUnit::Metre),
            "" | "unknown" | "pixel" | "unit" => Some(LengthUnit::Unknown),
            _ => None,
        }
    }
}

impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.symbol())
    }
}

/// Where the voxels of a volume are: dims, spacing `(sx, sy, sz)` > 0, unit,
/// origin (physical position of voxel (0,0,0)'s centre) and direction cosines
/// (`direction[r][c]`: component r of the unit vector of axis c, as in ITK).
///
/// Origin and direction are kept from a file and written back unchanged;
/// algorithms use only dims and spacing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// Number of voxels along x, y, z.
    pub dims: [usize; 3],
    /// Voxel size along x, y, z, in `unit`.
    pub spacing: [f64; 3],
    /// Unit of spacing and origin.
    pub unit: LengthUnit,
    /// Physical position of the centre of voxel (0, 0, 0).
    pub origin: [f64; 3],
    /// Direction cosines, ITK convention (columns are the axes).
    pub direction: [[f64; 3]; 3],
}

/// The identity direction matrix.
pub const IDENTITY_DIRECTION: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl Geometry {
    /// A geometry with the given dims and spacing, origin 0 and identity direction.
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        unit: LengthUnit,
    ) -> Result<Geometry, CoreError> {
        let g = Geometry {
            dims,
            spacing,
            unit,
            origin: [0.0; 3],
            direction: IDENTITY_DIRECTION,
        };
        g.validate()?;
        Ok(g)
    }

    /// Check dims > 0 and finite spacing > 0.
    pub fn validate(&self) -> Result<(), CoreError> {
        if self.dims.contains(&0) {
            return Err(CoreError::InvalidGeometry(format!(
                "dims {:?} contain 0",
                self.dims
            )));
        }
        if self
            .dims
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .is_none()
        {
            return Err(CoreError::InvalidGeometry(format!(
                "dims {:?} overflow",
                self.dims
            )));
        }
        if self.spacing.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(CoreError::InvalidGeometry(format!(
                "spacing {:?} must be finite and > 0",
                self.spacing
            )));
        }
        if self.origin.iter().any(|o| !o.is_finite()) {
            return Err(CoreError::InvalidGeometry(format!(
                "origin {:?} is not finite",
                self.origin
            )));
        }
        Ok(())
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// True if the volume has no voxels (never true for a validated geometry).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Linear index of voxel (i, j, k): `i + nx * (j + ny * k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Voxel (i, j, k) of a linear index.
    #[inline]
    pub fn ijk(&self, index: usize) -> [usize; 3] {
        let nx = self.dims[0];
        let ny = self.dims[1];
        [index % nx, (index / nx) % ny, index / (nx * ny)]
    }

    /// Physical volume of one voxel, `sx * sy * sz`, in `unit`³.
    pub fn voxel_volume(&self) -> f64 {
        self.spacing[0] * self.spacing[1] * self.spacing[2]
    }

    /// True when dims agree and spacing, origin and direction agree within a
    /// relative tolerance of 1e-6 (files store them as f32 or text).
    pub fn same_grid(&self, other: &Geometry) -> bool {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1.0);
        self.dims == other.dims
            && (0..3).all(|a| close(self.spacing[a], other.spacing[a]))
            && (0..3).all(|a| close(self.origin[a], other.origin[a]))
            && (0..3).all(|r| (0..3).all(|c| close(self.direction[r][c], other.direction[r][c])))
    }

    /// Err with a readable message unless `same_grid`.
    pub fn ensure_same_grid(&self, other: &Geometry) -> Result<(), CoreError> {
        if self.dims != other.dims {
            return Err(CoreError::GeometryMismatch(format!(
                "dims {:?} vs {:?}",
                self.dims, other.dims
            )));
        }
        if !self.same_grid(other) {
            return Err(CoreError::GeometryMismatch(format!(
                "spacing {:?} vs {:?}, origin {:?} vs {:?}",
                self.spacing, other.spacing, self.origin, other.origin
            )));
        }
        Ok(())
    }
}
