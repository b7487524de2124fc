//! `loadtest [--clients 20] [--duration 60] [--cells 4] [--size 64]
//! [--preload 0]`: many clients trace different cells and slices of a fresh
//! project over loopback HTTP; prints requests/s and latencies, then checks
//! the database for lost, crossed or unexpected writes (exit 1 if any, or on
//! any error) and prints the space it takes.
use clap::Parser;
use interslice_test_support::loadtest::{LoadConfig, run_preloaded};
use std::time::Duration;

/// Concurrency test of the tracing server.
#[derive(Parser)]
#[command(name = "loadtest")]
struct Args {
    /// Concurrent clients (one user each).
    #[arg(long, default_value_t = 20)]
    clients: usize,
    /// Seconds of tracing.
    #[arg(long, default_value_t = 60.0)]
    duration: f64,
    /// Cells in the project.
    #[arg(long, default_value_t = 4)]
    cells: usize,
    /// Voxels per side of each cell.
    #[arg(long, default_value_t = 64)]
    size: usize,
    /// Contours each client first puts on one of its slices (which it then
    /// keeps tracing on), at most 100000.
    #[arg(long, default_value_t = 0)]
    preload: usize,
}

fn main() -> anyhow::Result<()> {
    let a = Args::parse();
    if !(a.duration.is_finite() && a.duration > 0.0) {
        anyhow::bail!("--duration must be a positive number of seconds");
    }
    let cfg = LoadConfig {
        clients: a.clients,
        duration: Duration::from_secs_f64(a.duration),
        cells: a.cells,
        size: a.size,
    };
    eprintln!(
        "loadtest: {} clients, {} cells of {}³, {:.0} s, {} contours preloaded per client",
        cfg.clients, cfg.cells, cfg.size, a.duration, a.preload
    );
    let report = run_preloaded(&cfg, a.preload)?;
    print!("{report}");
    if !report.clean() {
        anyhow::bail!("the database does not hold exactly the acknowledged writes");
    }
    Ok(())
}
