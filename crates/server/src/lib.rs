//! HTTP API and the embedded web UI.
#![deny(missing_docs)]
