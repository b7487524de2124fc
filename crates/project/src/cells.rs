//! The cells of a project folder: discovery, safe ids and loading a volume
//! with what the API reports about it (range, histogram, content hash).
use crate::error::ProjectError;
use interslice_core::{AnyVolume, Volume, Voxel};
use interslice_interp::image::Conditioned;
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::path::{Component, Path, PathBuf};

/// Folder names inside a project that never hold cells.
pub const RESERVED_DIRS: [&str; 3] = [".interslice", "ground_truth", "segmentations"];

/// Volume file extensions, longest first, stripped to make a cell id.
const EXTENSIONS: [&str; 11] = [
    ".ome.tiff",
    ".ome.tif",
    ".nii.gz",
    ".nrrd",
    ".nhdr",
    ".tiff",
    ".nii",
    ".mha",
    ".mhd",
    ".tif",
    ".dcm",
];

/// True for a name usable as a cell id: 1..=128 of `[A-Za-z0-9._-]`, not
/// starting with a dot (so never `.`, `..` or a hidden file), never a path.
pub fn is_safe_id(id: &str) -> bool {
    !id.is_empty()
        && id.len() <= 128
        && !id.starts_with('.')
        && id
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'.' || b == b'_' || b == b'-')
}

/// The cell id of a file or folder name: the name without its volume
/// extension, characters outside `[A-Za-z0-9._-]` replaced by `_`.
pub fn id_of_name(name: &str) -> String {
    let lower = name.to_ascii_lowercase();
    let stem = EXTENSIONS
        .iter()
        .find(|e| lower.ends_with(*e) && lower.len() > e.len())
        .map(|e| &name[..name.len() - e.len()])
        .unwrap_or(name);
    let mut id: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if id.starts_with('.') || id.is_empty() {
        id.insert(0, '_');
    }
    id.truncate(120);
    id
}

/// A relative path given by a client (e.g. a segmentation file to evaluate):
/// refused when absolute or when it has `..` (or any non-normal component).
pub fn safe_relative_path(p: &str) -> Result<PathBuf, ProjectError> {
    let path = Path::new(p);
    if p.is_empty() || p.contains('\0') {
        return Err(ProjectError::invalid("empty path"));
    }
    if path.is_absolute() || p.starts_with('/') || p.starts_with('\\') {
        return Err(ProjectError::invalid(format!(
            "absolute paths are not allowed: '{p}'"
        )));
    }
    for c in path.components() {
        if !matches!(c, Component::Normal(_)) {
            return Err(ProjectError::invalid(format!(
                "paths may not contain '..' or '.': '{p}'"
            )));
        }
    }
    if p.split(['/', '\\']).any(|s| s == "..") {
        return Err(ProjectError::invalid(format!(
            "paths may not contain '..': '{p}'"
        )));
    }
    Ok(path.to_path_buf())
}

fn has_slice_images(dir: &Path) -> bool {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return false;
    };
    rd.flatten()
        .filter(|e| {
            let n = e.file_name().to_string_lossy().to_ascii_lowercase();
            n.ends_with(".png") || n.ends_with(".tif") || n.ends_with(".tiff")
        })
        .take(2)
        .count()
        >= 2
}

/// The leaf that addresses one series of a multi-series DICOM folder:
/// `FOLDER/@series=UID` (no DICOM file is named so; see [`series_of`]).
const SERIES_LEAF: &str = "@series=";

/// The path of the cell that is series `uid` of the DICOM folder `folder`.
pub fn series_path(folder: &Path, uid: &str) -> PathBuf {
    folder.join(format!("{SERIES_LEAF}{uid}"))
}

/// The DICOM folder and series UID of a path made by [`series_path`].
pub fn series_of(path: &Path) -> Option<(&Path, &str)> {
    let leaf = path.file_name()?.to_str()?.strip_prefix(SERIES_LEAF)?;
    Some((path.parent()?, leaf))
}

/// What a cell's file is called in lists: its file name, or for one series
/// of a DICOM folder `FOLDER (series UID)`.
pub fn display_name(path: &Path) -> String {
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    match series_of(path) {
        Some((folder, uid)) => format!("{} (series {uid})", name(folder)),
        None => name(path),
    }
}

/// The series of a DICOM folder (`None` when it cannot be listed). Listing
/// reads every file's header, and the cells are scanned again at every
/// cell list, so the answer is kept while the folder's modification time
/// (which changes when files are added, removed or renamed) stays the same.
fn series_listed(path: &Path) -> Option<Vec<interslice_io::dicom::SeriesInfo>> {
    type Listed = (
        std::time::SystemTime,
        Option<Vec<interslice_io::dicom::SeriesInfo>>,
    );
    static LISTED: std::sync::LazyLock<std::sync::Mutex<HashMap<PathBuf, Listed>>> =
        std::sync::LazyLock::new(Default::default);
    let list = || interslice_io::dicom::list_series(path).ok();
    let Ok(modified) = std::fs::metadata(path).and_then(|m| m.modified()) else {
        return list();
    };
    let cache = || LISTED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((at, series)) = cache().get(path)
        && *at == modified
    {
        return series.clone();
    }
    // Listed without the lock held: other folders are not kept waiting.
    let series = list();
    cache().insert(path.to_path_buf(), (modified, series.clone()));
    series
}

/// The cells of a DICOM folder named `name`: the folder itself when it holds
/// one series (or cannot be listed: reading it then reports why), else one
/// cell per series, `NAME-s<SeriesNumber>` (`NAME-<n>` when the numbers
/// are missing or repeat), in SeriesNumber order.
fn dicom_cells(name: &str, path: &Path) -> Vec<(String, PathBuf)> {
    let base = id_of_name(name);
    let series = match series_listed(path) {
        Some(s) if s.len() > 1 => s,
        _ => return vec![(base, path.to_path_buf())],
    };
    let numbers: Vec<Option<i64>> = series.iter().map(|s| s.number).collect();
    let unique = numbers.iter().all(Option::is_some)
        && numbers
            .iter()
            .collect::<std::collections::BTreeSet<_>>()
            .len()
            == numbers.len();
    series
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let id = match (unique, s.number) {
                (true, Some(n)) => format!("{base}-s{n}"),
                _ => format!("{base}-{}", i + 1),
            };
            (id, series_path(path, &s.uid))
        })
        .collect()
}

/// The cells of `dir`, by id: supported volume files, folders of slice
/// images and folders of DICOM files (one cell per series) at the top level;
/// hidden entries and the reserved folders skipped. Two names mapping to one
/// id get `-2`, `-3`, ... in name order.
pub fn scan(dir: &Path) -> std::io::Result<BTreeMap<String, PathBuf>> {
    let mut entries: Vec<(String, PathBuf)> = std::fs::read_dir(dir)?
        .flatten()
        .map(|e| (e.file_name().to_string_lossy().to_string(), e.path()))
        .collect();
    entries.sort();
    let mut out = BTreeMap::new();
    for (name, path) in entries {
        if name.starts_with('.') || RESERVED_DIRS.contains(&name.as_str()) {
            continue;
        }
        let found = if path.is_dir() && interslice_io::dicom::is_dicom_folder(&path) {
            dicom_cells(&name, &path)
        } else if path.is_dir() {
            if has_slice_images(&path) && interslice_io::Format::of_path(&path).is_ok() {
                vec![(id_of_name(&name), path)]
            } else {
                Vec::new()
            }
        } else if interslice_io::Format::of_path(&path).is_ok() {
            vec![(id_of_name(&name), path)]
        } else {
            Vec::new()
        };
        for (base, path) in found {
            let mut id = base.clone();
            let mut n = 2;
            while out.contains_key(&id) {
                id = format!("{base}-{n}");
                n += 1;
            }
            out.insert(id, path);
        }
    }
    Ok(out)
}

/// A volume in memory with what the API reports about it.
#[derive(Debug)]
pub struct LoadedCell {
    /// The voxels.
    pub volume: AnyVolume,
    /// Smallest finite intensity.
    pub min: f64,
    /// Largest finite intensity.
    pub max: f64,
    /// Width of a histogram bin.
    pub bin_width: f64,
    /// 256 histogram bins from `min` (finite voxels only).
    pub counts: Vec<u64>,
    /// BLAKE3 of the dims and voxel bytes (detects a file changed under tracings).
    pub content_hash: String,
    /// The voxels as `f32` for the image-guided method, made on its first use
    /// (four bytes a voxel, so only cells interpolated with the image pay it).
    intensity: std::sync::OnceLock<Conditioned>,
}

fn histogram<T: Voxel>(v: &Volume<T>, min: f64, width: f64) -> Vec<u64> {
    v.data()
        .par_chunks(1 << 16)
        .fold(
            || vec![0u64; 256],
            |mut acc, chunk| {
                for &x in chunk {
                    let x = x.to_f64();
                    // NaN and infinities (float files) have no bin.
                    if x.is_finite() {
                        acc[((x - min) / width).floor().clamp(0.0, 255.0) as usize] += 1;
                    }
                }
                acc
            },
        )
        .reduce(
            || vec![0u64; 256],
            |mut a, b| {
                a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                a
            },
        )
}

/// Smallest and largest finite value ((0, 0) when there is none): a NaN or
/// an infinity in a float file would otherwise make the range, the
/// histogram and every window computed from them meaningless.
fn finite_range(volume: &AnyVolume) -> (f64, f64) {
    let AnyVolume::F32(v) = volume else {
        return volume.min_max();
    };
    let (lo, hi) = v
        .data()
        .par_iter()
        .filter(|x| x.is_finite())
        .fold(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |(l, h), &x| (l.min(x), h.max(x)),
        )
        .reduce(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    if lo > hi {
        (0.0, 0.0)
    } else {
        (f64::from(lo), f64::from(hi))
    }
}

impl LoadedCell {
    /// Read a cell and compute its range, histogram and content hash.
    /// Every allocation the file's header asks for is checked by the reader
    /// (the default [`interslice_io::ReadLimits`]); a reader that panics
    /// all the same makes this cell's error, never the server's end.
    pub fn load(path: &Path) -> Result<LoadedCell, ProjectError> {
        let read = std::panic::catch_unwind(|| match series_of(path) {
            Some((folder, uid)) => interslice_io::read_volume_series(folder, Some(uid)),
            None => interslice_io::read_volume_with(path, &interslice_io::ReadLimits::default()),
        });
        let name = display_name(path);
        match read {
            Ok(Ok(volume)) => Ok(Self::from_volume(volume)),
            Ok(Err(e)) => Err(ProjectError::from(e)),
            Err(_) => Err(ProjectError::internal(format!(
                "cell file {name} cannot be read (the reader failed)"
            ))),
        }
    }

    /// Wrap a volume already in memory.
    pub fn from_volume(volume: AnyVolume) -> LoadedCell {
        let (min, max) = finite_range(&volume);
        let integer = !matches!(volume, AnyVolume::F32(_));
        let bin_width = if integer {
            ((max - min + 1.0) / 256.0).ceil().max(1.0)
        } else if max > min {
            (max - min) / 256.0
        } else {
            1.0
        };
        let counts = match &volume {
            AnyVolume::U8(v) => histogram(v, min, bin_width),
            AnyVolume::U16(v) => histogram(v, min, bin_width),
            AnyVolume::I16(v) => histogram(v, min, bin_width),
            AnyVolume::F32(v) => histogram(v, min, bin_width),
        };
        let mut h = blake3::Hasher::new();
        h.update(volume.type_name().as_bytes());
        for d in volume.geometry().dims {
            h.update(&(d as u64).to_le_bytes());
        }
        let n = volume.geometry().len();
        let step = 1 << 16;
        let mut start = 0;
        while start < n {
            let end = (start + step).min(n);
            h.update(&volume.le_bytes(start..end));
            start = end;
        }
        LoadedCell {
            volume,
            min,
            max,
            bin_width,
            counts,
            content_hash: h.finalize().to_hex().to_string(),
            intensity: std::sync::OnceLock::new(),
        }
    }

    /// The intensities as `f32`, [`Conditioned`] for the image-aware methods
    /// (finite, at a workable scale), shared by every image-guided
    /// interpolation and advice on this cell: conditioned once here, never
    /// scanned or copied again.
    pub fn intensity(&self) -> Conditioned {
        self.intensity
            .get_or_init(|| {
                Conditioned::from(interslice_interp::image::intensity_f32(&self.volume))
            })
            .clone()
    }

    /// "u8", "u16", "i16" or "f32".
    pub fn dtype(&self) -> &'static str {
        self.volume.type_name()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_safe_names() {
        assert_eq!(id_of_name("cell 01.nii.gz"), "cell_01");
        assert_eq!(id_of_name("A.NRRD"), "A");
        assert_eq!(id_of_name(".hidden.nii"), "_.hidden");
        assert_eq!(id_of_name("slices"), "slices");
        for n in ["cell 01.nii.gz", "../x.nii", "é.tif", "..", "a/b"] {
            assert!(is_safe_id(&id_of_name(n)), "{n}");
        }
        assert!(!is_safe_id("../etc"));
        assert!(!is_safe_id("/etc"));
        assert!(!is_safe_id(".."));
        assert!(!is_safe_id(""));
        assert!(is_safe_id("cell-1.v2"));
    }

    #[test]
    fn relative_paths_refuse_escapes() {
        assert!(safe_relative_path("segmentations/c1/otsu.nii.gz").is_ok());
        for bad in ["../x", "/etc/passwd", "a/../../b", "./a", "", "a/..", "\\x"] {
            assert!(safe_relative_path(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn histogram_of_u8_has_unit_bins() {
        let g = interslice_core::Geometry::new([4, 1, 1], [1.0; 3], Default::default()).unwrap();
        let v = Volume::from_vec(g, vec![3u8, 3, 5, 200]).unwrap();
        let c = LoadedCell::from_volume(AnyVolume::U8(v));
        assert_eq!((c.min, c.max, c.bin_width), (3.0, 200.0, 1.0));
        assert_eq!(c.counts[0], 2);
        assert_eq!(c.counts[2], 1);
        assert_eq!(c.counts[197], 1);
        assert_eq!(c.counts.iter().sum::<u64>(), 4);
    }

    #[test]
    fn float_range_and_histogram_skip_nan_and_infinities() {
        let g = interslice_core::Geometry::new([6, 1, 1], [1.0; 3], Default::default()).unwrap();
        let data = vec![f32::NAN, -2.0, f32::INFINITY, 0.5, 6.0, f32::NEG_INFINITY];
        let c = LoadedCell::from_volume(AnyVolume::F32(Volume::from_vec(g.clone(), data).unwrap()));
        assert_eq!((c.min, c.max, c.bin_width), (-2.0, 6.0, 8.0 / 256.0));
        assert_eq!(c.counts.iter().sum::<u64>(), 3);
        assert_eq!((c.counts[0], c.counts[80], c.counts[255]), (1, 1, 1));
        let none = vec![f32::NAN; 6];
        let c = LoadedCell::from_volume(AnyVolume::F32(Volume::from_vec(g, none).unwrap()));
        assert_eq!((c.min, c.max), (0.0, 0.0));
        assert_eq!(c.counts.iter().sum::<u64>(), 0);
    }

    #[test]
    fn histogram_of_i16_spans_the_signed_range() {
        let g = interslice_core::Geometry::new([4, 1, 1], [1.0; 3], Default::default()).unwrap();
        let v = Volume::from_vec(g, vec![-1024i16, -1000, 40, 3071]).unwrap();
        let c = LoadedCell::from_volume(AnyVolume::I16(v));
        assert_eq!((c.min, c.max, c.bin_width), (-1024.0, 3071.0, 16.0));
        assert_eq!(
            (c.counts[0], c.counts[1], c.counts[66], c.counts[255]),
            (1, 1, 1, 1)
        );
    }
}
