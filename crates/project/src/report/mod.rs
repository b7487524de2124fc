//! The report builders of the CLI's studies: each measures, then writes its
//! CSV, JSON, Markdown and SVG files, every file atomically (a reader never
//! sees half a report).
use crate::error::{ProjectError, ResultExt};
use std::path::Path;

pub mod effort;
pub mod strategy;
pub mod study;
pub mod variability;

/// Colours of the plots' lines and dots: the colour-blind safe Okabe-Ito
/// palette (blue, vermillion, green, purple, orange, sky blue), then black
/// and yellow.
pub(crate) const COLOURS: &[(u8, u8, u8)] = &[
    (0, 114, 178),
    (213, 94, 0),
    (0, 158, 115),
    (204, 121, 167),
    (230, 159, 0),
    (86, 180, 233),
    (0, 0, 0),
    (240, 228, 66),
];

/// Write `text` to `path` atomically (temporary file, then rename).
pub fn write_text(path: &Path, text: &str) -> Result<(), ProjectError> {
    use std::io::Write as _;
    interslice_io::raw::write_atomic(path, |w| w.write_all(text.as_bytes()))
        .context_with(|| format!("writing {}", path.display()))
}
