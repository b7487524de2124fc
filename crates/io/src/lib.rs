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
pub mod limits;
pub mod mesh;
pub mod raw;

mod folder;
mod header;
mod meta;
mod nii;
mod nrrd;
mod planes;
pub mod segmentation;
mod source;
mod tiff_stack;

pub use error::IoError;
pub use limits::{ReadLimits, VolumeHeader};

use limits::{Loaded, Want};
use source::Source;

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
        Format::of_name(path)
    }

    /// The format a file name's extension gives, never a folder and without
    /// looking at the file system.
    pub fn of_name(path: &Path) -> Result<Format, IoError> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
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

/// Read a volume with the default [`ReadLimits`]; the format is chosen by
/// [`Format::of_path`].
pub fn read_volume(path: &Path) -> Result<AnyVolume, IoError> {
    read_volume_with(path, &ReadLimits::default())
}

/// Read a volume within `limits`: the header is checked against them before
/// any voxel data is read or decompressed.
pub fn read_volume_with(path: &Path, limits: &ReadLimits) -> Result<AnyVolume, IoError> {
    volume(path, load(Source::file(path), limits, Want::Volume)?)
}

/// Read only the header of a volume file (dims, type, spacing, ...): cheap,
/// no voxel data is read. Checked against the default [`ReadLimits`].
pub fn read_header(path: &Path) -> Result<VolumeHeader, IoError> {
    header(
        path,
        load(Source::file(path), &ReadLimits::default(), Want::Header)?,
    )
}

/// Read a volume from bytes in memory (an upload), the format chosen by
/// `name` like [`Format::of_path`] does. Only self-contained files are read:
/// a detached header (`.nhdr`, `.mhd`), a header that names a data file and
/// a slice folder are refused. Errors name `name` only.
pub fn read_bytes(name: &str, bytes: &[u8], limits: &ReadLimits) -> Result<AnyVolume, IoError> {
    let path = Path::new(name);
    volume(path, load(memory(path, bytes)?, limits, Want::Volume)?)
}

/// The header of a volume in memory (see [`read_bytes`]).
pub fn read_header_bytes(name: &str, bytes: &[u8]) -> Result<VolumeHeader, IoError> {
    let path = Path::new(name);
    header(
        path,
        load(memory(path, bytes)?, &ReadLimits::default(), Want::Header)?,
    )
}

/// A label volume from bytes in memory: [`read_bytes`] then
/// [`AnyVolume::to_labels`].
pub fn read_labels_bytes(
    name: &str,
    bytes: &[u8],
    limits: &ReadLimits,
) -> Result<LabelVolume, IoError> {
    read_bytes(name, bytes, limits)?
        .to_labels()
        .map_err(|e| IoError::invalid(Path::new(name), format!("not a label volume: {e}")))
}

/// Bytes named `name` as a source, when their format is self-contained.
fn memory<'a>(path: &'a Path, bytes: &'a [u8]) -> Result<Source<'a>, IoError> {
    // By name only: a name that happens to exist on disk must not matter.
    let lower = path.to_string_lossy().to_ascii_lowercase();
    let detached = [".nhdr", ".mhd"].iter().any(|e| lower.ends_with(e));
    if detached || !lower.contains('.') || lower.ends_with('/') {
        return Err(IoError::unsupported(
            path,
            "only a self-contained volume file can be read here (.nii, .nii.gz, .nrrd, .mha, .tif); a detached header or a folder of slices cannot",
        ));
    }
    Ok(Source::memory(path, bytes))
}

fn load(src: Source<'_>, limits: &ReadLimits, want: Want) -> Result<Loaded, IoError> {
    let path = src.name;
    let format = if src.bytes.is_some() {
        Format::of_name(path)?
    } else {
        Format::of_path(path)?
    };
    match format {
        Format::Nifti | Format::NiftiGz => nii::read(src, limits, want),
        Format::Nrrd | Format::Nhdr => nrrd::read(src, limits, want),
        Format::Mha | Format::Mhd => meta::read(src, limits, want),
        Format::Tiff => tiff_stack::read(src, limits, want),
        Format::SliceFolder => folder::read(path, limits, want),
        Format::Dicom => dicom_load(path, None, limits, want),
    }
}

/// A DICOM series through the limits. The DICOM reader bounds its own
/// allocations from each file's header (rows, columns, frames, file count);
/// the limits are checked on the geometry it assembles, and a header read
/// assembles the volume (a series has no single header to stop after).
fn dicom_load(
    path: &Path,
    series: Option<&str>,
    limits: &ReadLimits,
    want: Want,
) -> Result<Loaded, IoError> {
    let v = dicom::read(path, series)?;
    let g = v.geometry().clone();
    let stored_type = raw::RawType::of(&v);
    let data_bytes = (g.len() as u64).saturating_mul(stored_type.size() as u64);
    limits.check(path, g.dims, data_bytes)?;
    Ok(match want {
        Want::Volume => Loaded::Volume(v),
        Want::Header => Loaded::Header(VolumeHeader {
            format: Format::Dicom,
            geometry: g,
            stored_type,
            data_bytes,
        }),
    })
}

fn volume(path: &Path, l: Loaded) -> Result<AnyVolume, IoError> {
    match l {
        Loaded::Volume(v) => Ok(v),
        Loaded::Header(_) => Err(IoError::invalid(path, "no voxel data was read")),
    }
}

fn header(path: &Path, l: Loaded) -> Result<VolumeHeader, IoError> {
    match l {
        Loaded::Header(h) => Ok(h),
        Loaded::Volume(_) => Err(IoError::invalid(path, "no header was read")),
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
        Format::Dicom => volume(
            path,
            dicom_load(path, Some(uid), &ReadLimits::default(), Want::Volume)?,
        ),
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

/// The bytes [`write_volume`] would write to a file named `name`, made in
/// memory (downloads, uploads to other services): one-file formats only
/// (`.nii`, `.nii.gz`, `.nrrd`, `.mha`, `.tif`/`.tiff`).
pub fn write_volume_bytes(name: &str, v: &AnyVolume) -> Result<Vec<u8>, IoError> {
    let path = Path::new(name);
    let mut out = std::io::Cursor::new(Vec::new());
    match Format::of_path(path)? {
        Format::Nifti => nii::encode(&mut out, path, v, false)?,
        Format::NiftiGz => nii::encode(&mut out, path, v, true)?,
        Format::Nrrd => nrrd::encode(&mut out, path, v, &[])?,
        Format::Mha => meta::encode_mha(&mut out, path, v)?,
        Format::Tiff => tiff_stack::encode(&mut out, path, v)?,
        Format::Nhdr | Format::Mhd | Format::SliceFolder | Format::Dicom => {
            return Err(IoError::unsupported(
                path,
                "in memory only one-file formats are written (.nii, .nii.gz, .nrrd, .mha, .tif)",
            ));
        }
    }
    Ok(out.into_inner())
}

/// A label volume in its narrowest voxel type: u8 when the largest label is
/// at most 255 (what most viewers expect of a segmentation), else u16.
pub(crate) fn narrowest(v: &LabelVolume) -> AnyVolume {
    if v.data().iter().all(|&x| x <= u16::from(u8::MAX)) {
        let data: Vec<u8> = v.data().iter().map(|&x| x as u8).collect();
        AnyVolume::U8(Volume::from_vec(v.geometry().clone(), data).expect("same length"))
    } else {
        AnyVolume::U16(v.clone())
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
    write_volume(path, &narrowest(v))
}

/// The bytes [`write_labels`] would write to a file named `name`, made in
/// memory ([`write_volume_bytes`]).
pub fn write_labels_bytes(name: &str, v: &LabelVolume) -> Result<Vec<u8>, IoError> {
    write_volume_bytes(name, &narrowest(v))
}
