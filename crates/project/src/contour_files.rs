//! Contours files (`docs/contours-format.md`) on disk: read with a size
//! bound, and interpolated into a label volume by the same function the
//! server uses for a tracing in its database ([`crate::groundtruth::label_volume`]),
//! each label with its own drawn slices.
use crate::error::{ProjectError, ResultExt};
use crate::groundtruth::{FileTracing, label_volume};
use interslice_core::contour_file::{self, ContourFile, MAX_FILE_BYTES};
use interslice_core::{Cancel, LabelVolume};
use interslice_interp::Interpolator;
use std::io::Read as _;
use std::path::Path;

/// Read and check a contours file; a file over
/// [`contour_file::MAX_FILE_BYTES`] is refused before it is read whole.
pub fn read(path: &Path) -> Result<ContourFile, ProjectError> {
    let f = std::fs::File::open(path).context_with(|| format!("cannot read {}", path.display()))?;
    let mut text = String::new();
    f.take(MAX_FILE_BYTES as u64 + 1)
        .read_to_string(&mut text)
        .context_with(|| format!("cannot read {}", path.display()))?;
    if text.len() > MAX_FILE_BYTES {
        return Err(ProjectError::invalid(format!(
            "{}: over {} MiB",
            path.display(),
            MAX_FILE_BYTES >> 20
        )));
    }
    contour_file::read(&text).context_with(|| path.display().to_string())
}

/// Whether `path` names a contours file: `.json` by its extension, else a
/// file whose first non-blank byte opens a JSON object (no volume format
/// starts with `{`).
pub fn is_contours_file(path: &Path) -> bool {
    let name = path.to_string_lossy().to_ascii_lowercase();
    if name.ends_with(".json") {
        return true;
    }
    if !path.is_file() {
        return false;
    }
    let mut head = [0u8; 64];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    head[..n]
        .iter()
        .find(|b| !b.is_ascii_whitespace())
        .is_some_and(|&b| b == b'{')
}

/// The label volume of a contours file on its own grid: each label is
/// interpolated from its own traced and drawn-empty slices along every axis
/// with at least two of them (one result per label), then painted in
/// ascending label order.
pub fn interpolate(
    file: &ContourFile,
    name: &str,
    method: &dyn Interpolator,
    only_label: Option<u16>,
    cancel: &Cancel,
) -> Result<LabelVolume, ProjectError> {
    let tracing = FileTracing { file, name };
    label_volume(&tracing, &file.geometry, method, only_label, cancel)
}
