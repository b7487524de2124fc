//! Interpolators behind one trait, distance transforms, meshes and voxelisation.
//!
//! An interpolator turns a *sparse* binary mask — the tracing of one label on
//! the drawn slices along one axis — into a full 3D mask. Drawn slices are
//! given explicitly: a drawn slice with no foreground is a known-empty slice.
#![deny(missing_docs)]

pub mod method;

pub use method::{InterpError, Interpolator, SparseMask};
