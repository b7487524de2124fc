//! The background WAL checkpoint thread.
use crate::{Result, StoreError};
use rusqlite::Connection;
use std::path::Path;
use std::time::Duration;

/// Copies the WAL back into the database file on its own thread and
/// connection, so that no request pays for a checkpoint (SQLite's automatic
/// checkpoint runs inside the commit that crosses 1000 pages, and with its
/// fsyncs it was the whole p99 of a contour save).
///
/// It also keeps the WAL file bounded: a PASSIVE checkpoint never waits, so
/// under a steady stream of writes it may never catch up with the writer and
/// the WAL grows without end (SQLite rewinds it only when a write starts after
/// a complete checkpoint, and never shrinks the file unless told to). Once the
/// file passes the limit, a TRUNCATE checkpoint waits for the writer's current
/// transaction, copies everything and empties the file. The file's size is
/// looked at every [`Self::SIZE_CHECK`] (one `stat`), because a busy server
/// writes tens of MiB to the WAL within one checkpoint period.
pub(super) struct Checkpointer {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Checkpointer {
    /// How often the WAL is checkpointed.
    const PERIOD: Duration = Duration::from_millis(500);
    /// How often the WAL's size is compared with the limit.
    const SIZE_CHECK: Duration = Duration::from_millis(50);

    /// Start checkpointing the database at `path`, truncating its WAL once
    /// the file exceeds `wal_limit` bytes.
    pub(super) fn start(path: &Path, wal_limit: u64) -> Result<Checkpointer> {
        use std::sync::atomic::{AtomicBool, Ordering};
        let conn = Connection::open(path)?;
        conn.busy_timeout(Duration::from_secs(10))?;
        conn.pragma_update(None, "journal_size_limit", wal_limit as i64)?;
        let mut wal = path.as_os_str().to_owned();
        wal.push("-wal");
        let wal = std::path::PathBuf::from(wal);
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("sqlite-checkpoint".into())
            .spawn(move || {
                let mut last_passive = std::time::Instant::now();
                while !flag.load(Ordering::Acquire) {
                    std::thread::park_timeout(Self::SIZE_CHECK);
                    if last_passive.elapsed() >= Self::PERIOD {
                        // PASSIVE never waits for readers or the writer; a
                        // busy or failed round is retried on the next period.
                        let _ = conn.query_row("PRAGMA wal_checkpoint(PASSIVE)", [], |_| Ok(()));
                        last_passive = std::time::Instant::now();
                    }
                    if std::fs::metadata(&wal).is_ok_and(|m| m.len() > wal_limit) {
                        // Waits (busy timeout) for the writer; a failed round
                        // is retried on the next tick.
                        let _ = conn.query_row("PRAGMA wal_checkpoint(TRUNCATE)", [], |_| Ok(()));
                    }
                }
            })
            .map_err(|source| StoreError::Io {
                path: path.display().to_string(),
                source,
            })?;
        Ok(Checkpointer {
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for Checkpointer {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Release);
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}
