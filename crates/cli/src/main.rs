//! The `interslice` command-line tool: parses arguments, calls the library
//! crates, prints. Each subcommand lives in its own module under `cmd/`.
//! Errors print as one line `error: ...` and exit with status 1 (2 for usage).

mod cmd;

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
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(a) => cmd::info::run(a),
    };
    if let Err(e) = result {
        // One line: the chain of causes joined by ": ".
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
