//! The tracing server over real HTTP on loopback, one module per concern, all
//! in one test binary.
//!
//! One binary, not one per file: each test binary links every dependency
//! and monomorphises its generic code again; the four crates' 43 binaries
//! took 346–398 crate-seconds of a cold build, these four 295.
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
