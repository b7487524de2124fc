//! Errors of the core crate.
use thiserror::Error;

/// What can go wrong in core operations; every message is one line for the user.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CoreError {
    /// The data length does not match the dims.
    #[error("volume data has {got} voxels but dims {dims:?} need {expected}")]
    DataLength {
        /// Dims given.
        dims: [usize; 3],
        /// Voxels expected from the dims.
        expected: usize,
        /// Voxels present.
        got: usize,
    },
    /// Two volumes that must share a geometry do not.
    #[error("geometry mismatch: {0}")]
    GeometryMismatch(String),
    /// A geometry value is invalid (zero dim, non-positive spacing, ...).
    #[error("invalid geometry: {0}")]
    InvalidGeometry(String),
    /// A slice index is outside the volume.
    #[error("slice {axis}={index} is out of range (0..{len})")]
    SliceOutOfRange {
        /// Axis of the slice.
        axis: crate::Axis,
        /// Requested index.
        index: usize,
        /// Number of slices along the axis.
        len: usize,
    },
    /// The computation was stopped through its [`crate::Cancel`] token.
    #[error("the computation was cancelled")]
    Cancelled,
    /// Any other invalid input, with a message.
    #[error("{0}")]
    Invalid(String),
}
