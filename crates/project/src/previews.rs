//! Live previews of an interpolation, kept in memory per user instead of
//! the database: a tracer asks for one after every pen lift, and saving each
//! as a stored result would grow the database with masks nobody asked to
//! keep. A user's previews are bounded by count and bytes (the oldest go
//! first); their ids are negative, so they never collide with stored results.
use interslice_core::{Axis, Mask};
use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex};

/// Most previews kept per user.
pub const MAX_PER_USER: usize = 8;
/// Most mask bytes kept per user (a 512³ mask is 128 MiB; the newest preview
/// is kept whatever its size).
pub const MAX_BYTES_PER_USER: usize = 256 << 20;

/// One preview.
#[derive(Debug, Clone)]
pub struct Preview {
    /// Its id (negative).
    pub id: i64,
    /// The cell.
    pub cell: String,
    /// The label interpolated.
    pub label: u16,
    /// The axis of the drawn slices.
    pub axis: Axis,
    /// The method.
    pub method: String,
    /// The interpolated mask.
    pub mask: Arc<Mask>,
}

/// Every user's recent previews.
#[derive(Default)]
pub struct PreviewCache {
    inner: Mutex<(i64, HashMap<i64, VecDeque<Preview>>)>,
}

impl PreviewCache {
    /// Keep a preview of `user_id`; its id.
    pub fn insert(
        &self,
        user_id: i64,
        cell: &str,
        label: u16,
        axis: Axis,
        method: &str,
        mask: Mask,
    ) -> i64 {
        let mut g = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        g.0 -= 1;
        let id = g.0;
        let list = g.1.entry(user_id).or_default();
        list.push_back(Preview {
            id,
            cell: cell.to_string(),
            label,
            axis,
            method: method.to_string(),
            mask: Arc::new(mask),
        });
        let bytes = |l: &VecDeque<Preview>| l.iter().map(|p| p.mask.data().len()).sum::<usize>();
        while list.len() > 1 && (list.len() > MAX_PER_USER || bytes(list) > MAX_BYTES_PER_USER) {
            list.pop_front();
        }
        id
    }

    /// The preview `id` of `user_id` on `cell`, if still kept.
    pub fn get(&self, user_id: i64, cell: &str, id: i64) -> Option<Preview> {
        let g = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        g.1.get(&user_id)?
            .iter()
            .find(|p| p.id == id && p.cell == cell)
            .cloned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{Geometry, Volume};

    fn mask(n: usize) -> Mask {
        let g = Geometry::new([n, 1, 1], [1.0; 3], Default::default()).unwrap();
        Volume::from_vec(g, vec![true; n]).unwrap()
    }

    #[test]
    fn previews_are_per_user_and_bounded() {
        let c = PreviewCache::default();
        let first = c.insert(1, "c", 1, Axis::Z, "linear", mask(4));
        assert!(first < 0);
        assert_eq!(c.get(1, "c", first).unwrap().mask.data().len(), 4);
        assert!(c.get(2, "c", first).is_none(), "another user's");
        assert!(c.get(1, "d", first).is_none(), "another cell's");
        let ids: Vec<i64> = (0..MAX_PER_USER)
            .map(|_| c.insert(1, "c", 1, Axis::Z, "linear", mask(4)))
            .collect();
        assert!(c.get(1, "c", first).is_none(), "the oldest went first");
        assert!(ids.iter().all(|&id| c.get(1, "c", id).is_some()));
    }
}
