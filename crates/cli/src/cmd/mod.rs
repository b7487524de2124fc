//! One module per subcommand.
pub mod contours;
pub mod convert;
pub mod evaluate;
pub mod info;
pub mod interpolate;
pub mod mesh;
pub mod phantom;
pub mod study;
