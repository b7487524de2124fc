//! Interpolators behind one trait, distance transforms, meshes and voxelisation.
//!
//! An interpolator turns a *sparse* binary mask — the tracing of one label on
//! the drawn slices along one axis — into a full 3D mask. Drawn slices are
//! given explicitly: a drawn slice with no foreground is a known-empty slice.
#![deny(missing_docs)]

pub mod advise;
pub mod aligned;
pub mod area_profile;
pub mod auto;
pub mod ceiling;
pub mod confidence;
pub mod contest;
pub mod crop;
pub mod drawn;
pub mod image;
pub mod jump;
pub mod labels;
pub mod linear;
pub mod loo;
pub mod mesh;
pub mod method;
pub mod multi_axis;
pub mod nearest;
pub mod predict;
pub mod protocol;
pub mod registry;
pub mod sdf;
pub mod shape_area;
pub mod shape_based;
pub mod shape_cubic;
pub mod slices;

pub use labels::{interpolate_labels, interpolate_labels_as, interpolate_labels_with_confidence};
pub use method::{BoxReach, InterpError, Interpolator, SparseMask};
pub use registry::{
    DEFAULT_METHOD, IMAGE_METHOD, by_name, by_name_with_image, default_method, methods,
};
