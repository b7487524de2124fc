//! `interslice advise SPARSE [--image IMAGE] [--method M] [--axis z]
//! [--drawn FILE] [--count N] [--json]`: the N undrawn slices whose tracing
//! is expected to improve the interpolation most, best first
//! (`interslice_interp::advise` explains the model). SPARSE, `--drawn`,
//! `--axis`, `--image` and `--method` mean what they mean for `interpolate`.
use crate::cmd::interpolate::{DEFAULT_MAX_LABELS, SparseInput, TracingArgs};
use anyhow::{Context, Result, bail};
use interslice_interp::advise::advise;
use std::path::PathBuf;

/// Arguments of `advise`.
#[derive(clap::Args)]
pub struct Args {
    /// The sparse label volume (drawn slices carry the tracings).
    pub sparse: PathBuf,
    #[command(flatten)]
    pub series: crate::series::SeriesArg,
    #[command(flatten)]
    pub tracing: TracingArgs,
    /// How many slices to suggest (1..=1000).
    #[arg(long, default_value_t = 5)]
    pub count: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Run `advise`.
pub fn run(a: Args) -> Result<()> {
    if !(1..=1000).contains(&a.count) {
        bail!("--count must be 1..=1000, got {}", a.count);
    }
    let SparseInput {
        sparse,
        method,
        image,
        drawn,
        ..
    } = a.tracing.read(&a.sparse, &a.series, DEFAULT_MAX_LABELS)?;
    let advice = advise(
        &sparse,
        a.tracing.axis,
        &drawn,
        a.count,
        a.tracing.method.as_deref(),
        image,
    )
    .with_context(|| format!("method {}", method.name()))?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&advice)?);
        return Ok(());
    }
    println!(
        "{} drawn slices along {}; predicted Dice of the interpolation now {:.4} ({})",
        advice.drawn.len(),
        advice.axis,
        advice.predicted_dice,
        method.name()
    );
    if advice.suggestions.is_empty() {
        println!("every slice between the outermost drawn ones is drawn");
    }
    println!(
        "{:>4}  {:>6}  {:>13}  {:>10}  between",
        "rank", "slice", "gain (voxels)", "Dice gain"
    );
    for (i, s) in advice.suggestions.iter().enumerate() {
        println!(
            "{:>4}  {:>6}  {:>13.0}  {:>10.4}  {}..{}",
            i + 1,
            s.slice,
            s.gain_voxels,
            s.dice_gain,
            s.between[0],
            s.between[1]
        );
    }
    Ok(())
}
