//! The tracing server over real HTTP on loopback, one module per concern, all
//! in one test binary.
//!
//! One binary, not one per file: each test binary links every dependency,
//! and on two cores linking and monomorphising them per file cost minutes
//! of every test run.
mod advice;
mod common;
mod confidence;
mod http;
mod image_method;
mod orientations;
mod security;
mod security_requests;
mod summary;
mod uploads;
mod voxel_types;
