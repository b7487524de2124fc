//! The report builders of the CLI's studies: each measures, then writes its
//! CSV, JSON, Markdown and SVG files, every file atomically (a reader never
//! sees half a report).
use crate::error::{ProjectError, ResultExt};
use std::path::Path;

pub mod study;
pub mod variability;

/// Write `text` to `path` atomically (temporary file, then rename).
pub fn write_text(path: &Path, text: &str) -> Result<(), ProjectError> {
    use std::io::Write as _;
    interslice_io::raw::write_atomic(path, |w| w.write_all(text.as_bytes()))
        .context_with(|| format!("writing {}", path.display()))
}
