//! Cooperative cancellation of long computations.
//!
//! A [`Cancel`] is a shared flag that a long computation (smoothing, STAPLE,
//! interpolation of a user's labels) checks at its loop boundaries; whoever
//! holds a clone can stop it. The server sets it when a request times out,
//! its client goes away or the process is asked to stop, so no core keeps
//! computing an answer nobody will read. A token made with [`Cancel::child`]
//! is also cancelled with its parent (the server's shutdown token is the
//! parent of every request's token).
use crate::CoreError;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A cancellation token: cheap to clone, every clone sees the same flag.
#[derive(Debug, Clone)]
pub struct Cancel {
    /// This token's flag, then its ancestors'.
    flags: Vec<Arc<AtomicBool>>,
}

impl Default for Cancel {
    fn default() -> Cancel {
        Cancel::new()
    }
}

impl Cancel {
    /// A token nobody has cancelled yet.
    pub fn new() -> Cancel {
        Cancel {
            flags: vec![Arc::new(AtomicBool::new(false))],
        }
    }

    /// A token cancelled by itself or whenever `self` is.
    pub fn child(&self) -> Cancel {
        let mut flags = vec![Arc::new(AtomicBool::new(false))];
        flags.extend(self.flags.iter().cloned());
        Cancel { flags }
    }

    /// Ask the computations holding this token (and its children) to stop.
    pub fn cancel(&self) {
        if let Some(f) = self.flags.first() {
            f.store(true, Ordering::Relaxed);
        }
    }

    /// Whether this token or an ancestor was cancelled.
    pub fn is_cancelled(&self) -> bool {
        self.flags.iter().any(|f| f.load(Ordering::Relaxed))
    }

    /// `Err(CoreError::Cancelled)` once cancelled: the `?` of a loop boundary.
    pub fn check(&self) -> Result<(), CoreError> {
        if self.is_cancelled() {
            Err(CoreError::Cancelled)
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Cancel;

    #[test]
    fn children_follow_their_parent_not_the_reverse() {
        let root = Cancel::new();
        let a = root.child();
        let b = a.child();
        let other = root.child();
        assert!(!b.is_cancelled() && b.check().is_ok());
        a.cancel();
        assert!(a.is_cancelled() && b.is_cancelled());
        assert!(!root.is_cancelled() && !other.is_cancelled());
        root.cancel();
        assert!(other.check().is_err());
        assert!(Cancel::default().check().is_ok());
    }
}
