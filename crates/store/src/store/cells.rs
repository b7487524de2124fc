//! Cells, labels, per-user cell status and tracing time.
use super::Store;
use super::audit::audit;
use crate::model::{CellRecord, CellStatus, Label, Progress};
use crate::{Result, StoreError, now_rfc3339};
use interslice_core::Geometry;
use interslice_core::components;
use rusqlite::{OptionalExtension, Transaction, params};
use std::collections::HashMap;

/// Mark the cell in progress for the user unless it has a status already.
pub(super) fn touch_status(tx: &Transaction<'_>, cell: &str, user_id: i64) -> Result<()> {
    tx.prepare_cached(
        "INSERT OR IGNORE INTO cell_status (cell, user_id, status, updated) \
         VALUES (?1, ?2, 'in_progress', ?3)",
    )?
    .execute(params![cell, user_id, now_rfc3339()])?;
    Ok(())
}

impl Store {
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
        if name.is_empty() || name.chars().count() > components::MAX_NAME_CHARS {
            return Err(StoreError::Invalid(format!(
                "a label name has 1 to {} characters",
                components::MAX_NAME_CHARS
            )));
        }
        if let Some(c) = color {
            components::parse_hex_color(c).map_err(|e| StoreError::Invalid(e.to_string()))?;
        }
        // Added labels take the palette's colours after the cell-CT four.
        let palette = &components::PALETTE[4..];
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
            let color = color.map(str::to_ascii_lowercase).unwrap_or_else(|| {
                let [r, g, b] = palette[(id as usize) % palette.len()];
                format!("#{r:02x}{g:02x}{b:02x}")
            });
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

    pub(super) fn check_label(tx: &Transaction<'_>, label: u16) -> Result<()> {
        if !tx
            .prepare_cached("SELECT 1 FROM labels WHERE id = ?1")?
            .exists([label])?
        {
            return Err(StoreError::Invalid(format!("unknown label {label}")));
        }
        Ok(())
    }

    pub(super) fn check_cell(tx: &Transaction<'_>, cell: &str) -> Result<()> {
        if !tx
            .prepare_cached("SELECT 1 FROM cells WHERE id = ?1")?
            .exists([cell])?
        {
            return Err(StoreError::NotFound(format!("unknown cell '{cell}'")));
        }
        Ok(())
    }
}
