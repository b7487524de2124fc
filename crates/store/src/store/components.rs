//! The project's components as the store's labels: a project that names its
//! own components (a brain MRI project: "Tumour, Oedema") gets exactly those,
//! not the cell-CT set the database starts with.
use super::Store;
use super::audit::audit;
use crate::{Result, StoreError};
use interslice_core::components::{Component, Components, parse_hex_color};
use rusqlite::params;

impl Store {
    /// The project's labels as components (value, name, colour).
    pub fn components(&self) -> Result<Components> {
        let list = self
            .labels()?
            .into_iter()
            .map(|l| {
                let color =
                    parse_hex_color(&l.color).map_err(|e| StoreError::Invalid(e.to_string()))?;
                Ok(Component {
                    value: l.id,
                    name: l.name,
                    color,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Components::new(list).map_err(|e| StoreError::Invalid(e.to_string()))
    }

    /// Make the labels the given components: each is inserted or renamed and
    /// recoloured in place (contours keep their label value); a label the list
    /// does not declare is removed when nothing is traced with it, and kept
    /// otherwise (tracings are never dropped by a configuration change).
    pub fn sync_components(&self, components: &Components) -> Result<()> {
        self.write(|tx| {
            let existing: Vec<(u16, String)> = tx
                .prepare_cached("SELECT id, name FROM labels ORDER BY id")?
                .query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?
                .collect::<rusqlite::Result<_>>()?;
            let mut kept = Vec::new();
            for (id, name) in &existing {
                if components.by_value(*id).is_some() {
                    continue;
                }
                let used = tx
                    .prepare_cached(
                        "SELECT 1 FROM contours WHERE label = ?1 \
                         UNION ALL SELECT 1 FROM drawn_empty WHERE label = ?1 LIMIT 1",
                    )?
                    .exists([id])?;
                if used {
                    kept.push((*id, name.clone()));
                } else {
                    tx.prepare_cached("DELETE FROM labels WHERE id = ?1")?
                        .execute([id])?;
                }
            }
            for c in components.as_slice() {
                if let Some((id, _)) = kept.iter().find(|(_, n)| n.eq_ignore_ascii_case(&c.name)) {
                    return Err(StoreError::Invalid(format!(
                        "component '{}' = {} clashes with label {id} of the same name, which has tracings",
                        c.name, c.value
                    )));
                }
                // Free the name first if another declared value holds it now.
                tx.prepare_cached("UPDATE labels SET name = '#' || id WHERE name = ?1 AND id != ?2")?
                    .execute(params![c.name, c.value])?;
                tx.prepare_cached(
                    "INSERT INTO labels (id, name, color) VALUES (?1, ?2, ?3) \
                     ON CONFLICT(id) DO UPDATE SET name = excluded.name, color = excluded.color",
                )?
                .execute(params![c.value, c.name, c.hex_color()])?;
            }
            audit(
                tx,
                None,
                None,
                "labels.sync",
                serde_json::json!({
                    "components": components.as_slice().iter()
                        .map(|c| serde_json::json!({"id": c.value, "name": c.name, "color": c.hex_color()}))
                        .collect::<Vec<_>>(),
                    "kept": kept.iter().map(|(id, _)| id).collect::<Vec<_>>(),
                }),
            )?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::Store;
    use interslice_core::components::Components;

    #[test]
    fn a_project_gets_its_own_components_and_keeps_traced_labels() {
        let s = Store::open_in_memory().unwrap();
        s.sync_components(&Components::from_names("Tumour,Oedema").unwrap())
            .unwrap();
        let names = crate::store::fixtures::label_names(&s);
        assert_eq!(
            names,
            [(1, "Tumour".to_string()), (2, "Oedema".to_string())]
        );
        // Back to the cell-CT set: names and colours follow the values.
        s.sync_components(&Components::cell_ct()).unwrap();
        let labels = s.labels().unwrap();
        assert_eq!(labels.len(), 4);
        assert_eq!(labels[1].name, "Nucleus");
        assert_eq!(labels[0].color, "#e6194b");
        // Swapping two names is not a uniqueness clash.
        let swapped = Components::new(vec![
            interslice_core::components::Component::new(1, "Nucleus"),
            interslice_core::components::Component::new(2, "Cell"),
        ])
        .unwrap();
        s.sync_components(&swapped).unwrap();
        assert_eq!(s.labels().unwrap()[0].name, "Nucleus");
    }
}
