//! The `interslice` command-line tool: parses arguments, calls the library
//! crates, prints. Each subcommand lives in its own module under `cmd/`.
//! Errors print as one line `error: ...` and exit with status 1 (2 for usage).

mod cmd;
mod label;
mod progress;
mod project;
mod series;

use clap::{Parser, Subcommand};

/// Ground-truth 3D segmentation: trace a few slices, interpolate the rest, measure.
#[derive(Parser)]
#[command(name = "interslice", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print a volume's dims, spacing, type, range and labels.
    Info(cmd::info::Args),
    /// Convert a volume between formats (values and geometry unchanged).
    Convert(cmd::convert::Args),
    /// Fill the slices between drawn slices of a sparse label volume.
    Interpolate(cmd::interpolate::Args),
    /// Which undrawn slices to trace next, best first, with the expected gain.
    Advise(cmd::advise::Args),
    /// Drop slices of a ground truth, interpolate with every method, measure.
    Study(cmd::study::Args),
    /// The interpolation benchmark on the development data (scripts/fetch-interp-data.sh).
    Bench(cmd::bench::Args),
    /// Convert between contours files and label volumes.
    Contours(cmd::contours::Args),
    /// Measure a segmentation against a ground truth (overlap and surface metrics).
    Evaluate(cmd::evaluate::Args),
    /// Generate synthetic cell-CT volumes with their exact label volumes.
    Phantom(cmd::phantom::Args),
    /// Write the surface mesh of a label, or of a method's interpolation (STL, PLY, OBJ).
    Mesh(cmd::mesh::Args),
    /// Serve a project folder: the tracing web UI and its HTTP API.
    Serve(cmd::serve::Args),
    /// Write phantom cells to a project folder and serve it (the quick start).
    Demo(cmd::demo::Args),
    /// Manage the accounts of a project (required when serving off loopback).
    User(cmd::user::Args),
    /// Write a user's interpolated label volume (or contours) of one cell.
    Export(cmd::export::Args),
    /// Segment a volume automatically by an intensity threshold (Otsu, Rosin, k-means, multi-Otsu).
    Segment(cmd::segment::Args),
    /// The STAPLE consensus of several label volumes, with each rater's sensitivity and specificity.
    Staple(cmd::staple::Args),
    /// Inter-user variability of a project: volumes per user, pairwise Dice, STAPLE consensus, ratings.
    Variability(cmd::variability::Args),
    /// Simulated tracing campaigns (phantom cells traced by simulated users).
    Campaign(cmd::campaign::Args),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(a) => cmd::info::run(a),
        Command::Convert(a) => cmd::convert::run(a),
        Command::Interpolate(a) => cmd::interpolate::run(a),
        Command::Advise(a) => cmd::advise::run(a),
        Command::Study(a) => cmd::study::run(a),
        Command::Bench(a) => cmd::bench::run(a),
        Command::Contours(a) => cmd::contours::run(a),
        Command::Evaluate(a) => cmd::evaluate::run(a),
        Command::Phantom(a) => cmd::phantom::run(a),
        Command::Mesh(a) => cmd::mesh::run(a),
        Command::Serve(a) => cmd::serve::run(a),
        Command::Demo(a) => cmd::demo::run(a),
        Command::User(a) => cmd::user::run(a),
        Command::Export(a) => cmd::export::run(a),
        Command::Segment(a) => cmd::segment::run(a),
        Command::Staple(a) => cmd::staple::run(a),
        Command::Variability(a) => cmd::variability::run(a),
        Command::Campaign(a) => cmd::campaign::run(a),
    };
    if let Err(e) = result {
        // One line: the chain of causes joined by ": ".
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
