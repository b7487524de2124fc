//! `interslice demo [DIR] [--bind ADDR] [--size S] [--count N]`: write a few
//! phantom cells into a project folder (once), then serve it.
//!
//! Intensities go to `DIR/cell_NNN.nii.gz` (the cells to trace); their exact
//! label volumes to `DIR/ground_truth/` (a reserved folder the server does not
//! list as cells), so a tracing can be measured against the truth.
use anyhow::{Context, Result};
use interslice_core::phantom::{PhantomParams, cell_seed, generate};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

/// Arguments of `demo`.
#[derive(clap::Args)]
pub struct Args {
    /// The project folder (created; existing cells and tracings are kept).
    #[arg(default_value = "demo-data/project")]
    pub dir: PathBuf,
    /// Address to listen on.
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub bind: SocketAddr,
    /// Voxels per side of each phantom cell.
    #[arg(long, default_value_t = 128)]
    pub size: usize,
    /// Number of phantom cells.
    #[arg(long, default_value_t = 3)]
    pub count: u32,
    /// Write the cells and exit without serving.
    #[arg(long)]
    pub no_serve: bool,
}

/// Run the command.
pub fn run(a: Args) -> Result<()> {
    write_cells(&a.dir, a.size, a.count)?;
    if a.no_serve {
        return Ok(());
    }
    let mut config = interslice_server::Config::new(&a.dir);
    config.bind = a.bind;
    // The demo is cell CT: its components are the study's set.
    config.components = Some(interslice_core::components::Components::cell_ct());
    super::serve::serve(config)
}

/// Write the phantom cells that are not there yet (8-bit, seed 1).
pub fn write_cells(dir: &Path, size: usize, count: u32) -> Result<()> {
    let truth = dir.join("ground_truth");
    std::fs::create_dir_all(&truth).with_context(|| format!("creating {}", truth.display()))?;
    for n in 1..=u64::from(count) {
        let image = dir.join(format!("cell_{n:03}.nii.gz"));
        let labels = truth.join(format!("cell_{n:03}_labels.nii.gz"));
        if image.is_file() && labels.is_file() {
            continue;
        }
        let params = PhantomParams {
            size,
            seed: cell_seed(1, n),
            bits: 8,
            noise: 0.02,
        };
        let ph = generate(&params).with_context(|| format!("phantom cell {n}"))?;
        interslice_io::write_volume(&image, &ph.intensity)
            .with_context(|| format!("writing {}", image.display()))?;
        interslice_io::write_labels(&labels, &ph.labels)
            .with_context(|| format!("writing {}", labels.display()))?;
        eprintln!("wrote {}", image.display());
    }
    Ok(())
}
