//! The append-only audit log.
use super::{Store, json_err};
use crate::model::AuditEntry;
use crate::{Result, now_rfc3339};
use rusqlite::{Transaction, params};

pub(super) fn audit(
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

impl Store {
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
