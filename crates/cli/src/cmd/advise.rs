//! `interslice advise SPARSE [--image IMAGE] [--method M] [--axis z]
//! [--drawn FILE] [--count N] [--json]`: the N undrawn slices whose tracing
//! is expected to improve the interpolation most, best first
//! (`interslice_interp::advise` explains the model). SPARSE, `--drawn`,
//! `--axis`, `--image` and `--method` mean what they mean for `interpolate`.
use crate::cmd::interpolate::{DEFAULT_MAX_LABELS, drawn_slices, read_image};
use anyhow::{Context, Result, bail};
use interslice_core::Axis;
use interslice_interp::{advise::advise, by_name_with_image};
use std::path::PathBuf;
use std::sync::Arc;

/// Arguments of `advise`.
#[derive(clap::Args)]
pub struct Args {
    /// The sparse label volume (drawn slices carry the tracings).
    pub sparse: PathBuf,
    #[command(flatten)]
    pub series: crate::series::SeriesArg,
    /// The intensity volume of the cell, on SPARSE's grid: the advice then
    /// comes from the image-aware interpolation.
    #[arg(long)]
    pub image: Option<PathBuf>,
    /// The interpolation method the advice is for (as for `interpolate`).
    #[arg(long)]
    pub method: Option<String>,
    /// Axis the slices were drawn along.
    #[arg(long, default_value = "z")]
    pub axis: Axis,
    /// File listing the drawn slice indices, one integer a line.
    #[arg(long)]
    pub drawn: Option<PathBuf>,
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
    let input = a
        .series
        .read_volume(&a.sparse)
        .with_context(|| format!("reading {}", a.sparse.display()))?;
    let sparse = input
        .to_labels()
        .with_context(|| format!("{} is not a label volume", a.sparse.display()))?;
    let image = match &a.image {
        Some(p) => Some(Arc::new(read_image(p, &sparse)?)),
        None => None,
    };
    let method = by_name_with_image(a.method.as_deref(), image)?;
    let drawn = drawn_slices(&sparse, a.axis, a.drawn.as_deref())?;
    let labels = interslice_interp::labels::drawn_labels(&sparse, a.axis, &drawn).len();
    if labels > DEFAULT_MAX_LABELS {
        bail!(
            "{} has {labels} labels on its drawn slices (is it an intensity image?)",
            a.sparse.display()
        );
    }
    let advice = advise(&sparse, a.axis, &drawn, a.count, method.as_ref())
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
