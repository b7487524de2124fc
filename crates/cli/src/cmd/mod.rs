//! One module per subcommand.
pub mod bench;
pub mod campaign;
pub mod contours;
pub mod convert;
pub mod demo;
pub mod evaluate;
pub mod export;
pub mod info;
pub mod interpolate;
pub mod mesh;
pub mod phantom;
pub mod segment;
pub mod serve;
pub mod staple;
pub mod study;
pub mod user;
pub mod variability;
