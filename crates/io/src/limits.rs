//! What one read may allocate: [`ReadLimits`] (checked on the header, before
//! any voxel data is read or decompressed) and [`VolumeHeader`], what a
//! header says about the volume.
//!
//! Every allocation whose size comes from a file goes through these checks
//! or through `try_vec`, so a lying header gives an error, never an
//! allocation failure (which aborts the process).
use crate::raw::RawType;
use crate::{Format, IoError};
use interslice_core::Geometry;
use std::path::Path;

/// Limits on one read, checked against the header before any voxel data is
/// read or decompressed.
///
/// The [`Default`] is generous but finite (2^31 voxels, 8 GiB of voxel
/// data): what a workstation can hold. A server reading an upload for a
/// known grid uses [`ReadLimits::for_grid`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReadLimits {
    /// Most voxels the volume may have.
    pub max_voxels: u64,
    /// Most bytes of voxel data, as stored in the file but decompressed, one
    /// read may decode: also the bound on what a gzip or zlib stream may
    /// inflate to (bytes skipped inside a compressed stream count too).
    pub max_bytes: u64,
    /// When set, the volume must have exactly these dims; a header that says
    /// otherwise is refused before its data is read.
    pub expected_dims: Option<[usize; 3]>,
}

/// Default [`ReadLimits::max_voxels`]: 2^31 (a 1290³ volume).
pub const DEFAULT_MAX_VOXELS: u64 = 1 << 31;
/// Default [`ReadLimits::max_bytes`]: 8 GiB.
pub const DEFAULT_MAX_BYTES: u64 = 8 << 30;

impl Default for ReadLimits {
    fn default() -> ReadLimits {
        ReadLimits {
            max_voxels: DEFAULT_MAX_VOXELS,
            max_bytes: DEFAULT_MAX_BYTES,
            expected_dims: None,
        }
    }
}

impl ReadLimits {
    /// Limits for a volume that must lie on a grid of `dims`: exactly those
    /// dims, and at most 8 bytes a voxel of data (the widest type a file may
    /// store).
    pub fn for_grid(dims: [usize; 3]) -> ReadLimits {
        let n = dims.iter().map(|&d| d as u64).product::<u64>();
        ReadLimits {
            max_voxels: n,
            max_bytes: n.saturating_mul(8),
            expected_dims: Some(dims),
        }
    }

    /// Check a header's dims and its voxel data size (`data_bytes`, the bytes
    /// the stored array needs) against the limits.
    pub(crate) fn check(
        &self,
        path: &Path,
        dims: [usize; 3],
        data_bytes: u64,
    ) -> Result<(), IoError> {
        if dims.contains(&0) {
            return Err(IoError::invalid(path, format!("dims {dims:?} contain 0")));
        }
        if let Some(want) = self.expected_dims
            && want != dims
        {
            return Err(IoError::invalid(
                path,
                format!("dims {dims:?} do not match the expected {want:?}"),
            ));
        }
        let voxels = dims
            .iter()
            .try_fold(1u64, |a, &d| a.checked_mul(d as u64))
            .unwrap_or(u64::MAX);
        if voxels > self.max_voxels {
            return Err(IoError::unsupported(
                path,
                format!(
                    "dims {dims:?} are too large ({voxels} voxels, the limit is {})",
                    self.max_voxels
                ),
            ));
        }
        if data_bytes > self.max_bytes {
            return Err(IoError::unsupported(
                path,
                format!(
                    "the voxel data is too large ({data_bytes} bytes, the limit is {})",
                    self.max_bytes
                ),
            ));
        }
        Ok(())
    }

    /// Check dims of a plain array of `t` and return its byte count.
    pub(crate) fn array_bytes(
        &self,
        path: &Path,
        dims: [usize; 3],
        t: RawType,
    ) -> Result<usize, IoError> {
        let bytes = dims
            .iter()
            .try_fold(t.size() as u64, |a, &d| a.checked_mul(d as u64))
            .unwrap_or(u64::MAX);
        self.check(path, dims, bytes)?;
        usize::try_from(bytes)
            .map_err(|_| IoError::unsupported(path, "the voxel data is too large"))
    }
}

/// What a volume file's header says, read without its voxel data.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeHeader {
    /// The file's format.
    pub format: Format,
    /// Dims, spacing, unit, origin and direction.
    pub geometry: Geometry,
    /// The element type stored in the file (the in-memory type may be
    /// narrower: see `docs/formats.md`).
    pub stored_type: RawType,
    /// Bytes of voxel data the file holds once decompressed.
    pub data_bytes: u64,
}

/// Whether a reader stops after the header or reads the voxels too.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Want {
    Header,
    Volume,
}

/// What a reader returns: the header only, or the volume.
pub(crate) enum Loaded {
    Header(VolumeHeader),
    Volume(interslice_core::AnyVolume),
}

/// A vector of `n` elements allocated fallibly: an error naming the file
/// instead of the abort an allocation failure causes.
pub(crate) fn try_vec<T>(path: &Path, n: usize) -> Result<Vec<T>, IoError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        IoError::unsupported(
            path,
            format!(
                "not enough memory for {} bytes of voxel data",
                n.saturating_mul(std::mem::size_of::<T>())
            ),
        )
    })?;
    Ok(v)
}
