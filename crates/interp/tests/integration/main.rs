//! The interpolation methods through the public API: invariants, methods,
//! the image-aware method, orientations, meshes and cancellation, all in one
//! test binary.
//!
//! One binary, not one per file: each test binary links every dependency
//! and monomorphises its generic code again; the four crates' 43 binaries
//! took 346–398 crate-seconds of a cold build, these four 295.
mod cancel;
mod common;
mod confidence;
mod image;
mod image_data;
mod invariants;
mod mesh_methods;
mod mesh_surface;
mod methods;
mod multi_axis;
