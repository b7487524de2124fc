//! Volume and mesh file formats: NIfTI, NRRD, MetaImage, TIFF stacks, slice
//! folders and DICOM series (read only).
//!
//! [`read_volume`] and [`write_volume`] pick the format from the path (see
//! [`Format::of_path`]); geometry (dims, spacing, unit, origin, direction) is
//! kept, intensities are never rescaled, and every write is atomic (a
//! temporary file in the same directory renamed over the target). Errors are
//! [`IoError`], whose message is one line naming the file. The supported
//! formats and their conventions are documented in `docs/formats.md`.
#![deny(missing_docs)]

pub mod dicom;
pub mod error;
pub mod mesh;
pub mod raw;

mod folder;
mod header;
mod meta;
mod nii;
mod nrrd;
mod planes;
mod tiff_stack;

pub use error::IoError;

use interslice_core::{AnyVolume, LabelVolume, Volume};
use std::fmt;
use std::path::Path;

/// A volume file format, chosen by the file name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// NIfTI-1, `.nii`.
    Nifti,
    /// NIfTI-1 gzip-compressed, `.nii.gz`.
    NiftiGz,
    /// NRRD with attached data, `.nrrd` (also 3D Slicer `.seg.nrrd`).
    Nrrd,
    /// NRRD header with a detached data file, `.nhdr` (read only).
    Nhdr,
    /// MetaImage with attached data, `.mha`.
    Mha,
    /// MetaImage header with a `.raw` data file, `.mhd`.
    Mhd,
    /// Multi-page TIFF with ImageJ metadata, `.tif` or `.tiff`.
    Tiff,
    /// A folder of 2D PNG or TIFF slices (written as `slice_0000.png`, ...).
    SliceFolder,
    /// A folder of DICOM files, or one DICOM file (read only; see [`dicom`]).
    Dicom,
}

impl Format {
    /// The format of a path: by extension (case-insensitive); [`Format::Dicom`]
    /// for a directory holding DICOM files, a `.dcm` file or an existing file
    /// that starts with the DICOM preamble; [`Format::SliceFolder`] for
    /// another existing directory, a path ending in `/`, or a path that does
    /// not exist and whose name has no extension.
    pub fn of_path(path: &Path) -> Result<Format, IoError> {
        let text = path.to_string_lossy();
        if path.is_dir() && dicom::is_dicom_folder(path) {
            return Ok(Format::Dicom);
        }
        if path.is_dir() || text.ends_with('/') || text.ends_with(std::path::MAIN_SEPARATOR) {
            return Ok(Format::SliceFolder);
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if !name.is_empty() && !name.contains('.') && !path.exists() {
            return Ok(Format::SliceFolder);
        }
        if name.ends_with(".nii.gz") {
            Ok(Format::NiftiGz)
        } else if name.ends_with(".nii") {
            Ok(Format::Nifti)
        } else if name.ends_with(".nrrd") {
            Ok(Format::Nrrd)
        } else if name.ends_with(".nhdr") {
            Ok(Format::Nhdr)
        } else if name.ends_with(".mha") {
            Ok(Format::Mha)
        } else if name.ends_with(".mhd") {
            Ok(Format::Mhd)
        } else if name.ends_with(".tif") || name.ends_with(".tiff") {
            Ok(Format::Tiff)
        } else if name.ends_with(".dcm") || (path.is_file() && dicom::is_dicom_file(path)) {
            Ok(Format::Dicom)
        } else {
            Err(IoError::unsupported(
                path,
                "unknown volume format (expected .nii, .nii.gz, .nrrd, .mha, .mhd, .tif/.tiff, a folder of slices or DICOM files)",
            ))
        }
    }

    /// Short name of the format ("NIfTI-1", ...).
    pub fn name(self) -> &'static str {
        match self {
            Format::Nifti => "NIfTI-1",
            Format::NiftiGz => "NIfTI-1 (gzip)",
            Format::Nrrd => "NRRD",
            Format::Nhdr => "NRRD (detached)",
            Format::Mha => "MetaImage",
            Format::Mhd => "MetaImage (detached)",
            Format::Tiff => "TIFF stack",
            Format::SliceFolder => "slice folder",
            Format::Dicom => "DICOM",
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Read a volume; the format is chosen by [`Format::of_path`].
pub fn read_volume(path: &Path) -> Result<AnyVolume, IoError> {
    match Format::of_path(path)? {
        Format::Nifti | Format::NiftiGz => nii::read(path),
        Format::Nrrd | Format::Nhdr => nrrd::read(path),
        Format::Mha | Format::Mhd => meta::read(path),
        Format::Tiff => tiff_stack::read(path),
        Format::SliceFolder => folder::read(path),
        Format::Dicom => dicom::read(path, None),
    }
}

/// Read a volume like [`read_volume`]; `series` (a SeriesInstanceUID)
/// chooses the series of a DICOM folder that holds several, and is an error
/// for any other format.
pub fn read_volume_series(path: &Path, series: Option<&str>) -> Result<AnyVolume, IoError> {
    let Some(uid) = series else {
        return read_volume(path);
    };
    match Format::of_path(path)? {
        Format::Dicom => dicom::read(path, Some(uid)),
        other => Err(IoError::unsupported(
            path,
            format!("a series UID chooses a DICOM series, but this is a {other}"),
        )),
    }
}

/// Write a volume atomically; the format is chosen by [`Format::of_path`].
/// Errs (and writes nothing) when the format cannot hold the voxel type
/// without loss.
pub fn write_volume(path: &Path, v: &AnyVolume) -> Result<(), IoError> {
    match Format::of_path(path)? {
        Format::Nifti => nii::write(path, v, false),
        Format::NiftiGz => nii::write(path, v, true),
        Format::Nrrd => nrrd::write(path, v),
        Format::Nhdr => Err(IoError::unsupported(
            path,
            "writing detached NRRD (.nhdr) is not supported; write .nrrd",
        )),
        Format::Mha => meta::write(path, v, true),
        Format::Mhd => meta::write(path, v, false),
        Format::Tiff => tiff_stack::write(path, v),
        Format::SliceFolder => folder::write(path, v),
        Format::Dicom => Err(IoError::unsupported(
            path,
            "writing DICOM is not supported (write .nii.gz, .nrrd, .mha or .tif)",
        )),
    }
}

/// Read a label volume: [`read_volume`] then [`AnyVolume::to_labels`]
/// (integer values 0..=65535; anything else is an error).
pub fn read_labels(path: &Path) -> Result<LabelVolume, IoError> {
    read_labels_series(path, None)
}

/// Read a label volume, choosing a DICOM series as [`read_volume_series`] does.
pub fn read_labels_series(path: &Path, series: Option<&str>) -> Result<LabelVolume, IoError> {
    let v = read_volume_series(path, series)?;
    v.to_labels()
        .map_err(|e| IoError::invalid(path, format!("not a label volume: {e}")))
}

/// Write a label volume, stored as u8 when the largest label is at most 255
/// (what most viewers expect of a segmentation), else as u16.
pub fn write_labels(path: &Path, v: &LabelVolume) -> Result<(), IoError> {
    let max = v.data().iter().copied().max().unwrap_or(0);
    if max <= u16::from(u8::MAX) {
        let g = v.geometry().clone();
        let data: Vec<u8> = v.data().iter().map(|&x| x as u8).collect();
        let v8 = Volume::from_vec(g, data).map_err(|e| IoError::invalid(path, e.to_string()))?;
        write_volume(path, &AnyVolume::U8(v8))
    } else {
        write_volume(path, &AnyVolume::U16(v.clone()))
    }
}
