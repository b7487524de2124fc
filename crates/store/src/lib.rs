//! The annotation database: users, sessions, cells, labels, contours, drawn-empty
//! slices, interpolation results, time spent, cell status, automated
//! segmentations, ratings and an append-only audit log, in one SQLite file.
//!
//! Why SQLite: a tracing campaign is one folder that can be copied, backed up and
//! opened by any SQLite tool; WAL mode lets the server read while it writes, and
//! every change is one transaction, so a crash loses at most the stroke being
//! drawn (a process kill loses nothing that was committed; `synchronous=NORMAL`
//! in WAL mode may lose the last commits only on power loss).
//!
//! The schema is versioned with SQLite's `user_version` (see [`migrations`]);
//! opening an older database migrates it forward in one transaction.
#![deny(missing_docs)]

mod codec;
pub mod migrations;
mod model;
mod store;

pub use model::*;
pub use store::Store;

use thiserror::Error;

/// Errors of the annotation database; every message is one line for the user.
#[derive(Debug, Error)]
pub enum StoreError {
    /// SQLite failed (I/O, corruption, constraint).
    #[error("database: {0}")]
    Sqlite(#[from] rusqlite::Error),
    /// The thing asked for does not exist.
    #[error("{0}")]
    NotFound(String),
    /// The thing exists but belongs to another user.
    #[error("{0}")]
    Forbidden(String),
    /// The input is invalid (bad points, unknown role, duplicate name...).
    #[error("{0}")]
    Invalid(String),
    /// A wrong name or password.
    #[error("wrong name or password")]
    BadCredentials,
    /// The database was written by a newer interslice.
    #[error("database schema version {found} is newer than this program knows ({known})")]
    TooNew {
        /// The `user_version` in the file.
        found: i64,
        /// The newest version this program knows.
        known: i64,
    },
    /// Creating the database folder failed.
    #[error("cannot create {path}: {source}")]
    Io {
        /// The folder.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// Stored data could not be decoded (a damaged blob).
    #[error("stored data is damaged: {0}")]
    Corrupt(String),
}

/// The reserved user name that stands for the consensus of every user's
/// tracing in exports and evaluations (no account may take it).
pub const CONSENSUS: &str = "consensus";

/// Result alias of this crate.
pub type Result<T, E = StoreError> = std::result::Result<T, E>;

/// The database path used for a project folder unless `--db` says otherwise:
/// `DIR/.interslice/annotations.sqlite`.
pub fn default_db_path(dir: &std::path::Path) -> std::path::PathBuf {
    dir.join(".interslice").join("annotations.sqlite")
}

/// Current time as RFC 3339 UTC with milliseconds.
pub fn now_rfc3339() -> String {
    humantime::format_rfc3339_millis(std::time::SystemTime::now()).to_string()
}
