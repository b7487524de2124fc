//! Long work off the async threads, stopped when nobody waits for it.
//!
//! Handlers run their computations (segmentation, interpolation, STAPLE,
//! evaluation) through [`Jobs::run`] on the blocking pool with a
//! [`Cancel`] token. The token is cancelled when the request's future is
//! dropped (the request timed out, or the client went away) and when the
//! server shuts down, so no core keeps computing an answer nobody will read,
//! and SIGTERM ends the process within seconds. The request timeout itself is
//! [`timeout`]: a 408 with a JSON error like every other.
use crate::error::{ApiError, error_response};
use axum::http::StatusCode;
use interslice_core::Cancel;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// The running computations of a server and the token that stops them all.
#[derive(Debug, Default)]
pub struct Jobs {
    /// Parent of every job's token; cancelled on shutdown.
    root: Cancel,
    running: AtomicUsize,
    cancelled: AtomicUsize,
}

/// Cancels its token when dropped: held by the request's future, so a
/// dropped request (timeout, client gone) stops its computation.
struct CancelOnDrop(Cancel);

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        self.0.cancel();
    }
}

/// Counts a running job; decrements even if the job panics.
struct Running<'a>(&'a AtomicUsize);

impl Drop for Running<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

impl Jobs {
    /// Run `f` on the blocking pool with a token that is cancelled when the
    /// returned future is dropped or the server shuts down. A job stopped by
    /// its token answers 503.
    pub async fn run<T: Send + 'static>(
        self: &std::sync::Arc<Self>,
        f: impl FnOnce(&Cancel) -> Result<T, ApiError> + Send + 'static,
    ) -> Result<T, ApiError> {
        let cancel = self.root.child();
        let _guard = CancelOnDrop(cancel.clone());
        let jobs = self.clone();
        tokio::task::spawn_blocking(move || {
            jobs.running.fetch_add(1, Ordering::SeqCst);
            let _running = Running(&jobs.running);
            if cancel.is_cancelled() {
                jobs.cancelled.fetch_add(1, Ordering::SeqCst);
                return Err(cancelled());
            }
            let out = f(&cancel);
            if out.is_err() && cancel.is_cancelled() {
                jobs.cancelled.fetch_add(1, Ordering::SeqCst);
                return Err(cancelled());
            }
            out
        })
        .await?
    }

    /// Cancel every running and future job (the server is stopping).
    pub fn shutdown(&self) {
        self.root.cancel();
    }

    /// Jobs computing right now.
    pub fn running(&self) -> usize {
        self.running.load(Ordering::SeqCst)
    }

    /// Jobs stopped by their token so far.
    pub fn cancelled(&self) -> usize {
        self.cancelled.load(Ordering::SeqCst)
    }
}

/// The answer of a job stopped by its token (seen only by a client still
/// connected while the server shuts down): 503.
fn cancelled() -> ApiError {
    ApiError::from(interslice_core::CoreError::Cancelled)
}

/// The request timeout: a request not answered within `limit` is dropped
/// (which cancels its job) and answered 408 with a JSON error.
pub async fn timeout(
    limit: Duration,
    req: axum::extract::Request,
    next: axum::middleware::Next,
) -> axum::response::Response {
    match tokio::time::timeout(limit, next.run(req)).await {
        Ok(resp) => resp,
        Err(_) => error_response(
            StatusCode::REQUEST_TIMEOUT,
            &format!(
                "the request took longer than {} s and was stopped",
                limit.as_secs_f64()
            ),
        ),
    }
}
