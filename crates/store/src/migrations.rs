//! Versioned schema migrations, tracked in SQLite's `PRAGMA user_version`.
//!
//! Migration `n` (1-based) takes a database at version `n - 1` to version `n`.
//! Migrations are append-only: a released migration is never edited, a change
//! of schema is a new entry at the end of [`MIGRATIONS`].
use crate::{Result, StoreError};
use rusqlite::Connection;

/// The SQL of every migration, oldest first.
pub const MIGRATIONS: &[&str] = &[
    // 1: the initial schema.
    r#"
CREATE TABLE users (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL UNIQUE,
    role TEXT NOT NULL CHECK (role IN ('tracer', 'reviewer')),
    password_hash TEXT,
    created TEXT NOT NULL
);
CREATE TABLE sessions (
    token TEXT PRIMARY KEY,
    user_id INTEGER NOT NULL REFERENCES users(id) ON DELETE CASCADE,
    created TEXT NOT NULL,
    expires_unix INTEGER NOT NULL
);
CREATE TABLE cells (
    id TEXT PRIMARY KEY,
    path TEXT NOT NULL,
    content_hash TEXT,
    geometry TEXT,
    dtype TEXT,
    updated TEXT NOT NULL
);
CREATE TABLE labels (
    id INTEGER PRIMARY KEY CHECK (id BETWEEN 1 AND 65535),
    name TEXT NOT NULL UNIQUE,
    color TEXT NOT NULL
);
INSERT INTO labels (id, name, color) VALUES
    (1, 'Cell', '#e6194b'),
    (2, 'Nucleus', '#3cb44b'),
    (3, 'Nucleolus 1', '#4363d8'),
    (4, 'Nucleolus 2', '#f58231');
CREATE TABLE contours (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    cell TEXT NOT NULL REFERENCES cells(id),
    user_id INTEGER NOT NULL REFERENCES users(id),
    label INTEGER NOT NULL REFERENCES labels(id),
    axis TEXT NOT NULL CHECK (axis IN ('x', 'y', 'z')),
    slice INTEGER NOT NULL CHECK (slice >= 0),
    points TEXT NOT NULL,
    pressure TEXT,
    times_ms TEXT,
    duration_ms REAL,
    tool TEXT NOT NULL,
    client_id TEXT,
    created TEXT NOT NULL,
    updated TEXT NOT NULL
);
CREATE INDEX contours_by_slice ON contours (cell, user_id, label, axis, slice);
CREATE UNIQUE INDEX contours_client_id ON contours (user_id, client_id) WHERE client_id IS NOT NULL;
CREATE TABLE drawn_empty (
    cell TEXT NOT NULL REFERENCES cells(id),
    user_id INTEGER NOT NULL REFERENCES users(id),
    label INTEGER NOT NULL REFERENCES labels(id),
    axis TEXT NOT NULL CHECK (axis IN ('x', 'y', 'z')),
    slice INTEGER NOT NULL CHECK (slice >= 0),
    created TEXT NOT NULL,
    PRIMARY KEY (cell, user_id, label, axis, slice)
);
CREATE TABLE changes (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    cell TEXT NOT NULL REFERENCES cells(id),
    user_id INTEGER NOT NULL REFERENCES users(id),
    label INTEGER NOT NULL,
    axis TEXT NOT NULL,
    slice INTEGER NOT NULL,
    before TEXT NOT NULL,
    after TEXT NOT NULL,
    undone INTEGER NOT NULL DEFAULT 0
);
CREATE INDEX changes_by_user ON changes (cell, user_id, undone, id);
CREATE TABLE results (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    cell TEXT NOT NULL REFERENCES cells(id),
    user_id INTEGER NOT NULL REFERENCES users(id),
    label INTEGER NOT NULL,
    axis TEXT NOT NULL,
    method TEXT NOT NULL,
    geometry TEXT NOT NULL,
    voxels INTEGER NOT NULL,
    mask BLOB NOT NULL,
    created TEXT NOT NULL
);
CREATE TABLE time_spent (
    cell TEXT NOT NULL REFERENCES cells(id),
    user_id INTEGER NOT NULL REFERENCES users(id),
    seconds REAL NOT NULL,
    PRIMARY KEY (cell, user_id)
);
CREATE TABLE cell_status (
    cell TEXT NOT NULL REFERENCES cells(id),
    user_id INTEGER NOT NULL REFERENCES users(id),
    status TEXT NOT NULL CHECK (status IN ('not_started', 'in_progress', 'done')),
    updated TEXT NOT NULL,
    PRIMARY KEY (cell, user_id)
);
CREATE TABLE segmentations (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    cell TEXT NOT NULL REFERENCES cells(id),
    name TEXT NOT NULL,
    method TEXT NOT NULL,
    params TEXT NOT NULL,
    geometry TEXT NOT NULL,
    labels BLOB NOT NULL,
    created TEXT NOT NULL
);
CREATE TABLE ratings (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    cell TEXT NOT NULL REFERENCES cells(id),
    user_id INTEGER NOT NULL REFERENCES users(id),
    segmentation TEXT NOT NULL,
    score INTEGER NOT NULL CHECK (score BETWEEN 1 AND 5),
    comment TEXT NOT NULL,
    created TEXT NOT NULL
);
CREATE TABLE audit (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    at TEXT NOT NULL,
    user_id INTEGER,
    cell TEXT,
    action TEXT NOT NULL,
    detail TEXT NOT NULL
);
CREATE INDEX audit_by_cell_user ON audit (cell, user_id);
CREATE TRIGGER audit_no_update BEFORE UPDATE ON audit
    BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
CREATE TRIGGER audit_no_delete BEFORE DELETE ON audit
    BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
"#,
    // 2: the change and audit logs record per-contour deltas instead of whole
    // slices (see the file for how version-1 data is converted).
    include_str!("migrations/002_change_deltas.sql"),
    // 3: how a session was opened. A session opened by name alone (loopback)
    // is refused by a server that requires passwords; sessions from before
    // this column count as opened by name.
    r#"
ALTER TABLE sessions ADD COLUMN with_password INTEGER NOT NULL DEFAULT 0;
"#,
];

/// The first version whose change and audit logs hold deltas: migrating a
/// database from below it frees most of its pages (see [`migrate`]).
const DELTA_HISTORY: i64 = 2;

/// The schema version this program writes.
pub fn latest_version() -> i64 {
    MIGRATIONS.len() as i64
}

/// Bring `conn` to the latest version; each migration runs in its own transaction.
///
/// Converting the whole-slice history of a version-1 database frees most of
/// its pages; a VACUUM then returns them to the file system (once, after the
/// migrations, outside their transactions as SQLite requires).
pub fn migrate(conn: &mut Connection) -> Result<()> {
    let current: i64 = conn.query_row("PRAGMA user_version", [], |r| r.get(0))?;
    if current > latest_version() {
        return Err(StoreError::TooNew {
            found: current,
            known: latest_version(),
        });
    }
    for (n, sql) in MIGRATIONS.iter().enumerate().skip(current as usize) {
        let tx = conn.transaction()?;
        tx.execute_batch(sql)?;
        tx.pragma_update(None, "user_version", (n + 1) as i64)?;
        tx.commit()?;
    }
    if (1..DELTA_HISTORY).contains(&current) {
        conn.execute_batch("VACUUM")?;
    }
    Ok(())
}
