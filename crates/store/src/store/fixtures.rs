//! What the store's tests share: a store with one cell and one user, slice
//! keys on that cell and a small square contour.
use super::*;
use crate::model::*;

/// An in-memory store with cell `cell1` and user `alice`.
pub(crate) fn store_with_cell() -> (Store, User) {
    let s = Store::open_in_memory().unwrap();
    s.upsert_cell("cell1", "cell1.nii.gz").unwrap();
    let u = s.ensure_user("alice").unwrap();
    (s, u)
}

/// The key of slice z=`index` of `cell1` for `user` and `label`.
pub(crate) fn key(user: &User, label: u16, index: usize) -> SliceKey {
    SliceKey {
        cell: "cell1".into(),
        user_id: user.id,
        label,
        axis: Axis::Z,
        index,
    }
}

/// A 4 x 4 square pen stroke at (`x`, `x`).
pub(crate) fn square(x: f64) -> NewContour {
    NewContour {
        points: vec![[x, x], [x + 4.0, x], [x + 4.0, x + 4.0], [x, x + 4.0]],
        pressure: Some(vec![0.5; 4]),
        times_ms: Some(vec![0.0, 10.0, 20.0, 35.0]),
        tool: Some("pen".into()),
        duration_ms: None,
    }
}

/// The `(id, name)` of every label of the project, by id.
pub(crate) fn label_names(s: &Store) -> Vec<(u16, String)> {
    s.labels()
        .unwrap()
        .into_iter()
        .map(|l| (l.id, l.name))
        .collect()
}
