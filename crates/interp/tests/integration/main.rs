//! The interpolation methods through the public API: invariants, methods,
//! the image-aware method, orientations, meshes and cancellation, all in one
//! test binary.
//!
//! One binary, not one per file: each test binary links every dependency,
//! and on two cores linking and monomorphising them per file cost minutes
//! of every test run.
mod cancel;
mod common;
mod image;
mod image_data;
mod invariants;
mod mesh_methods;
mod mesh_surface;
mod methods;
mod multi_axis;
