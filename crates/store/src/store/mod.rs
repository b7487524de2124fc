//! The [`Store`]: a SQLite connection behind a mutex, with typed operations.
//!
//! Every public write runs in one transaction together with its audit entry,
//! so the database never holds half a change.
//!
//! The operations are split by table group: `users` (users and sessions),
//! `cells` (cells, labels, status, time), `contours` (contours and
//! drawn-empty slices), `changes` (the undo/redo change log), `results`
//! (interpolation results), `segmentations` (automated segmentations and
//! ratings) and `audit` (the append-only audit log).
use crate::migrations;
use crate::model::SpaceUsage;
use crate::{Result, StoreError};
use checkpoint::Checkpointer;
use interslice_core::Axis;
use rusqlite::{Connection, Transaction};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;

mod audit;
mod cells;
mod changes;
mod checkpoint;
mod components;
mod contours;
mod results;
mod segmentations;
mod users;

/// The size past which the WAL file is emptied by a TRUNCATE checkpoint (see
/// `Checkpointer`); with one tick of writes on top it stays well under 64 MiB.
const WAL_LIMIT: u64 = 32 << 20;

/// The annotation database.
///
/// One connection serialised by a mutex: SQLite allows one writer at a time
/// anyway, and every operation here is a few indexed statements (well under a
/// millisecond), so a pool would add complexity without throughput.
pub struct Store {
    conn: Mutex<Connection>,
    path: Option<PathBuf>,
    checkpointer: Option<Checkpointer>,
}

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Store")
            .field("path", &self.path)
            .field("background_checkpoints", &self.checkpointer.is_some())
            .finish()
    }
}

fn axis_str(a: Axis) -> &'static str {
    match a {
        Axis::X => "x",
        Axis::Y => "y",
        Axis::Z => "z",
    }
}

fn parse_axis(s: &str) -> rusqlite::Result<Axis> {
    Axis::parse(s).map_err(|e| {
        rusqlite::Error::FromSqlConversionFailure(0, rusqlite::types::Type::Text, Box::new(e))
    })
}

fn json_err(e: serde_json::Error) -> rusqlite::Error {
    rusqlite::Error::FromSqlConversionFailure(0, rusqlite::types::Type::Text, Box::new(e))
}

fn unix_now() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0)
}

impl Store {
    /// Open (creating if needed) the database at `path`: WAL, foreign keys,
    /// migrations to the latest version.
    pub fn open(path: &Path) -> Result<Store> {
        Self::open_with_wal_limit(path, WAL_LIMIT)
    }

    /// [`Store::open`] with another bound on the WAL file.
    fn open_with_wal_limit(path: &Path, wal_limit: u64) -> Result<Store> {
        if let Some(parent) = path.parent()
            && !parent.as_os_str().is_empty()
        {
            std::fs::create_dir_all(parent).map_err(|source| StoreError::Io {
                path: parent.display().to_string(),
                source,
            })?;
        }
        let conn = Connection::open(path)?;
        Self::init(conn, Some(path.to_path_buf()), wal_limit)
    }

    /// A private in-memory database (tests, throw-away runs).
    pub fn open_in_memory() -> Result<Store> {
        Self::init(Connection::open_in_memory()?, None, WAL_LIMIT)
    }

    fn init(mut conn: Connection, path: Option<PathBuf>, wal_limit: u64) -> Result<Store> {
        conn.busy_timeout(Duration::from_secs(10))?;
        // WAL: readers do not block the writer; NORMAL: a commit is durable against
        // a process crash (the WAL is written before COMMIT returns), fsync at checkpoints.
        conn.pragma_update_and_check(None, "journal_mode", "WAL", |_| Ok(()))?;
        conn.pragma_update(None, "synchronous", "NORMAL")?;
        conn.pragma_update(None, "foreign_keys", "ON")?;
        conn.set_prepared_statement_cache_capacity(64);
        migrations::migrate(&mut conn)?;
        // Checkpoints happen on their own thread (see `Checkpointer`); the last
        // connection to close still checkpoints and removes the WAL.
        let checkpointer = match &path {
            Some(p) => {
                conn.pragma_update(None, "wal_autocheckpoint", 0)?;
                // SQLite truncates the WAL file to this size when it rewinds it.
                conn.pragma_update(None, "journal_size_limit", wal_limit as i64)?;
                Some(Checkpointer::start(p, wal_limit)?)
            }
            None => None,
        };
        Ok(Store {
            conn: Mutex::new(conn),
            path,
            checkpointer,
        })
    }

    /// The database file, if not in memory.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    fn lock(&self) -> MutexGuard<'_, Connection> {
        // A panic while holding the lock dropped its transaction (rolled back),
        // so the connection is still consistent.
        self.conn.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn write<T>(&self, f: impl FnOnce(&Transaction<'_>) -> Result<T>) -> Result<T> {
        let mut conn = self.lock();
        let tx = conn.transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)?;
        let out = f(&tx)?;
        tx.commit()?;
        Ok(out)
    }

    fn read<T>(&self, f: impl FnOnce(&Transaction<'_>) -> Result<T>) -> Result<T> {
        let mut conn = self.lock();
        let tx = conn.transaction()?;
        let out = f(&tx)?;
        tx.commit()?;
        Ok(out)
    }

    /// `PRAGMA integrity_check`: "ok" for a sound database.
    pub fn integrity_check(&self) -> Result<String> {
        let conn = self.lock();
        let rows: Vec<String> = conn
            .prepare("PRAGMA integrity_check")?
            .query_map([], |r| r.get(0))?
            .collect::<rusqlite::Result<_>>()?;
        Ok(rows.join("; "))
    }

    /// How much space the database takes: its pages, the pages of the
    /// `contours` table, and the WAL file.
    pub fn space(&self) -> Result<SpaceUsage> {
        let conn = self.lock();
        let page_size: i64 = conn.query_row("PRAGMA page_size", [], |r| r.get(0))?;
        let pages: i64 = conn.query_row("PRAGMA page_count", [], |r| r.get(0))?;
        let contours: i64 = conn.query_row(
            "SELECT COALESCE(SUM(pgsize), 0) FROM dbstat WHERE name = 'contours'",
            [],
            |r| r.get(0),
        )?;
        let by_object: Vec<(String, u64)> = conn
            .prepare("SELECT name, SUM(pgsize) AS b FROM dbstat GROUP BY name ORDER BY b DESC")?
            .query_map([], |r| {
                Ok((r.get::<_, String>(0)?, r.get::<_, i64>(1)? as u64))
            })?
            .collect::<rusqlite::Result<_>>()?;
        let wal_bytes = match &self.path {
            Some(p) => {
                let mut wal = p.as_os_str().to_owned();
                wal.push("-wal");
                std::fs::metadata(wal).map_or(0, |m| m.len())
            }
            None => 0,
        };
        Ok(SpaceUsage {
            database_bytes: (page_size * pages) as u64,
            contours_bytes: contours as u64,
            wal_bytes,
            by_object,
        })
    }

    /// The schema version of the open database.
    pub fn schema_version(&self) -> Result<i64> {
        Ok(self
            .lock()
            .query_row("PRAGMA user_version", [], |r| r.get(0))?)
    }
}

#[cfg(test)]
mod fixtures;
#[cfg(test)]
mod history_tests;
#[cfg(test)]
mod tests;
