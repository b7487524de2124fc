//! A project folder and what is computed from it, below any HTTP: its cells,
//! each user's tracing as a label volume, the STAPLE consensus, exports, the
//! interpolation methods by name and the project file. The server
//! (`interslice-server`) answers requests with these functions and the CLI
//! calls them directly, so both compute the same thing.
//!
//! A project folder holds the cells (volume files or folders of slices); the
//! annotation database lives at `DIR/.interslice/annotations.sqlite`.
#![deny(missing_docs)]

pub mod cells;
pub mod consensus;
pub mod contour_files;
pub mod error;
pub mod export;
pub mod groundtruth;
pub mod methods;
pub mod previews;
pub mod project_file;
pub mod report;

pub use error::ProjectError;

use interslice_core::components::Components;
use interslice_store::Store;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Open a project's annotation database (`db`, default
/// `DIR/.interslice/annotations.sqlite`) and settle its components: the
/// given ones are written to the project file, else the project file's are
/// used; either way they become the database's labels (none: the
/// database's own).
pub fn open_store(
    dir: &Path,
    db: Option<&Path>,
    components: Option<&Components>,
) -> Result<Store, ProjectError> {
    if !dir.is_dir() {
        return Err(ProjectError::invalid(format!(
            "{} is not a folder",
            dir.display()
        )));
    }
    let db = db
        .map(Path::to_path_buf)
        .unwrap_or_else(|| interslice_store::default_db_path(dir));
    let store = Store::open(&db)
        .map_err(|e| ProjectError::invalid(format!("cannot open {}: {e}", db.display())))?;
    let components = match components {
        Some(c) => {
            project_file::write_components(dir, c)?;
            Some(c.clone())
        }
        None => project_file::read_components(dir)?,
    };
    if let Some(c) = &components {
        store.sync_components(c).map_err(|e| {
            ProjectError::invalid(format!("cannot set the project's components: {e}"))
        })?;
    }
    Ok(store)
}

/// The cells of `dir` ([`cells::scan`]), registering in the database those
/// not in `known` (new or moved): listing the cells is frequent and must not
/// cost a write transaction per cell.
pub fn register_cells(
    store: &Store,
    dir: &Path,
    known: &BTreeMap<String, PathBuf>,
) -> Result<BTreeMap<String, PathBuf>, ProjectError> {
    let found = cells::scan(dir).map_err(|e| ProjectError::internal(e.to_string()))?;
    for (id, path) in &found {
        if known.get(id) == Some(path) {
            continue;
        }
        let rel = path.strip_prefix(dir).unwrap_or(path);
        store.upsert_cell(id, &rel.to_string_lossy())?;
    }
    Ok(found)
}

/// The path of cell `id` among `cells`: invalid for an unsafe id, not found
/// for an unknown one.
pub fn cell_path(cells: &BTreeMap<String, PathBuf>, id: &str) -> Result<PathBuf, ProjectError> {
    if !cells::is_safe_id(id) {
        return Err(ProjectError::invalid(format!(
            "invalid cell id '{id}' (ids are names, never paths)"
        )));
    }
    cells
        .get(id)
        .cloned()
        .ok_or_else(|| ProjectError::not_found(format!("unknown cell '{id}'")))
}
