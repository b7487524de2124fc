//! The undo/redo change log.
use super::audit::audit;
use super::contours::{SliceState, apply_state, slice_state};
use super::{Store, axis_str, parse_axis};
use crate::model::{SliceKey, UndoOutcome};
use crate::{Result, StoreError};
use rusqlite::{OptionalExtension, Transaction, params};

/// Record a change for undo (dropping the redo stack) and in the audit log.
pub(super) fn record_change(
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

impl Store {
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
}
