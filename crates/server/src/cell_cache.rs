//! A small LRU of loaded cells (a 512³ 16-bit volume is 256 MiB, so only a
//! few stay loaded); concurrent requests for one cell share one load.
use crate::error::ApiError;
use interslice_project::cells::LoadedCell;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use tokio::sync::OnceCell;

type Slot = Arc<OnceCell<Arc<LoadedCell>>>;

/// An LRU of loaded cells; concurrent requests for one cell share one load.
pub struct CellCache {
    capacity: usize,
    slots: Mutex<VecDeque<(String, Slot)>>,
}

impl CellCache {
    /// A cache holding at most `capacity` volumes (at least 1).
    pub fn new(capacity: usize) -> CellCache {
        CellCache {
            capacity: capacity.max(1),
            slots: Mutex::new(VecDeque::new()),
        }
    }

    fn slot(&self, id: &str) -> Slot {
        let mut slots = self.slots.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(pos) = slots.iter().position(|(k, _)| k == id) {
            let entry = slots.remove(pos).expect("position is valid");
            let slot = entry.1.clone();
            slots.push_back(entry);
            return slot;
        }
        let slot: Slot = Arc::new(OnceCell::new());
        slots.push_back((id.to_string(), slot.clone()));
        while slots.len() > self.capacity {
            slots.pop_front();
        }
        slot
    }

    /// The loaded cell `id`, reading it with `load` on a blocking thread if needed.
    pub async fn get<F>(&self, id: &str, load: F) -> Result<Arc<LoadedCell>, ApiError>
    where
        F: FnOnce() -> Result<LoadedCell, ApiError> + Send + 'static,
    {
        let slot = self.slot(id);
        let cell = slot
            .get_or_try_init(|| async move {
                let loaded = tokio::task::spawn_blocking(load).await??;
                Ok::<_, ApiError>(Arc::new(loaded))
            })
            .await?;
        Ok(cell.clone())
    }
}
