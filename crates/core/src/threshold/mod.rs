//! Automatic intensity thresholds: Otsu, multi-class Otsu, Rosin's unimodal
//! threshold, k-means on intensities, and (as cross-checks) scikit-image's
//! triangle and ISODATA.
//!
//! Every method works on a [`Histogram`] (or, for k-means, on the distinct
//! values with their counts) and returns thresholds in intensity units.
//! **Foreground is `v > t`** for every threshold `t` (the convention of the
//! references in `refs/THRESHOLDS.md`): with native bins the threshold is a
//! grey level that belongs to the lower class.
//!
//! The methods reproduce the reference values of scikit-image and of the
//! exact float64 searches in `refs/thresholds_expected.json`; where
//! scikit-image computes in float32 and misses the optimum (multi-Otsu on
//! nearly empty valleys), ours is the exact float64 optimum.
//!
//! Written here rather than taken from a crate: no maintained Rust crate
//! offers these thresholds on 16-bit histograms with numpy's exact binning.

pub mod histogram;
pub mod isodata;
pub mod kmeans;
pub mod multi_otsu;
pub mod otsu;
mod partition;
pub mod rosin;
pub mod triangle;

pub use histogram::{Binning, Histogram, count_above, distinct_values};
pub use isodata::isodata;
pub use kmeans::{KMeans, kmeans_exact, kmeans_lloyd};
pub use multi_otsu::{multi_otsu, multi_otsu_objective};
pub use otsu::{otsu, otsu_bin};
pub use rosin::{Rosin, RosinEnd, rosin};
pub use triangle::triangle;

use thiserror::Error;

/// Why a threshold could not be computed; messages are one line for the user.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ThresholdError {
    /// The histogram holds no voxel.
    #[error("the volume is empty")]
    Empty,
    /// Fewer distinct values (or non-empty bins) than classes asked for.
    #[error(
        "cannot split into {classes} classes: the volume has only {found} distinct value(s) after binning"
    )]
    TooFewValues {
        /// Classes asked for.
        classes: usize,
        /// Distinct values (non-empty bins) present.
        found: usize,
    },
    /// The volume holds NaN or infinite values.
    #[error("the volume holds NaN or infinite values")]
    NonFinite,
    /// Any other invalid input.
    #[error("{0}")]
    Invalid(String),
}
