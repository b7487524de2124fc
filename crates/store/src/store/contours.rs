//! Contours and drawn-empty slices.
//!
//! A contour id names one content forever: ids are AUTOINCREMENT (never
//! reused) and a trigger refuses to update a contour row. A contour taken off
//! its slice (deleted, replaced, cleared, undone) is first copied into the
//! append-only `contour_archive`, so the change log and the audit log name
//! contours by id instead of copying them, and undo puts them back from there.
use super::cells::touch_status;
use super::changes::{Delta, record_change};
use super::users::user_from_row;
use super::{Store, axis_str, json_err, parse_axis};
use crate::model::*;
use crate::{Result, StoreError, now_rfc3339};
use interslice_core::{Axis, Contour, SliceRef};
use rusqlite::{OptionalExtension, Transaction, params};

/// The five columns of a slice key as SQL parameters `?1..?5`, in the order
/// of [`SLICE_WHERE`].
macro_rules! slice_params {
    ($key:expr $(, $extra:expr)*) => {
        params![
            $key.cell,
            $key.user_id,
            $key.label,
            axis_str($key.axis),
            $key.index as i64
            $(, $extra)*
        ]
    };
}
pub(super) use slice_params;

/// The rows of one label on one slice of one user's tracing.
const SLICE_WHERE: &str = "cell = ?1 AND user_id = ?2 AND label = ?3 AND axis = ?4 AND slice = ?5";

/// The columns of a contour row, shared by `contours` and `contour_archive`.
const ROW_COLUMNS: &str = "id, cell, user_id, label, axis, slice, points, pressure, times_ms, \
     duration_ms, tool, client_id, created, updated";

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

const CONTOUR_COLUMNS: &str = "c.id, c.cell, c.label, c.axis, c.slice, c.points, c.pressure, \
     c.times_ms, c.duration_ms, c.tool, u.name, c.user_id, c.client_id, c.created, c.updated";

fn contour_from_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<StoredContour> {
    let points: String = r.get(5)?;
    let pressure: Option<String> = r.get(6)?;
    let times: Option<String> = r.get(7)?;
    Ok(StoredContour {
        id: r.get(0)?,
        cell: r.get(1)?,
        contour: Contour {
            slice: SliceRef {
                axis: parse_axis(&r.get::<_, String>(3)?)?,
                index: r.get::<_, i64>(4)? as usize,
            },
            label: r.get(2)?,
            points: serde_json::from_str(&points).map_err(json_err)?,
            author: r.get(10)?,
            created: r.get(13)?,
            pressure: pressure
                .map(|p| serde_json::from_str(&p))
                .transpose()
                .map_err(json_err)?,
            times_ms: times
                .map(|p| serde_json::from_str(&p))
                .transpose()
                .map_err(json_err)?,
            tool: Some(r.get(9)?),
        },
        duration_ms: r.get(8)?,
        user_id: r.get(11)?,
        client_id: r.get(12)?,
        updated: r.get(14)?,
    })
}

/// The live contours of a slice, oldest first.
fn slice_contours(tx: &Transaction<'_>, key: &SliceKey) -> Result<Vec<StoredContour>> {
    let sql = format!(
        "SELECT {CONTOUR_COLUMNS} FROM contours c JOIN users u ON u.id = c.user_id \
         WHERE c.cell = ?1 AND c.user_id = ?2 AND c.label = ?3 AND c.axis = ?4 AND c.slice = ?5 \
         ORDER BY c.id"
    );
    let mut st = tx.prepare_cached(&sql)?;
    let rows = st.query_map(slice_params!(key), contour_from_row)?;
    Ok(rows.collect::<rusqlite::Result<Vec<_>>>()?)
}

/// One live contour by id.
fn contour_by_id(tx: &Transaction<'_>, id: i64) -> Result<Option<StoredContour>> {
    let sql = format!(
        "SELECT {CONTOUR_COLUMNS} FROM contours c JOIN users u ON u.id = c.user_id WHERE c.id = ?1"
    );
    Ok(tx
        .prepare_cached(&sql)?
        .query_row([id], contour_from_row)
        .optional()?)
}

/// Whether the slice is marked drawn-empty.
fn is_empty(tx: &Transaction<'_>, key: &SliceKey) -> Result<bool> {
    let sql = format!("SELECT 1 FROM drawn_empty WHERE {SLICE_WHERE}");
    Ok(tx.prepare_cached(&sql)?.exists(slice_params!(key))?)
}

/// Set or clear the drawn-empty mark of a slice; returns whether it was set.
pub(super) fn set_empty(tx: &Transaction<'_>, key: &SliceKey, empty: bool) -> Result<bool> {
    let sql = format!("DELETE FROM drawn_empty WHERE {SLICE_WHERE}");
    let was = tx.prepare_cached(&sql)?.execute(slice_params!(key))? > 0;
    if empty {
        tx.prepare_cached(
            "INSERT INTO drawn_empty (cell, user_id, label, axis, slice, created) \
             VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
        )?
        .execute(slice_params!(key, now_rfc3339()))?;
    }
    Ok(was)
}

/// Archive and delete every live contour of a slice; returns their ids, ascending.
fn clear_slice(tx: &Transaction<'_>, key: &SliceKey) -> Result<Vec<i64>> {
    let sql = format!(
        "INSERT OR IGNORE INTO contour_archive ({ROW_COLUMNS}) \
         SELECT {ROW_COLUMNS} FROM contours WHERE {SLICE_WHERE}"
    );
    tx.prepare_cached(&sql)?.execute(slice_params!(key))?;
    let sql = format!("DELETE FROM contours WHERE {SLICE_WHERE} RETURNING id");
    let mut st = tx.prepare_cached(&sql)?;
    let mut ids = st
        .query_map(slice_params!(key), |r| r.get(0))?
        .collect::<rusqlite::Result<Vec<i64>>>()?;
    ids.sort_unstable();
    Ok(ids)
}

/// Store a new contour on its slice; returns its id.
fn insert_contour(tx: &Transaction<'_>, key: &SliceKey, c: &StoredContour) -> Result<i64> {
    let mut st = tx.prepare_cached(
        "INSERT INTO contours (cell, user_id, label, axis, slice, points, pressure, \
         times_ms, duration_ms, tool, client_id, created, updated) \
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13)",
    )?;
    st.execute(params![
        key.cell,
        key.user_id,
        key.label,
        axis_str(key.axis),
        key.index as i64,
        serde_json::to_string(&c.contour.points).expect("points serialise"),
        c.contour
            .pressure
            .as_ref()
            .map(|p| serde_json::to_string(p).expect("serialise")),
        c.contour
            .times_ms
            .as_ref()
            .map(|p| serde_json::to_string(p).expect("serialise")),
        c.duration_ms,
        c.contour.tool.as_deref().unwrap_or(DEFAULT_TOOL),
        c.client_id,
        c.contour.created,
        c.updated,
    ])?;
    Ok(tx.last_insert_rowid())
}

/// Put archived contours back where they were, under their own ids (undo of
/// a removal, redo of an addition).
pub(super) fn restore_contours(tx: &Transaction<'_>, ids: &[i64]) -> Result<()> {
    let sql = format!(
        "INSERT INTO contours ({ROW_COLUMNS}) SELECT {ROW_COLUMNS} FROM contour_archive WHERE id = ?1"
    );
    let mut st = tx.prepare_cached(&sql)?;
    for &id in ids {
        if st.execute([id])? != 1 {
            return Err(StoreError::Corrupt(format!(
                "contour {id} is missing from the archive"
            )));
        }
    }
    Ok(())
}

/// Archive and delete live contours by id (a delete, the undo of an
/// addition, the redo of a removal). A contour archived before (removed,
/// restored, removed again) keeps its one archived row.
pub(super) fn remove_contours(tx: &Transaction<'_>, ids: &[i64]) -> Result<()> {
    let sql = format!(
        "INSERT OR IGNORE INTO contour_archive ({ROW_COLUMNS}) \
         SELECT {ROW_COLUMNS} FROM contours WHERE id = ?1"
    );
    let mut archive = tx.prepare_cached(&sql)?;
    let mut delete = tx.prepare_cached("DELETE FROM contours WHERE id = ?1")?;
    for &id in ids {
        archive.execute([id])?;
        delete.execute([id])?;
    }
    Ok(())
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
        contour: Contour {
            slice: SliceRef {
                axis: key.axis,
                index: key.index,
            },
            label: key.label,
            points: c.points,
            author: String::new(),
            created: now.clone(),
            pressure: c.pressure,
            times_ms: c.times_ms,
            tool: Some(c.tool.unwrap_or_else(|| DEFAULT_TOOL.to_string())),
        },
        duration_ms,
        user_id: key.user_id,
        client_id,
        updated: now,
    }
}

impl Store {
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
        self.read(|tx| contour_by_id(tx, id))
    }

    /// A contour as it was stored under `id`, whether it is still on its slice
    /// or was deleted or replaced since: the content that change-log and audit
    /// entries refer to by id.
    pub fn archived_contour(&self, id: i64) -> Result<Option<StoredContour>> {
        self.read(|tx| {
            if let Some(c) = contour_by_id(tx, id)? {
                return Ok(Some(c));
            }
            let sql = format!(
                "SELECT {CONTOUR_COLUMNS} FROM contour_archive c JOIN users u ON u.id = c.user_id \
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
            let empty_before = set_empty(tx, key, false)?;
            let id = insert_contour(tx, key, &stored_from_new(key, contour, client_id))?;
            touch_status(tx, &key.cell, key.user_id)?;
            let delta = Delta {
                added: vec![id],
                removed: vec![],
                empty_before,
                empty_after: false,
            };
            record_change(tx, key, "contour.add", &delta)?;
            let created = contour_by_id(tx, id)?
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
            let removed = clear_slice(tx, key)?;
            let empty_before = set_empty(tx, key, false)?;
            let added = contours
                .into_iter()
                .map(|c| insert_contour(tx, key, &stored_from_new(key, c, None)))
                .collect::<Result<Vec<i64>>>()?;
            touch_status(tx, &key.cell, key.user_id)?;
            let delta = Delta {
                added,
                removed,
                empty_before,
                empty_after: false,
            };
            record_change(tx, key, "slice.replace", &delta)?;
            slice_contours(tx, key)
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
            remove_contours(tx, &[id])?;
            let empty = is_empty(tx, &key)?;
            let delta = Delta {
                added: vec![],
                removed: vec![id],
                empty_before: empty,
                empty_after: empty,
            };
            record_change(tx, &key, "contour.delete", &delta)
        })
    }

    /// Mark a slice drawn with no contour of the label (removes its contours there).
    pub fn mark_empty(&self, key: &SliceKey) -> Result<()> {
        self.write(|tx| {
            Self::check_cell(tx, &key.cell)?;
            Self::check_label(tx, key.label)?;
            let removed = clear_slice(tx, key)?;
            let empty_before = set_empty(tx, key, true)?;
            touch_status(tx, &key.cell, key.user_id)?;
            let delta = Delta {
                added: vec![],
                removed,
                empty_before,
                empty_after: true,
            };
            record_change(tx, key, "slice.empty", &delta)
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
}
