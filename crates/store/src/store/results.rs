//! Stored interpolation results.
use super::audit::audit;
use super::{Store, axis_str, parse_axis};
use crate::codec;
use crate::model::ResultMeta;
use crate::{Result, StoreError, now_rfc3339};
use interslice_core::{Axis, Geometry, Mask, Volume};
use rusqlite::{OptionalExtension, params};

impl Store {
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
            let rows = st.query_map(params![cell, user_id], result_meta)?;
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
                        result_meta(r)?,
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
}

/// The [`ResultMeta`] of a row whose first columns are `id, cell, user_id,
/// label, axis, method, voxels, created`.
fn result_meta(r: &rusqlite::Row<'_>) -> rusqlite::Result<ResultMeta> {
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
}
