//! The undo/redo change log: one row per change of a slice in `changes`, the
//! contour ids it added and removed in `change_contours` (their content is in
//! `contours` while they are on their slice, in `contour_archive` once taken
//! off). A change costs storage in proportion to what it changed, whatever
//! the size of the slice.
use super::audit::audit;
use super::contours::{remove_contours, restore_contours, set_empty, slice_params};
use super::{Store, axis_str, parse_axis};
use crate::Result;
use crate::model::{SliceKey, UndoOutcome};
use rusqlite::{OptionalExtension, Transaction, params};

/// What one change did to one slice.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct Delta {
    /// Contours put on the slice, by id.
    pub(super) added: Vec<i64>,
    /// Contours taken off the slice, by id.
    pub(super) removed: Vec<i64>,
    /// Whether the slice was marked drawn-empty before the change.
    pub(super) empty_before: bool,
    /// Whether it is marked drawn-empty after.
    pub(super) empty_after: bool,
}

impl Delta {
    /// The change that takes the slice back (undo).
    fn inverse(self) -> Delta {
        Delta {
            added: self.removed,
            removed: self.added,
            empty_before: self.empty_after,
            empty_after: self.empty_before,
        }
    }

    /// The audit detail of this change: which slice, which contours (by id,
    /// see `Store::archived_contour`) and the drawn-empty mark.
    fn audit_detail(&self, change: i64, key: &SliceKey) -> serde_json::Value {
        serde_json::json!({
            "change": change, "label": key.label, "axis": axis_str(key.axis), "index": key.index,
            "added": self.added, "removed": self.removed,
            "empty_before": self.empty_before, "empty_after": self.empty_after,
        })
    }
}

/// Record a change for undo (dropping the redo stack) and in the audit log.
pub(super) fn record_change(
    tx: &Transaction<'_>,
    key: &SliceKey,
    action: &str,
    delta: &Delta,
) -> Result<()> {
    // The redo stack goes with its deltas (ON DELETE CASCADE).
    tx.prepare_cached("DELETE FROM changes WHERE cell = ?1 AND user_id = ?2 AND undone = 1")?
        .execute(params![key.cell, key.user_id])?;
    tx.prepare_cached(
        "INSERT INTO changes (cell, user_id, label, axis, slice, empty_before, empty_after) \
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
    )?
    .execute(slice_params!(key, delta.empty_before, delta.empty_after))?;
    let change = tx.last_insert_rowid();
    let mut st = tx.prepare_cached(
        "INSERT INTO change_contours (change_id, contour_id, added) VALUES (?1, ?2, ?3)",
    )?;
    for (ids, added) in [(&delta.added, true), (&delta.removed, false)] {
        for id in ids {
            st.execute(params![change, id, added])?;
        }
    }
    audit(
        tx,
        Some(key.user_id),
        Some(&key.cell),
        action,
        delta.audit_detail(change, key),
    )
}

/// The contours a stored change added and removed, ascending.
fn change_contours(tx: &Transaction<'_>, change: i64) -> Result<(Vec<i64>, Vec<i64>)> {
    let mut st = tx.prepare_cached(
        "SELECT contour_id, added FROM change_contours WHERE change_id = ?1 ORDER BY contour_id",
    )?;
    let (mut added, mut removed) = (Vec::new(), Vec::new());
    for row in st.query_map([change], |r| {
        Ok((r.get::<_, i64>(0)?, r.get::<_, bool>(1)?))
    })? {
        let (id, was_added) = row?;
        if was_added {
            added.push(id);
        } else {
            removed.push(id);
        }
    }
    Ok((added, removed))
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

    /// Replay the last change (undo) or the first undone one (redo): every
    /// later change of the same slice was undone first, so the slice is
    /// exactly in the state the change left it in (or, for a redo, found it).
    fn undo_redo(&self, cell: &str, user_id: i64, undo: bool) -> Result<UndoOutcome> {
        self.write(|tx| {
            let sql = if undo {
                "SELECT id, label, axis, slice, empty_before, empty_after FROM changes \
                 WHERE cell = ?1 AND user_id = ?2 AND undone = 0 ORDER BY id DESC LIMIT 1"
            } else {
                "SELECT id, label, axis, slice, empty_before, empty_after FROM changes \
                 WHERE cell = ?1 AND user_id = ?2 AND undone = 1 ORDER BY id ASC LIMIT 1"
            };
            let row: Option<(i64, u16, String, i64, bool, bool)> = tx
                .prepare_cached(sql)?
                .query_row(params![cell, user_id], |r| {
                    Ok((
                        r.get(0)?,
                        r.get(1)?,
                        r.get(2)?,
                        r.get(3)?,
                        r.get(4)?,
                        r.get(5)?,
                    ))
                })
                .optional()?;
            let Some((id, label, axis, slice, empty_before, empty_after)) = row else {
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
            let (added, removed) = change_contours(tx, id)?;
            let mut delta = Delta {
                added,
                removed,
                empty_before,
                empty_after,
            };
            if undo {
                delta = delta.inverse();
            }
            remove_contours(tx, &delta.removed)?;
            restore_contours(tx, &delta.added)?;
            set_empty(tx, &key, delta.empty_after)?;
            tx.prepare_cached("UPDATE changes SET undone = ?2 WHERE id = ?1")?
                .execute(params![id, undo])?;
            audit(
                tx,
                Some(user_id),
                Some(cell),
                if undo { "undo" } else { "redo" },
                delta.audit_detail(id, &key),
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
