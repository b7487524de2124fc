//! Reading and writing every format through the public API: golden files,
//! round trips, DICOM, wide voxel types, errors, hostile files and the
//! mutation test, all in one test binary.
//!
//! One binary, not one per file: each test binary links every dependency,
//! and on two cores linking and monomorphising them per file cost minutes
//! of every test run.
mod dicom;
mod errors;
mod golden;
mod mesh_formats;
mod mutation;
mod roundtrip;
mod security;
mod wide_types;
