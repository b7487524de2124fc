//! What the server's tests, its latency benchmark and the CLI's server tests
//! share, kept out of the production library: a small blocking HTTP client
//! ([`client`]) and the concurrency load test with its test cells
//! ([`loadtest`], also the `loadtest` binary).
#![deny(missing_docs)]

pub mod client;
pub mod loadtest;
