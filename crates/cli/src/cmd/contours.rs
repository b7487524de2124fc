//! `interslice contours rasterize|extract`: move between the contours file
//! (`docs/contours-format.md`) and label volumes.
//!
//! `rasterize` paints every contour (any axis) into a label volume of the
//! file's geometry and can list the drawn slices of one axis — traced or
//! drawn empty — in the one-integer-a-line form `interpolate --drawn` reads,
//! so a tracing becomes an interpolation input without losing its
//! known-empty slices. `extract` traces the slices of a label volume into
//! contours (exact: rasterising them gives the slices back).
use anyhow::{Context, bail};
use interslice_core::contour_file::{self, ContourFile, LabelInfo};
use interslice_core::raster::contours_to_labels;
use interslice_core::trace::{mask_polygons, signed_area};
use interslice_core::{Axis, Contour, SliceRef};
use std::collections::BTreeSet;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `contours`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Subcommand)]
enum Command {
    /// Paint a contours file into a label volume.
    Rasterize {
        /// The contours file (JSON).
        input: PathBuf,
        /// The label volume to write (format by extension).
        #[arg(long)]
        out: PathBuf,
        /// Also write the drawn slices along `--axis` (one index a line),
        /// for `interpolate --drawn`.
        #[arg(long)]
        drawn_out: Option<PathBuf>,
        /// Axis of the drawn slices listed by `--drawn-out`.
        #[arg(long, default_value = "z", value_parser = parse_axis)]
        axis: Axis,
    },
    /// Trace the slices of a label volume into a contours file.
    Extract {
        /// The label volume.
        input: PathBuf,
        /// The contours file to write (JSON).
        #[arg(long)]
        out: PathBuf,
        /// Axis of the slices to trace.
        #[arg(long, default_value = "z", value_parser = parse_axis)]
        axis: Axis,
        /// Trace only every N-th slice (the first and last non-empty slices
        /// always), to simulate a sparse tracing.
        #[arg(long, default_value_t = 1)]
        every: usize,
        /// Author recorded on every contour.
        #[arg(long, default_value = "import")]
        author: String,
    },
}

fn parse_axis(s: &str) -> Result<Axis, String> {
    Axis::parse(s).map_err(|e| e.to_string())
}

/// Run `contours`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
        Command::Rasterize {
            input,
            out,
            drawn_out,
            axis,
        } => rasterize(&input, &out, drawn_out.as_deref(), axis),
        Command::Extract {
            input,
            out,
            axis,
            every,
            author,
        } => extract(&input, &out, axis, every, &author),
    }
}

fn read_file(path: &Path) -> anyhow::Result<ContourFile> {
    Ok(interslice_project::contour_files::read(path)?)
}

fn rasterize(input: &Path, out: &Path, drawn_out: Option<&Path>, axis: Axis) -> anyhow::Result<()> {
    let file = read_file(input)?;
    let labels = contours_to_labels(&file.geometry, &file.contours)
        .with_context(|| format!("{}", input.display()))?;
    interslice_io::write_labels(out, &labels)?;
    let drawn: BTreeSet<usize> = file
        .contours
        .iter()
        .map(|c| c.slice)
        .chain(file.drawn_empty.iter().map(|e| e.slice))
        .filter(|s| s.axis == axis)
        .map(|s| s.index)
        .collect();
    if let Some(path) = drawn_out {
        let text: String = drawn.iter().map(|i| format!("{i}\n")).collect();
        interslice_io::raw::write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    }
    println!(
        "{} contours ({} drawn slices along {axis}) -> {}",
        file.contours.len(),
        drawn.len(),
        out.display()
    );
    Ok(())
}

/// The slices to trace: every `every`-th non-empty slice counted from the
/// first non-empty one, plus the last non-empty one.
fn sparse_indices(non_empty: &[usize], every: usize) -> Vec<usize> {
    let (Some(&first), Some(&last)) = (non_empty.first(), non_empty.last()) else {
        return Vec::new();
    };
    interslice_core::slice::every_nth_slice(first, last, every)
}

fn extract(input: &Path, out: &Path, axis: Axis, every: usize, author: &str) -> anyhow::Result<()> {
    if every == 0 {
        bail!("--every must be at least 1");
    }
    let labels = interslice_io::read_labels(input)?;
    let n = labels.slice_count(axis);
    let (width, height) = labels.slice_shape(axis);
    let slices: Vec<Vec<u16>> = (0..n)
        .map(|k| labels.slice(axis, k))
        .collect::<Result<_, _>>()?;
    let non_empty: Vec<usize> = (0..n)
        .filter(|&k| slices[k].iter().any(|&l| l != 0))
        .collect();
    let created = humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string();
    let mut file = ContourFile::new(labels.geometry().clone());
    let present: BTreeSet<u16> = labels.label_counts().into_iter().map(|(l, _)| l).collect();
    let known: BTreeSet<u16> = file.labels.iter().map(|l| l.id).collect();
    for &id in present.difference(&known).filter(|&&l| l != 0) {
        file.labels.push(LabelInfo {
            id,
            name: format!("Label {id}"),
            color: "#808080".into(),
        });
    }
    for k in sparse_indices(&non_empty, every) {
        let slice = SliceRef { axis, index: k };
        for &label in present.iter().filter(|&&l| l != 0) {
            let mask: Vec<bool> = slices[k].iter().map(|&l| l == label).collect();
            if !mask.iter().any(|&b| b) {
                continue;
            }
            // Outer boundaries only: the contours of a label on a slice are
            // united, so a hole cannot be expressed and is filled.
            for points in mask_polygons(&mask, width, height)
                .into_iter()
                .filter(|p| signed_area(p) > 0.0)
            {
                file.contours
                    .push(Contour::new(slice, label, points, author, &created));
            }
        }
    }
    let text = contour_file::write(&file)?;
    interslice_io::raw::write_atomic(out, |w| w.write_all(text.as_bytes()))?;
    println!(
        "{} contours on {} slices along {axis} -> {}",
        file.contours.len(),
        sparse_indices(&non_empty, every).len(),
        out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::sparse_indices;

    #[test]
    fn sparse_keeps_first_last_and_every_nth() {
        assert_eq!(sparse_indices(&[], 3), Vec::<usize>::new());
        assert_eq!(sparse_indices(&[4, 5, 6, 7, 8, 9], 3), vec![4, 7, 9]);
        assert_eq!(sparse_indices(&[4, 5, 6, 7], 3), vec![4, 7]);
        assert_eq!(sparse_indices(&[2], 5), vec![2]);
        assert_eq!(sparse_indices(&[1, 2, 3], 1), vec![1, 2, 3]);
    }
}
