//! Automated segmentations and their ratings.
use super::audit::audit;
use super::{Store, json_err};
use crate::codec;
use crate::model::{Rating, SegmentationMeta};
use crate::{Result, StoreError, now_rfc3339};
use interslice_core::{Geometry, LabelVolume, Volume};
use rusqlite::{OptionalExtension, params};

impl Store {
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
}
