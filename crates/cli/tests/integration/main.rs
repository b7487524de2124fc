//! The `interslice` command line, run as a user runs it: one module per command
//! (and the reference cross-checks), all in one test binary.
//!
//! One binary, not one per file: each test binary links every dependency
//! and monomorphises its generic code again; the four crates' 43 binaries
//! took 346–398 crate-seconds of a cold build, these four 295.
mod bench_cli;
mod common;
mod contours_cli;
mod evaluate_cli;
mod interpolate_cli;
mod interpolate_image_cli;
mod interpolate_orientations_cli;
mod mesh_cli;
mod phantom_cli;
mod refs_metrics;
mod refs_thresholds;
mod segment_cli;
mod server_cli;
mod server_stop;
mod study_cli;
mod variability_cli;
