//! The [`Store`]: a SQLite connection behind a mutex, with typed operations.
//!
//! Every public write runs in one transaction together with its audit entry,
//! so the database never holds half a change.
use crate::codec;
use crate::migrations;
use crate::model::*;
use crate::{Result, StoreError, now_rfc3339};
use argon2::Argon2;
use argon2::password_hash::{PasswordHash, PasswordHasher, PasswordVerifier, SaltString};
use interslice_core::{Axis, Geometry, LabelVolume, Mask, Volume};
use rand::RngCore;
use rusqlite::{Connection, OptionalExtension, Transaction, params};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;

/// How long a login session lasts without use.
const SESSION_SECONDS: i64 = 30 * 24 * 3600;

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

/// Copies the WAL back into the database file on its own thread and
/// connection, so that no request pays for a checkpoint (SQLite's automatic
/// checkpoint runs inside the commit that crosses 1000 pages, and with its
/// fsyncs it was the whole p99 of a contour save).
struct Checkpointer {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Checkpointer {
    /// How often the WAL is checkpointed.
    const PERIOD: Duration = Duration::from_millis(500);

    fn start(path: &Path) -> Result<Checkpointer> {
        use std::sync::atomic::{AtomicBool, Ordering};
        let conn = Connection::open(path)?;
        conn.busy_timeout(Duration::from_secs(10))?;
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("sqlite-checkpoint".into())
            .spawn(move || {
                while !flag.load(Ordering::Acquire) {
                    std::thread::park_timeout(Self::PERIOD);
                    // PASSIVE never waits for readers or the writer; a busy
                    // or failed round is simply retried on the next tick.
                    let _ = conn.query_row("PRAGMA wal_checkpoint(PASSIVE)", [], |_| Ok(()));
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

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Store")
            .field("path", &self.path)
            .field("background_checkpoints", &self.checkpointer.is_some())
            .finish()
    }
}

/// The state of one label on one slice, as kept for undo/redo.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct SliceState {
    empty: bool,
    contours: Vec<StoredContour>,
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

/// Check a user-supplied contour: enough finite points, matching per-point arrays.
pub(crate) fn validate_contour(c: &NewContour) -> Result<()> {
    if c.points.len() < 3 {
        return Err(StoreError::Invalid(format!(
            "a contour needs at least 3 points, got {}",
            c.points.len()
        )));
    }
    if c.points.len() > 1_000_000 {
        return Err(StoreError::Invalid(
            "a contour may have at most 1000000 points".into(),
        ));
    }
    if c.points
        .iter()
        .any(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(StoreError::Invalid(
            "contour points must be finite numbers".into(),
        ));
    }
    if let Some(p) = &c.pressure {
        if p.len() != c.points.len() {
            return Err(StoreError::Invalid(format!(
                "pressure has {} values for {} points",
                p.len(),
                c.points.len()
            )));
        }
        if p.iter().any(|x| !x.is_finite()) {
            return Err(StoreError::Invalid("pressure values must be finite".into()));
        }
    }
    if let Some(t) = &c.times_ms {
        if t.len() != c.points.len() {
            return Err(StoreError::Invalid(format!(
                "times_ms has {} values for {} points",
                t.len(),
                c.points.len()
            )));
        }
        if t.iter().any(|x| !x.is_finite()) {
            return Err(StoreError::Invalid("times_ms values must be finite".into()));
        }
    }
    if let Some(d) = c.duration_ms
        && !(d.is_finite() && (0.0..=86_400_000.0).contains(&d))
    {
        return Err(StoreError::Invalid(
            "duration_ms must be between 0 and 86400000".into(),
        ));
    }
    if let Some(tool) = &c.tool
        && tool.len() > 64
    {
        return Err(StoreError::Invalid(
            "tool name is longer than 64 characters".into(),
        ));
    }
    Ok(())
}

/// Check a user name: 1..=64 printable characters, no leading/trailing space.
fn validate_name(name: &str) -> Result<()> {
    if name.is_empty() || name.chars().count() > 64 || name.trim() != name {
        return Err(StoreError::Invalid(
            "a user name has 1 to 64 characters and no surrounding spaces".into(),
        ));
    }
    // "consensus" names the combined tracing of all users in exports.
    if name.eq_ignore_ascii_case(crate::CONSENSUS) {
        return Err(StoreError::Invalid(format!(
            "'{name}' is reserved (it names the consensus of all users)"
        )));
    }
    if name
        .chars()
        .any(|c| c.is_control() || c == '/' || c == '\\')
    {
        return Err(StoreError::Invalid(
            "a user name may not contain control characters or slashes".into(),
        ));
    }
    Ok(())
}

const CONTOUR_COLUMNS: &str = "c.id, c.cell, c.label, c.axis, c.slice, c.points, c.pressure, \
     c.times_ms, c.duration_ms, c.tool, u.name, c.user_id, c.client_id, c.created, c.updated";

fn contour_from_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<StoredContour> {
    let points: String = r.get(5)?;
    let pressure: Option<String> = r.get(6)?;
    let times: Option<String> = r.get(7)?;
    Ok(StoredContour {
        id: r.get(0)?,
        cell: r.get(1)?,
        label: r.get(2)?,
        axis: parse_axis(&r.get::<_, String>(3)?)?,
        index: r.get::<_, i64>(4)? as usize,
        points: serde_json::from_str(&points).map_err(json_err)?,
        pressure: pressure
            .map(|p| serde_json::from_str(&p))
            .transpose()
            .map_err(json_err)?,
        times_ms: times
            .map(|p| serde_json::from_str(&p))
            .transpose()
            .map_err(json_err)?,
        duration_ms: r.get(8)?,
        tool: r.get(9)?,
        author: r.get(10)?,
        user_id: r.get(11)?,
        client_id: r.get(12)?,
        created: r.get(13)?,
        updated: r.get(14)?,
    })
}

fn user_from_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<User> {
    let role: String = r.get(2)?;
    Ok(User {
        id: r.get(0)?,
        name: r.get(1)?,
        role: Role::parse(&role).unwrap_or(Role::Tracer),
        has_password: r.get::<_, Option<String>>(3)?.is_some(),
    })
}

fn audit(
    tx: &Transaction<'_>,
    user_id: Option<i64>,
    cell: Option<&str>,
    action: &str,
    detail: serde_json::Value,
) -> Result<()> {
    tx.prepare_cached(
        "INSERT INTO audit (at, user_id, cell, action, detail) VALUES (?1, ?2, ?3, ?4, ?5)",
    )?
    .execute(params![
        now_rfc3339(),
        user_id,
        cell,
        action,
        detail.to_string()
    ])?;
    Ok(())
}

fn slice_contours(tx: &Transaction<'_>, key: &SliceKey) -> Result<Vec<StoredContour>> {
    let sql = format!(
        "SELECT {CONTOUR_COLUMNS} FROM contours c JOIN users u ON u.id = c.user_id \
         WHERE c.cell = ?1 AND c.user_id = ?2 AND c.label = ?3 AND c.axis = ?4 AND c.slice = ?5 \
         ORDER BY c.id"
    );
    let mut st = tx.prepare_cached(&sql)?;
    let rows = st.query_map(
        params![
            key.cell,
            key.user_id,
            key.label,
            axis_str(key.axis),
            key.index as i64
        ],
        contour_from_row,
    )?;
    Ok(rows.collect::<rusqlite::Result<Vec<_>>>()?)
}

fn slice_state(tx: &Transaction<'_>, key: &SliceKey) -> Result<SliceState> {
    let contours = slice_contours(tx, key)?;
    let empty = tx
        .prepare_cached(
            "SELECT 1 FROM drawn_empty WHERE cell = ?1 AND user_id = ?2 AND label = ?3 \
             AND axis = ?4 AND slice = ?5",
        )?
        .exists(params![
            key.cell,
            key.user_id,
            key.label,
            axis_str(key.axis),
            key.index as i64
        ])?;
    Ok(SliceState { empty, contours })
}

/// Overwrite the slice with `state`, keeping contour ids (ids are AUTOINCREMENT,
/// so an id freed by a delete is never reused by another contour).
fn apply_state(tx: &Transaction<'_>, key: &SliceKey, state: &SliceState) -> Result<()> {
    let k = params![
        key.cell,
        key.user_id,
        key.label,
        axis_str(key.axis),
        key.index as i64
    ];
    tx.prepare_cached(
        "DELETE FROM contours WHERE cell = ?1 AND user_id = ?2 AND label = ?3 AND axis = ?4 \
         AND slice = ?5",
    )?
    .execute(k)?;
    tx.prepare_cached(
        "DELETE FROM drawn_empty WHERE cell = ?1 AND user_id = ?2 AND label = ?3 AND axis = ?4 \
         AND slice = ?5",
    )?
    .execute(k)?;
    if state.empty {
        tx.prepare_cached(
            "INSERT INTO drawn_empty (cell, user_id, label, axis, slice, created) \
             VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
        )?
        .execute(params![
            key.cell,
            key.user_id,
            key.label,
            axis_str(key.axis),
            key.index as i64,
            now_rfc3339()
        ])?;
    }
    for c in &state.contours {
        insert_contour_row(tx, key, Some(c.id), c)?;
    }
    Ok(())
}

fn insert_contour_row(
    tx: &Transaction<'_>,
    key: &SliceKey,
    id: Option<i64>,
    c: &StoredContour,
) -> Result<i64> {
    let mut st = tx.prepare_cached(
        "INSERT INTO contours (id, cell, user_id, label, axis, slice, points, pressure, \
         times_ms, duration_ms, tool, client_id, created, updated) \
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14)",
    )?;
    st.execute(params![
        id,
        key.cell,
        key.user_id,
        key.label,
        axis_str(key.axis),
        key.index as i64,
        serde_json::to_string(&c.points).expect("points serialise"),
        c.pressure
            .as_ref()
            .map(|p| serde_json::to_string(p).expect("serialise")),
        c.times_ms
            .as_ref()
            .map(|p| serde_json::to_string(p).expect("serialise")),
        c.duration_ms,
        c.tool,
        c.client_id,
        c.created,
        c.updated,
    ])?;
    Ok(tx.last_insert_rowid())
}

fn stored_from_new(key: &SliceKey, c: NewContour, client_id: Option<String>) -> StoredContour {
    let now = now_rfc3339();
    // The client's measured drawing time wins; otherwise the last per-point time.
    let duration_ms = c.duration_ms.or_else(|| {
        c.times_ms.as_ref().and_then(|t| {
            t.iter()
                .cloned()
                .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))))
        })
    });
    StoredContour {
        id: 0,
        cell: key.cell.clone(),
        label: key.label,
        axis: key.axis,
        index: key.index,
        points: c.points,
        pressure: c.pressure,
        times_ms: c.times_ms,
        duration_ms,
        tool: c.tool.unwrap_or_else(|| "pen".to_string()),
        author: String::new(),
        user_id: key.user_id,
        client_id,
        created: now.clone(),
        updated: now,
    }
}

/// Record a change for undo (dropping the redo stack) and in the audit log.
fn record_change(
    tx: &Transaction<'_>,
    key: &SliceKey,
    action: &str,
    before: &SliceState,
    after: &SliceState,
) -> Result<()> {
    tx.prepare_cached("DELETE FROM changes WHERE cell = ?1 AND user_id = ?2 AND undone = 1")?
        .execute(params![key.cell, key.user_id])?;
    let before_s = serde_json::to_string(before).expect("serialise");
    let after_s = serde_json::to_string(after).expect("serialise");
    tx.prepare_cached(
        "INSERT INTO changes (cell, user_id, label, axis, slice, before, after) \
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
    )?
    .execute(params![
        key.cell,
        key.user_id,
        key.label,
        axis_str(key.axis),
        key.index as i64,
        before_s,
        after_s
    ])?;
    audit(
        tx,
        Some(key.user_id),
        Some(&key.cell),
        action,
        serde_json::json!({
            "label": key.label, "axis": axis_str(key.axis), "index": key.index,
            "before": before, "after": after,
        }),
    )
}

/// Mark the cell in progress for the user unless it has a status already.
fn touch_status(tx: &Transaction<'_>, cell: &str, user_id: i64) -> Result<()> {
    tx.prepare_cached(
        "INSERT OR IGNORE INTO cell_status (cell, user_id, status, updated) \
         VALUES (?1, ?2, 'in_progress', ?3)",
    )?
    .execute(params![cell, user_id, now_rfc3339()])?;
    Ok(())
}

impl Store {
    /// Open (creating if needed) the database at `path`: WAL, foreign keys,
    /// migrations to the latest version.
    pub fn open(path: &Path) -> Result<Store> {
        if let Some(parent) = path.parent()
            && !parent.as_os_str().is_empty()
        {
            std::fs::create_dir_all(parent).map_err(|source| StoreError::Io {
                path: parent.display().to_string(),
                source,
            })?;
        }
        let conn = Connection::open(path)?;
        Self::init(conn, Some(path.to_path_buf()))
    }

    /// A private in-memory database (tests, throw-away runs).
    pub fn open_in_memory() -> Result<Store> {
        Self::init(Connection::open_in_memory()?, None)
    }

    fn init(mut conn: Connection, path: Option<PathBuf>) -> Result<Store> {
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
                Some(Checkpointer::start(p)?)
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

    /// The schema version of the open database.
    pub fn schema_version(&self) -> Result<i64> {
        Ok(self
            .lock()
            .query_row("PRAGMA user_version", [], |r| r.get(0))?)
    }

    // ---------------------------------------------------------------- users

    /// The user called `name`, if any.
    pub fn user(&self, name: &str) -> Result<Option<User>> {
        self.read(|tx| {
            Ok(tx
                .prepare_cached("SELECT id, name, role, password_hash FROM users WHERE name = ?1")?
                .query_row([name], user_from_row)
                .optional()?)
        })
    }

    /// Every user, by name.
    pub fn users(&self) -> Result<Vec<User>> {
        self.read(|tx| {
            let mut st =
                tx.prepare_cached("SELECT id, name, role, password_hash FROM users ORDER BY name")?;
            let rows = st.query_map([], user_from_row)?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// Create a user, or update the role and password of an existing one.
    /// The password is stored as an argon2id hash.
    pub fn upsert_user(&self, name: &str, role: Role, password: Option<&str>) -> Result<User> {
        validate_name(name)?;
        let hash = match password {
            Some("") => {
                return Err(StoreError::Invalid("the password is empty".into()));
            }
            Some(p) => {
                let salt = SaltString::generate(&mut argon2::password_hash::rand_core::OsRng);
                Some(
                    Argon2::default()
                        .hash_password(p.as_bytes(), &salt)
                        .map_err(|e| StoreError::Invalid(format!("cannot hash password: {e}")))?
                        .to_string(),
                )
            }
            None => None,
        };
        self.write(|tx| {
            tx.prepare_cached(
                "INSERT INTO users (name, role, password_hash, created) VALUES (?1, ?2, ?3, ?4) \
                 ON CONFLICT(name) DO UPDATE SET role = excluded.role, \
                 password_hash = COALESCE(excluded.password_hash, users.password_hash)",
            )?
            .execute(params![name, role.as_str(), hash, now_rfc3339()])?;
            let user = tx
                .prepare_cached("SELECT id, name, role, password_hash FROM users WHERE name = ?1")?
                .query_row([name], user_from_row)?;
            audit(
                tx,
                Some(user.id),
                None,
                "user.upsert",
                serde_json::json!({"name": name, "role": role.as_str(), "password_set": password.is_some()}),
            )?;
            Ok(user)
        })
    }

    /// The user called `name`, created as a tracer without password if missing
    /// (the loopback login, where a name is enough).
    pub fn ensure_user(&self, name: &str) -> Result<User> {
        validate_name(name)?;
        if let Some(u) = self.user(name)? {
            return Ok(u);
        }
        self.write(|tx| {
            tx.prepare_cached(
                "INSERT OR IGNORE INTO users (name, role, created) VALUES (?1, 'tracer', ?2)",
            )?
            .execute(params![name, now_rfc3339()])?;
            let user = tx
                .prepare_cached("SELECT id, name, role, password_hash FROM users WHERE name = ?1")?
                .query_row([name], user_from_row)?;
            audit(
                tx,
                Some(user.id),
                None,
                "user.create",
                serde_json::json!({"name": name}),
            )?;
            Ok(user)
        })
    }

    /// Check a password; `BadCredentials` for an unknown user, a user without a
    /// password, or a wrong password (one message for all three).
    pub fn verify_password(&self, name: &str, password: &str) -> Result<User> {
        let row: Option<(User, Option<String>)> = self.read(|tx| {
            Ok(tx
                .prepare_cached("SELECT id, name, role, password_hash FROM users WHERE name = ?1")?
                .query_row([name], |r| Ok((user_from_row(r)?, r.get(3)?)))
                .optional()?)
        })?;
        let Some((user, Some(hash))) = row else {
            return Err(StoreError::BadCredentials);
        };
        let parsed = PasswordHash::new(&hash).map_err(|e| StoreError::Corrupt(e.to_string()))?;
        Argon2::default()
            .verify_password(password.as_bytes(), &parsed)
            .map_err(|_| StoreError::BadCredentials)?;
        Ok(user)
    }

    /// Start a login session, opened with a password or by name alone;
    /// returns its random token (256 bits, hex).
    pub fn create_session(&self, user_id: i64, with_password: bool) -> Result<String> {
        let mut bytes = [0u8; 32];
        rand::rngs::OsRng.fill_bytes(&mut bytes);
        let token: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
        self.write(|tx| {
            tx.prepare_cached("DELETE FROM sessions WHERE expires_unix < ?1")?
                .execute([unix_now()])?;
            tx.prepare_cached(
                "INSERT INTO sessions (token, user_id, created, expires_unix, with_password) \
                 VALUES (?1, ?2, ?3, ?4, ?5)",
            )?
            .execute(params![
                token,
                user_id,
                now_rfc3339(),
                unix_now() + SESSION_SECONDS,
                with_password
            ])?;
            audit(tx, Some(user_id), None, "login", serde_json::json!({}))?;
            Ok(token)
        })
    }

    /// The user of a live session token, and whether a password opened it.
    pub fn session_user(&self, token: &str) -> Result<Option<(User, bool)>> {
        self.read(|tx| {
            Ok(tx
                .prepare_cached(
                    "SELECT u.id, u.name, u.role, u.password_hash, s.with_password FROM sessions s \
                     JOIN users u ON u.id = s.user_id WHERE s.token = ?1 AND s.expires_unix >= ?2",
                )?
                .query_row(params![token, unix_now()], |r| {
                    Ok((user_from_row(r)?, r.get(4)?))
                })
                .optional()?)
        })
    }

    /// End a session (no error if it does not exist).
    pub fn delete_session(&self, token: &str) -> Result<()> {
        self.write(|tx| {
            tx.prepare_cached("DELETE FROM sessions WHERE token = ?1")?
                .execute([token])?;
            Ok(())
        })
    }

    // ---------------------------------------------------------------- cells

    /// Register a cell found in the project folder (or update its path).
    pub fn upsert_cell(&self, id: &str, path: &str) -> Result<()> {
        self.write(|tx| {
            tx.prepare_cached(
                "INSERT INTO cells (id, path, updated) VALUES (?1, ?2, ?3) \
                 ON CONFLICT(id) DO UPDATE SET path = excluded.path",
            )?
            .execute(params![id, path, now_rfc3339()])?;
            Ok(())
        })
    }

    /// Record what a cell's volume is once read; returns the previous content
    /// hash when it differs (the file changed under existing tracings).
    pub fn set_cell_content(
        &self,
        id: &str,
        content_hash: &str,
        geometry: &Geometry,
        dtype: &str,
    ) -> Result<Option<String>> {
        let geometry = serde_json::to_string(geometry).expect("geometry serialises");
        self.write(|tx| {
            let old: Option<Option<String>> = tx
                .prepare_cached("SELECT content_hash FROM cells WHERE id = ?1")?
                .query_row([id], |r| r.get(0))
                .optional()?;
            let Some(old) = old else {
                return Err(StoreError::NotFound(format!("unknown cell '{id}'")));
            };
            tx.prepare_cached(
                "UPDATE cells SET content_hash = ?2, geometry = ?3, dtype = ?4, updated = ?5 \
                 WHERE id = ?1",
            )?
            .execute(params![id, content_hash, geometry, dtype, now_rfc3339()])?;
            Ok(old.filter(|o| o != content_hash))
        })
    }

    /// A registered cell.
    pub fn cell(&self, id: &str) -> Result<Option<CellRecord>> {
        self.read(|tx| {
            Ok(tx
                .prepare_cached(
                    "SELECT id, path, content_hash, geometry, dtype FROM cells WHERE id = ?1",
                )?
                .query_row([id], |r| {
                    Ok(CellRecord {
                        id: r.get(0)?,
                        path: r.get(1)?,
                        content_hash: r.get(2)?,
                        geometry: r.get(3)?,
                        dtype: r.get(4)?,
                    })
                })
                .optional()?)
        })
    }

    /// The status of every cell the user has one for.
    pub fn statuses(&self, user_id: i64) -> Result<HashMap<String, CellStatus>> {
        self.read(|tx| {
            let mut st =
                tx.prepare_cached("SELECT cell, status FROM cell_status WHERE user_id = ?1")?;
            let rows = st.query_map([user_id], |r| {
                Ok((r.get::<_, String>(0)?, r.get::<_, String>(1)?))
            })?;
            let mut out = HashMap::new();
            for row in rows {
                let (cell, s) = row?;
                out.insert(
                    cell,
                    CellStatus::parse(&s).unwrap_or(CellStatus::NotStarted),
                );
            }
            Ok(out)
        })
    }

    /// Every user's progress on every cell they touched (a status, time or a
    /// contour), by cell then user; only `user_id`'s rows when given.
    pub fn progress(&self, user_id: Option<i64>) -> Result<Vec<Progress>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached(
                "SELECT c.id, u.name, cs.status, COALESCE(ts.seconds, 0), \
                 (SELECT COUNT(*) FROM contours k WHERE k.cell = c.id AND k.user_id = u.id) AS n \
                 FROM cells c CROSS JOIN users u \
                 LEFT JOIN cell_status cs ON cs.cell = c.id AND cs.user_id = u.id \
                 LEFT JOIN time_spent ts ON ts.cell = c.id AND ts.user_id = u.id \
                 WHERE (?1 IS NULL OR u.id = ?1) \
                 AND (cs.status IS NOT NULL OR ts.seconds IS NOT NULL OR n > 0) \
                 ORDER BY c.id, u.name",
            )?;
            let rows = st.query_map([user_id], |r| {
                Ok(Progress {
                    cell: r.get(0)?,
                    user: r.get(1)?,
                    status: r
                        .get::<_, Option<String>>(2)?
                        .as_deref()
                        .and_then(CellStatus::parse)
                        .unwrap_or(CellStatus::NotStarted),
                    seconds: r.get(3)?,
                    contours: r.get::<_, i64>(4)? as u64,
                })
            })?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// Set a cell's status for the user.
    pub fn set_status(&self, cell: &str, user_id: i64, status: CellStatus) -> Result<()> {
        self.write(|tx| {
            tx.prepare_cached(
                "INSERT INTO cell_status (cell, user_id, status, updated) VALUES (?1, ?2, ?3, ?4) \
                 ON CONFLICT(cell, user_id) DO UPDATE SET status = excluded.status, \
                 updated = excluded.updated",
            )?
            .execute(params![cell, user_id, status.as_str(), now_rfc3339()])?;
            audit(
                tx,
                Some(user_id),
                Some(cell),
                "cell.status",
                serde_json::json!({"status": status.as_str()}),
            )
        })
    }

    /// Add tracing time (seconds ≥ 0) to the user's total on a cell; returns the total.
    pub fn add_time(&self, cell: &str, user_id: i64, seconds: f64) -> Result<f64> {
        if !(seconds.is_finite() && (0.0..=86_400.0).contains(&seconds)) {
            return Err(StoreError::Invalid(
                "seconds must be between 0 and 86400".into(),
            ));
        }
        self.write(|tx| {
            tx.prepare_cached(
                "INSERT INTO time_spent (cell, user_id, seconds) VALUES (?1, ?2, ?3) \
                 ON CONFLICT(cell, user_id) DO UPDATE SET seconds = seconds + excluded.seconds",
            )?
            .execute(params![cell, user_id, seconds])?;
            Ok(tx
                .prepare_cached("SELECT seconds FROM time_spent WHERE cell = ?1 AND user_id = ?2")?
                .query_row(params![cell, user_id], |r| r.get(0))?)
        })
    }

    /// The user's total tracing time on a cell, in seconds.
    pub fn time_spent(&self, cell: &str, user_id: i64) -> Result<f64> {
        self.read(|tx| {
            Ok(tx
                .prepare_cached("SELECT seconds FROM time_spent WHERE cell = ?1 AND user_id = ?2")?
                .query_row(params![cell, user_id], |r| r.get(0))
                .optional()?
                .unwrap_or(0.0))
        })
    }

    // ---------------------------------------------------------------- labels

    /// The project's labels, by id.
    pub fn labels(&self) -> Result<Vec<Label>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached("SELECT id, name, color FROM labels ORDER BY id")?;
            let rows = st.query_map([], |r| {
                Ok(Label {
                    id: r.get(0)?,
                    name: r.get(1)?,
                    color: r.get(2)?,
                })
            })?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// Add a label with the next free id; `color` is `#rrggbb` (a palette colour if `None`).
    pub fn add_label(
        &self,
        name: &str,
        color: Option<&str>,
        user_id: Option<i64>,
    ) -> Result<Label> {
        let name = name.trim();
        if name.is_empty() || name.chars().count() > 64 {
            return Err(StoreError::Invalid(
                "a label name has 1 to 64 characters".into(),
            ));
        }
        if let Some(c) = color
            && !(c.len() == 7
                && c.starts_with('#')
                && c[1..].chars().all(|ch| ch.is_ascii_hexdigit()))
        {
            return Err(StoreError::Invalid(format!("colour '{c}' is not #rrggbb")));
        }
        const PALETTE: [&str; 8] = [
            "#911eb4", "#42d4f4", "#f032e6", "#bfef45", "#fabed4", "#469990", "#dcbeff", "#9a6324",
        ];
        self.write(|tx| {
            let exists = tx
                .prepare_cached("SELECT 1 FROM labels WHERE name = ?1")?
                .exists([name])?;
            if exists {
                return Err(StoreError::Invalid(format!(
                    "label '{name}' exists already"
                )));
            }
            let id: i64 = tx.query_row("SELECT COALESCE(MAX(id), 0) + 1 FROM labels", [], |r| {
                r.get(0)
            })?;
            if id > 65535 {
                return Err(StoreError::Invalid("no label ids left".into()));
            }
            let color = color
                .map(str::to_ascii_lowercase)
                .unwrap_or_else(|| PALETTE[(id as usize) % PALETTE.len()].to_string());
            tx.prepare_cached("INSERT INTO labels (id, name, color) VALUES (?1, ?2, ?3)")?
                .execute(params![id, name, color])?;
            audit(
                tx,
                user_id,
                None,
                "label.add",
                serde_json::json!({"id": id, "name": name, "color": color}),
            )?;
            Ok(Label {
                id: id as u16,
                name: name.to_string(),
                color,
            })
        })
    }

    fn check_label(tx: &Transaction<'_>, label: u16) -> Result<()> {
        if !tx
            .prepare_cached("SELECT 1 FROM labels WHERE id = ?1")?
            .exists([label])?
        {
            return Err(StoreError::Invalid(format!("unknown label {label}")));
        }
        Ok(())
    }

    fn check_cell(tx: &Transaction<'_>, cell: &str) -> Result<()> {
        if !tx
            .prepare_cached("SELECT 1 FROM cells WHERE id = ?1")?
            .exists([cell])?
        {
            return Err(StoreError::NotFound(format!("unknown cell '{cell}'")));
        }
        Ok(())
    }

    // ---------------------------------------------------------------- contours

    /// Contours of one author on one cell, optionally narrowed, ordered by slice then id.
    pub fn contours(&self, q: &ContourQuery) -> Result<Vec<StoredContour>> {
        self.read(|tx| {
            let sql = format!(
                "SELECT {CONTOUR_COLUMNS} FROM contours c JOIN users u ON u.id = c.user_id \
                 WHERE c.cell = ?1 AND c.user_id = ?2 AND (?3 IS NULL OR c.axis = ?3) \
                 AND (?4 IS NULL OR c.slice = ?4) AND (?5 IS NULL OR c.label = ?5) \
                 ORDER BY c.axis, c.slice, c.label, c.id"
            );
            let mut st = tx.prepare_cached(&sql)?;
            let rows = st.query_map(
                params![
                    q.cell,
                    q.user_id,
                    q.axis.map(axis_str),
                    q.index.map(|i| i as i64),
                    q.label
                ],
                contour_from_row,
            )?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// One contour by id.
    pub fn contour(&self, id: i64) -> Result<Option<StoredContour>> {
        self.read(|tx| {
            let sql = format!(
                "SELECT {CONTOUR_COLUMNS} FROM contours c JOIN users u ON u.id = c.user_id \
                 WHERE c.id = ?1"
            );
            Ok(tx
                .prepare_cached(&sql)?
                .query_row([id], contour_from_row)
                .optional()?)
        })
    }

    /// Add a contour on a slice (the slice stops being drawn-empty for its label).
    /// With a `client_id` the call is idempotent: a retry returns the stored
    /// contour instead of adding a second one. Returns the contour and whether
    /// it was created now.
    pub fn add_contour(
        &self,
        key: &SliceKey,
        contour: NewContour,
        client_id: Option<String>,
    ) -> Result<(StoredContour, bool)> {
        validate_contour(&contour)?;
        if let Some(c) = &client_id
            && (c.is_empty() || c.len() > 128)
        {
            return Err(StoreError::Invalid(
                "client_id has 1 to 128 characters".into(),
            ));
        }
        self.write(|tx| {
            Self::check_cell(tx, &key.cell)?;
            Self::check_label(tx, key.label)?;
            if let Some(cid) = &client_id {
                let sql = format!(
                    "SELECT {CONTOUR_COLUMNS} FROM contours c JOIN users u ON u.id = c.user_id \
                     WHERE c.user_id = ?1 AND c.client_id = ?2"
                );
                if let Some(existing) = tx
                    .prepare_cached(&sql)?
                    .query_row(params![key.user_id, cid], contour_from_row)
                    .optional()?
                {
                    return Ok((existing, false));
                }
            }
            let before = slice_state(tx, key)?;
            let mut stored = stored_from_new(key, contour, client_id);
            tx.prepare_cached(
                "DELETE FROM drawn_empty WHERE cell = ?1 AND user_id = ?2 AND label = ?3 \
                 AND axis = ?4 AND slice = ?5",
            )?
            .execute(params![
                key.cell,
                key.user_id,
                key.label,
                axis_str(key.axis),
                key.index as i64
            ])?;
            stored.id = insert_contour_row(tx, key, None, &stored)?;
            let after = slice_state(tx, key)?;
            touch_status(tx, &key.cell, key.user_id)?;
            record_change(tx, key, "contour.add", &before, &after)?;
            let created = after
                .contours
                .into_iter()
                .find(|c| c.id == stored.id)
                .ok_or_else(|| StoreError::Corrupt("inserted contour vanished".into()))?;
            Ok((created, true))
        })
    }

    /// Replace the author's contours of one label on one slice. An empty list
    /// clears the slice (it is then no longer drawn, unless marked empty later).
    pub fn replace_slice(
        &self,
        key: &SliceKey,
        contours: Vec<NewContour>,
    ) -> Result<Vec<StoredContour>> {
        for c in &contours {
            validate_contour(c)?;
        }
        self.write(|tx| {
            Self::check_cell(tx, &key.cell)?;
            Self::check_label(tx, key.label)?;
            let before = slice_state(tx, key)?;
            let state = SliceState {
                empty: false,
                contours: vec![],
            };
            apply_state(tx, key, &state)?;
            for c in contours {
                let stored = stored_from_new(key, c, None);
                insert_contour_row(tx, key, None, &stored)?;
            }
            let after = slice_state(tx, key)?;
            touch_status(tx, &key.cell, key.user_id)?;
            record_change(tx, key, "slice.replace", &before, &after)?;
            Ok(after.contours)
        })
    }

    /// Delete one of the user's contours: `NotFound` if it does not exist,
    /// `Forbidden` if it is someone else's.
    pub fn delete_contour(&self, cell: &str, user_id: i64, id: i64) -> Result<()> {
        self.write(|tx| {
            let row: Option<(String, i64, u16, String, i64)> = tx
                .prepare_cached(
                    "SELECT cell, user_id, label, axis, slice FROM contours WHERE id = ?1",
                )?
                .query_row([id], |r| {
                    Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?, r.get(4)?))
                })
                .optional()?;
            let Some((c_cell, owner, label, axis, slice)) = row else {
                return Err(StoreError::NotFound(format!("no contour {id}")));
            };
            if c_cell != cell {
                return Err(StoreError::NotFound(format!(
                    "no contour {id} on cell '{cell}'"
                )));
            }
            if owner != user_id {
                return Err(StoreError::Forbidden(format!(
                    "contour {id} is another user's"
                )));
            }
            let key = SliceKey {
                cell: c_cell,
                user_id,
                label,
                axis: parse_axis(&axis)?,
                index: slice as usize,
            };
            let before = slice_state(tx, &key)?;
            tx.prepare_cached("DELETE FROM contours WHERE id = ?1")?
                .execute([id])?;
            let after = slice_state(tx, &key)?;
            record_change(tx, &key, "contour.delete", &before, &after)
        })
    }

    /// Mark a slice drawn with no contour of the label (removes its contours there).
    pub fn mark_empty(&self, key: &SliceKey) -> Result<()> {
        self.write(|tx| {
            Self::check_cell(tx, &key.cell)?;
            Self::check_label(tx, key.label)?;
            let before = slice_state(tx, key)?;
            apply_state(
                tx,
                key,
                &SliceState {
                    empty: true,
                    contours: vec![],
                },
            )?;
            let after = slice_state(tx, key)?;
            touch_status(tx, &key.cell, key.user_id)?;
            record_change(tx, key, "slice.empty", &before, &after)
        })
    }

    /// The drawn slices of a label along an axis: those with contours and those
    /// marked empty, ascending.
    pub fn drawn(
        &self,
        cell: &str,
        user_id: i64,
        label: u16,
        axis: Axis,
    ) -> Result<Vec<DrawnSlice>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached(
                "SELECT slice, 0 FROM contours WHERE cell = ?1 AND user_id = ?2 AND label = ?3 AND axis = ?4 \
                 UNION SELECT slice, 1 FROM drawn_empty WHERE cell = ?1 AND user_id = ?2 AND label = ?3 AND axis = ?4 \
                 ORDER BY 1",
            )?;
            let rows = st.query_map(params![cell, user_id, label, axis_str(axis)], |r| {
                Ok(DrawnSlice {
                    index: r.get::<_, i64>(0)? as usize,
                    empty: r.get::<_, i64>(1)? == 1,
                })
            })?;
            let mut out: Vec<DrawnSlice> = Vec::new();
            for row in rows {
                let d = row?;
                // A slice cannot be both, but be safe: contours win.
                if out.last().is_some_and(|l| l.index == d.index) {
                    continue;
                }
                out.push(d);
            }
            Ok(out)
        })
    }

    /// The (label, axis) pairs the user has drawn anything for on a cell, with
    /// the number of drawn slices.
    pub fn drawn_labels(&self, cell: &str, user_id: i64) -> Result<Vec<(u16, Axis, usize)>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached(
                "SELECT label, axis, COUNT(DISTINCT slice) FROM ( \
                 SELECT label, axis, slice FROM contours WHERE cell = ?1 AND user_id = ?2 \
                 UNION SELECT label, axis, slice FROM drawn_empty WHERE cell = ?1 AND user_id = ?2) \
                 GROUP BY label, axis ORDER BY label, axis",
            )?;
            let rows = st.query_map(params![cell, user_id], |r| {
                Ok((r.get::<_, u16>(0)?, parse_axis(&r.get::<_, String>(1)?)?, r.get::<_, i64>(2)? as usize))
            })?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// Users who drew anything on a cell.
    pub fn tracers_of(&self, cell: &str) -> Result<Vec<User>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached(
                "SELECT id, name, role, password_hash FROM users WHERE id IN ( \
                 SELECT user_id FROM contours WHERE cell = ?1 UNION \
                 SELECT user_id FROM drawn_empty WHERE cell = ?1) ORDER BY name",
            )?;
            let rows = st.query_map([cell], user_from_row)?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// Undo the user's last change on a cell.
    pub fn undo(&self, cell: &str, user_id: i64) -> Result<UndoOutcome> {
        self.undo_redo(cell, user_id, true)
    }

    /// Redo the user's last undone change on a cell.
    pub fn redo(&self, cell: &str, user_id: i64) -> Result<UndoOutcome> {
        self.undo_redo(cell, user_id, false)
    }

    fn undo_redo(&self, cell: &str, user_id: i64, undo: bool) -> Result<UndoOutcome> {
        self.write(|tx| {
            let sql = if undo {
                "SELECT id, label, axis, slice, before FROM changes \
                 WHERE cell = ?1 AND user_id = ?2 AND undone = 0 ORDER BY id DESC LIMIT 1"
            } else {
                "SELECT id, label, axis, slice, after FROM changes \
                 WHERE cell = ?1 AND user_id = ?2 AND undone = 1 ORDER BY id ASC LIMIT 1"
            };
            let row: Option<(i64, u16, String, i64, String)> = tx
                .prepare_cached(sql)?
                .query_row(params![cell, user_id], |r| {
                    Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?, r.get(4)?))
                })
                .optional()?;
            let Some((id, label, axis, slice, state)) = row else {
                return Ok(UndoOutcome {
                    changed: false,
                    slice: None,
                });
            };
            let axis = parse_axis(&axis)?;
            let key = SliceKey {
                cell: cell.to_string(),
                user_id,
                label,
                axis,
                index: slice as usize,
            };
            let state: SliceState =
                serde_json::from_str(&state).map_err(|e| StoreError::Corrupt(e.to_string()))?;
            let current = slice_state(tx, &key)?;
            apply_state(tx, &key, &state)?;
            tx.prepare_cached("UPDATE changes SET undone = ?2 WHERE id = ?1")?
                .execute(params![id, undo as i64])?;
            audit(
                tx,
                Some(user_id),
                Some(cell),
                if undo { "undo" } else { "redo" },
                serde_json::json!({"change": id, "label": label, "axis": axis_str(axis),
                    "index": slice, "before": current, "after": state}),
            )?;
            Ok(UndoOutcome {
                changed: true,
                slice: Some((label, axis, slice as usize)),
            })
        })
    }

    /// A number that grows with every change the user makes on a cell (the
    /// last audit entry): caches of interpolated results compare it.
    pub fn revision(&self, cell: &str, user_id: i64) -> Result<i64> {
        self.read(|tx| {
            Ok(tx
                .prepare_cached(
                    "SELECT COALESCE(MAX(id), 0) FROM audit WHERE cell = ?1 AND user_id = ?2",
                )?
                .query_row(params![cell, user_id], |r| r.get(0))?)
        })
    }

    // ---------------------------------------------------------------- results

    /// Store an interpolation result (mask bit-packed and compressed); returns its id.
    pub fn save_result(
        &self,
        cell: &str,
        user_id: i64,
        label: u16,
        axis: Axis,
        method: &str,
        mask: &Mask,
    ) -> Result<i64> {
        let geometry = serde_json::to_string(mask.geometry()).expect("geometry serialises");
        let voxels = mask.data().iter().filter(|&&b| b).count() as i64;
        let blob = codec::encode_mask(mask.data());
        self.write(|tx| {
            tx.prepare_cached(
                "INSERT INTO results (cell, user_id, label, axis, method, geometry, voxels, mask, created) \
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)",
            )?
            .execute(params![cell, user_id, label, axis_str(axis), method, geometry, voxels, blob, now_rfc3339()])?;
            let id = tx.last_insert_rowid();
            audit(tx, Some(user_id), Some(cell), "interpolate",
                serde_json::json!({"result": id, "label": label, "axis": axis_str(axis), "method": method, "voxels": voxels}))?;
            Ok(id)
        })
    }

    /// The stored interpolation results of a user on a cell, newest first.
    pub fn results(&self, cell: &str, user_id: i64) -> Result<Vec<ResultMeta>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached(
                "SELECT id, cell, user_id, label, axis, method, voxels, created FROM results \
                 WHERE cell = ?1 AND user_id = ?2 ORDER BY id DESC",
            )?;
            let rows = st.query_map(params![cell, user_id], |r| {
                Ok(ResultMeta {
                    id: r.get(0)?,
                    cell: r.get(1)?,
                    user_id: r.get(2)?,
                    label: r.get(3)?,
                    axis: parse_axis(&r.get::<_, String>(4)?)?,
                    method: r.get(5)?,
                    voxels: r.get::<_, i64>(6)? as u64,
                    created: r.get(7)?,
                })
            })?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// A stored interpolation result and its mask.
    pub fn result(&self, id: i64) -> Result<Option<(ResultMeta, Mask)>> {
        let row = self.read(|tx| {
            Ok(tx
                .prepare_cached(
                    "SELECT id, cell, user_id, label, axis, method, voxels, created, geometry, mask \
                     FROM results WHERE id = ?1",
                )?
                .query_row([id], |r| {
                    Ok((
                        ResultMeta {
                            id: r.get(0)?,
                            cell: r.get(1)?,
                            user_id: r.get(2)?,
                            label: r.get(3)?,
                            axis: parse_axis(&r.get::<_, String>(4)?)?,
                            method: r.get(5)?,
                            voxels: r.get::<_, i64>(6)? as u64,
                            created: r.get(7)?,
                        },
                        r.get::<_, String>(8)?,
                        r.get::<_, Vec<u8>>(9)?,
                    ))
                })
                .optional()?)
        })?;
        let Some((meta, geometry, blob)) = row else {
            return Ok(None);
        };
        let geometry: Geometry =
            serde_json::from_str(&geometry).map_err(|e| StoreError::Corrupt(e.to_string()))?;
        let data = codec::decode_mask(&blob, geometry.len())?;
        let mask =
            Volume::from_vec(geometry, data).map_err(|e| StoreError::Corrupt(e.to_string()))?;
        Ok(Some((meta, mask)))
    }

    // ---------------------------------------------------------------- segmentations

    /// Store an automated segmentation of a cell.
    pub fn save_segmentation(
        &self,
        cell: &str,
        name: &str,
        method: &str,
        params_json: &serde_json::Value,
        labels: &LabelVolume,
        user_id: Option<i64>,
    ) -> Result<SegmentationMeta> {
        let geometry = serde_json::to_string(labels.geometry()).expect("geometry serialises");
        let blob = codec::encode_labels(labels.data());
        self.write(|tx| {
            Self::check_cell(tx, cell)?;
            let created = now_rfc3339();
            tx.prepare_cached(
                "INSERT INTO segmentations (cell, name, method, params, geometry, labels, created) \
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
            )?
            .execute(params![
                cell,
                name,
                method,
                params_json.to_string(),
                geometry,
                blob,
                created
            ])?;
            let id = tx.last_insert_rowid();
            audit(
                tx,
                user_id,
                Some(cell),
                "segmentation.add",
                serde_json::json!({"id": id, "method": method, "params": params_json}),
            )?;
            Ok(SegmentationMeta {
                id,
                cell: cell.to_string(),
                name: name.to_string(),
                method: method.to_string(),
                params: params_json.clone(),
                created,
            })
        })
    }

    /// The stored segmentations of a cell.
    pub fn segmentations(&self, cell: &str) -> Result<Vec<SegmentationMeta>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached(
                "SELECT id, cell, name, method, params, created FROM segmentations WHERE cell = ?1 ORDER BY id",
            )?;
            let rows = st.query_map([cell], |r| {
                let p: String = r.get(4)?;
                Ok(SegmentationMeta {
                    id: r.get(0)?,
                    cell: r.get(1)?,
                    name: r.get(2)?,
                    method: r.get(3)?,
                    params: serde_json::from_str(&p).map_err(json_err)?,
                    created: r.get(5)?,
                })
            })?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// The label volume of a stored segmentation of `cell`.
    pub fn segmentation_volume(&self, cell: &str, id: i64) -> Result<Option<LabelVolume>> {
        let row: Option<(String, Vec<u8>)> = self.read(|tx| {
            Ok(tx
                .prepare_cached(
                    "SELECT geometry, labels FROM segmentations WHERE id = ?1 AND cell = ?2",
                )?
                .query_row(params![id, cell], |r| Ok((r.get(0)?, r.get(1)?)))
                .optional()?)
        })?;
        let Some((geometry, blob)) = row else {
            return Ok(None);
        };
        let geometry: Geometry =
            serde_json::from_str(&geometry).map_err(|e| StoreError::Corrupt(e.to_string()))?;
        let data = codec::decode_labels(&blob, geometry.len())?;
        Ok(Some(
            Volume::from_vec(geometry, data).map_err(|e| StoreError::Corrupt(e.to_string()))?,
        ))
    }

    /// Rate a segmentation (score 1..=5).
    pub fn add_rating(
        &self,
        cell: &str,
        user_id: i64,
        segmentation: &str,
        score: u8,
        comment: &str,
    ) -> Result<Rating> {
        if !(1..=5).contains(&score) {
            return Err(StoreError::Invalid("score must be 1 to 5".into()));
        }
        if comment.len() > 10_000 {
            return Err(StoreError::Invalid(
                "comment is longer than 10000 bytes".into(),
            ));
        }
        self.write(|tx| {
            Self::check_cell(tx, cell)?;
            let created = now_rfc3339();
            tx.prepare_cached(
                "INSERT INTO ratings (cell, user_id, segmentation, score, comment, created) \
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
            )?
            .execute(params![
                cell,
                user_id,
                segmentation,
                score,
                comment,
                created
            ])?;
            let id = tx.last_insert_rowid();
            let user: String =
                tx.query_row("SELECT name FROM users WHERE id = ?1", [user_id], |r| {
                    r.get(0)
                })?;
            audit(
                tx,
                Some(user_id),
                Some(cell),
                "rating.add",
                serde_json::json!({"id": id, "segmentation": segmentation, "score": score}),
            )?;
            Ok(Rating {
                id,
                cell: cell.to_string(),
                user,
                segmentation: segmentation.to_string(),
                score,
                comment: comment.to_string(),
                created,
            })
        })
    }

    /// Ratings of a cell's segmentations (all cells with `None`), oldest first.
    pub fn ratings(&self, cell: Option<&str>) -> Result<Vec<Rating>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached(
                "SELECT r.id, r.cell, u.name, r.segmentation, r.score, r.comment, r.created \
                 FROM ratings r JOIN users u ON u.id = r.user_id \
                 WHERE ?1 IS NULL OR r.cell = ?1 ORDER BY r.id",
            )?;
            let rows = st.query_map([cell], |r| {
                Ok(Rating {
                    id: r.get(0)?,
                    cell: r.get(1)?,
                    user: r.get(2)?,
                    segmentation: r.get(3)?,
                    score: r.get(4)?,
                    comment: r.get(5)?,
                    created: r.get(6)?,
                })
            })?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    // ---------------------------------------------------------------- audit

    /// The last `limit` audit entries, newest first.
    pub fn audit_log(&self, limit: usize) -> Result<Vec<AuditEntry>> {
        self.read(|tx| {
            let mut st = tx.prepare_cached(
                "SELECT a.id, a.at, u.name, a.cell, a.action, a.detail FROM audit a \
                 LEFT JOIN users u ON u.id = a.user_id ORDER BY a.id DESC LIMIT ?1",
            )?;
            let rows = st.query_map([limit as i64], |r| {
                let d: String = r.get(5)?;
                Ok(AuditEntry {
                    id: r.get(0)?,
                    at: r.get(1)?,
                    user: r.get(2)?,
                    cell: r.get(3)?,
                    action: r.get(4)?,
                    detail: serde_json::from_str(&d).map_err(json_err)?,
                })
            })?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }
}

#[cfg(test)]
mod tests;
