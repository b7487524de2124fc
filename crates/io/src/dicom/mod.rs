//! DICOM: a folder of DICOM files (or one file) read as a volume, with the
//! `dicom-object` and `dicom-pixeldata` crates.
//!
//! A folder is scanned flat (no subfolders): every non-hidden file that
//! starts with the 128-byte preamble and `DICM` is a DICOM file, whatever
//! its name; other files and non-image objects (DICOMDIR, reports) are
//! skipped. Files are grouped by SeriesInstanceUID; a folder with several
//! series needs one chosen ([`read`] with a UID; [`list_series`] lists
//! them). A series becomes a volume as `series.rs` describes (sorted along
//! the slice normal, spacing measured from the positions, LPS geometry as
//! ITK reports it), and its pixels as `pixels.rs` describes (rescale
//! slope/intercept, narrowest lossless type). The conventions are in
//! `docs/formats.md`.
mod header;
mod pixels;
mod series;

use crate::IoError;
use header::FileHeader;
use interslice_core::AnyVolume;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Most DICOM files we read from one folder (a bound on the work and
/// memory a folder can ask for before anything is decoded).
pub const MAX_FILES: usize = 100_000;

/// Files looked at (for the `DICM` magic) to call a folder a DICOM folder.
const SNIFF_FILES: usize = 64;

/// One series of a DICOM folder, as [`list_series`] reports it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SeriesInfo {
    /// SeriesInstanceUID (empty for files without one).
    pub uid: String,
    /// SeriesDescription ("" when absent).
    pub description: String,
    /// SeriesNumber, when present.
    pub number: Option<i64>,
    /// Modality ("CT", "MR", ...).
    pub modality: String,
    /// Number of image files.
    pub files: usize,
    /// Columns, rows (of the first file) and number of image planes
    /// (frames of all files): the dims of the volume when it reads.
    pub dims: [usize; 3],
}

/// True when the file starts with the DICOM preamble and `DICM`.
pub fn is_dicom_file(path: &Path) -> bool {
    header::has_dicm_magic(path)
}

/// True when `dir` is a folder with DICOM files: one of its first non-hidden
/// files that are not PNG or TIFF slices starts with the DICOM preamble.
pub fn is_dicom_folder(dir: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    entries
        .flatten()
        .filter(|e| {
            let name = e.file_name().to_string_lossy().to_ascii_lowercase();
            !name.starts_with('.')
                && ![".png", ".tif", ".tiff"].iter().any(|x| name.ends_with(x))
                && e.path().is_file()
        })
        .take(SNIFF_FILES)
        .any(|e| is_dicom_file(&e.path()))
}

/// The DICOM files of a folder (non-hidden files with the `DICM` magic),
/// sorted naturally by name; or the file itself.
fn dicom_files(path: &Path) -> Result<Vec<PathBuf>, IoError> {
    if !path.is_dir() {
        if !is_dicom_file(path) {
            std::fs::metadata(path).map_err(|e| IoError::read(path, e))?;
            return Err(IoError::invalid(
                path,
                "not a DICOM file (no DICM preamble)",
            ));
        }
        return Ok(vec![path.to_path_buf()]);
    }
    let mut names = Vec::new();
    for entry in std::fs::read_dir(path).map_err(|e| IoError::read(path, e))? {
        let entry = entry.map_err(|e| IoError::read(path, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') || !entry.path().is_file() {
            continue;
        }
        names.push(name);
        if names.len() > 4 * MAX_FILES {
            return Err(IoError::unsupported(
                path,
                format!("folder holds more than {} files", 4 * MAX_FILES),
            ));
        }
    }
    names.sort_by(|a, b| natord::compare(a, b));
    let files: Vec<PathBuf> = names
        .par_iter()
        .map(|n| path.join(n))
        .filter(|p| is_dicom_file(p))
        .collect();
    if files.len() > MAX_FILES {
        return Err(IoError::unsupported(
            path,
            format!(
                "folder holds {} DICOM files (at most {MAX_FILES} are read)",
                files.len()
            ),
        ));
    }
    Ok(files)
}

/// The image headers of a folder (or file), grouped by SeriesInstanceUID.
fn scan(path: &Path) -> Result<BTreeMap<String, Vec<FileHeader>>, IoError> {
    let files = dicom_files(path)?;
    let headers: Vec<Option<FileHeader>> = files
        .par_iter()
        .map(|f| header::read_header(f))
        .collect::<Result<_, _>>()?;
    let mut groups: BTreeMap<String, Vec<FileHeader>> = BTreeMap::new();
    for h in headers.into_iter().flatten() {
        groups.entry(h.series_uid.clone()).or_default().push(h);
    }
    if groups.is_empty() {
        return Err(IoError::invalid(
            path,
            if path.is_dir() {
                "folder has no DICOM images"
            } else {
                "DICOM file holds no image"
            },
        ));
    }
    Ok(groups)
}

fn info(uid: &str, files: &[FileHeader]) -> SeriesInfo {
    let first = &files[0];
    SeriesInfo {
        uid: uid.to_string(),
        description: first.description.clone(),
        number: first.series_number,
        modality: first.modality.clone(),
        files: files.len(),
        dims: [
            first.cols,
            first.rows,
            files.iter().map(|h| h.frames.len()).sum(),
        ],
    }
}

fn sorted_infos(groups: &BTreeMap<String, Vec<FileHeader>>) -> Vec<SeriesInfo> {
    let mut infos: Vec<SeriesInfo> = groups.iter().map(|(uid, f)| info(uid, f)).collect();
    infos.sort_by(|a, b| (a.number, &a.uid).cmp(&(b.number, &b.uid)));
    infos
}

/// The series of a DICOM folder (or file), by SeriesNumber then UID: what
/// a caller shows to let someone choose, or makes one item per series of.
pub fn list_series(path: &Path) -> Result<Vec<SeriesInfo>, IoError> {
    Ok(sorted_infos(&scan(path)?))
}

/// One line listing series: `UID "description" 256 x 256 x 20, ...`.
fn summary(infos: &[SeriesInfo]) -> String {
    const SHOWN: usize = 8;
    let mut parts: Vec<String> = infos
        .iter()
        .take(SHOWN)
        .map(|s| {
            let [x, y, z] = s.dims;
            format!("{} \"{}\" {x} x {y} x {z}", s.uid, s.description)
        })
        .collect();
    if infos.len() > SHOWN {
        parts.push(format!("and {} more", infos.len() - SHOWN));
    }
    parts.join(", ")
}

/// Read a DICOM folder (or file) as a volume: the series with the given
/// SeriesInstanceUID, or the only series there is.
pub fn read(path: &Path, series: Option<&str>) -> Result<AnyVolume, IoError> {
    let mut groups = scan(path)?;
    let files = match series {
        Some(uid) => match groups.remove(uid) {
            Some(files) => files,
            None => {
                return Err(IoError::invalid(
                    path,
                    format!(
                        "no DICOM series {uid} here; the series are: {}",
                        summary(&sorted_infos(&groups))
                    ),
                ));
            }
        },
        None if groups.len() == 1 => groups.into_values().next().unwrap_or_default(),
        None => {
            let infos = sorted_infos(&groups);
            return Err(IoError::invalid(
                path,
                format!(
                    "holds {} DICOM series; choose one by its UID (--series UID): {}",
                    infos.len(),
                    summary(&infos)
                ),
            ));
        }
    };
    let arranged = series::arrange(path, &files)?;
    pixels::read(path, &files, &arranged)
}
