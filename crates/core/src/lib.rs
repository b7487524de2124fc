//! Core types of interslice: volumes and their geometry, slices, and the pure
//! algorithms built on them (contours, rasterisation, metrics, thresholds).
//!
//! This crate does no I/O. Conventions (shared by every crate) are fixed in
//! `docs/conventions.md`: dims `(nx, ny, nz)`, voxel `(i, j, k)`, x-fastest storage
//! `index = i + nx * (j + ny * k)`.
#![deny(missing_docs)]

pub mod cancel;
pub mod components;
pub mod contour;
pub mod contour_file;
pub mod edt;
pub mod error;
pub mod geometry;
pub mod le;
pub mod mesh;
pub mod metrics;
pub mod morph;
pub mod phantom;
pub mod raster;
pub mod regions;
pub mod segment;
pub mod slice;
pub mod staple;
pub mod threshold;
pub mod trace;
pub mod volume;

pub use cancel::Cancel;
pub use contour::Contour;
pub use error::CoreError;
pub use geometry::{Geometry, LengthUnit};
pub use slice::{Axis, SliceRef};
pub use volume::{AnyVolume, LabelVolume, Mask, SliceView, Volume, Voxel};
