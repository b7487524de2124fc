//! Reading and writing every format through the public API: golden files,
//! round trips, DICOM, wide voxel types, errors, hostile files and the
//! mutation test, all in one test binary.
//!
//! One binary, not one per file: each test binary links every dependency
//! and monomorphises its generic code again; the four crates' 43 binaries
//! took 346–398 crate-seconds of a cold build, these four 295.
mod dicom;
mod errors;
mod golden;
mod mesh_formats;
mod mutation;
mod roundtrip;
mod security;
mod wide_types;
