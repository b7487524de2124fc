//! The project folder and its annotation database, as the commands that work
//! on a project (`serve`, `export`, `variability`) take them.
use crate::label::LabelArg;
use anyhow::{Result, bail};
use interslice_store::Store;
use std::path::PathBuf;

/// `DIR [--db FILE]`.
#[derive(clap::Args)]
pub struct ProjectArgs {
    /// The project folder: volume files and folders of slices, one cell each.
    pub dir: PathBuf,
    /// The annotation database (default DIR/.interslice/annotations.sqlite).
    #[arg(long)]
    pub db: Option<PathBuf>,
}

impl ProjectArgs {
    /// The database file.
    pub fn db_path(&self) -> PathBuf {
        self.db
            .clone()
            .unwrap_or_else(|| interslice_store::default_db_path(&self.dir))
    }

    /// Open the database, creating it when missing (serving, exporting).
    pub fn open(&self) -> Result<Store> {
        Ok(interslice_project::open_store(
            &self.dir,
            self.db.as_deref(),
            None,
        )?)
    }

    /// Open a database that must exist already: reports on what was traced.
    pub fn open_existing(&self) -> Result<Store> {
        let db = self.db_path();
        if self.dir.is_dir() && !db.is_file() {
            bail!(
                "{} has no annotation database ({}); trace with `interslice serve` first",
                self.dir.display(),
                db.display()
            );
        }
        self.open()
    }
}

/// `--label`, resolved against the project's components (None: every label).
pub fn resolve_label(store: &Store, label: Option<&LabelArg>) -> Result<Option<u16>> {
    let Some(l) = label else { return Ok(None) };
    l.resolve_in(&store.components()?).map(Some)
}
