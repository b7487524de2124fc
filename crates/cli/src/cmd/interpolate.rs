//! `interslice interpolate SPARSE --out OUT [--image IMAGE] [--confidence OUT2]
//! [--method M] [--axis z|y|x] [--drawn FILE]` and `interslice interpolate --list`.
//!
//! SPARSE is a label volume whose drawn slices carry the tracings. Drawn
//! slices are the slices with any non-zero voxel along `--axis`, or exactly
//! the indices listed in `--drawn FILE` (one integer a line; a listed slice
//! without voxels is a known-empty slice). Every label is interpolated on its
//! own; OUT has the geometry and voxel type of SPARSE, in the format its
//! extension names. With `--image` (an intensity volume on SPARSE's grid) and
//! no `--method`, the image-guided method is used; `--confidence OUT2` writes
//! the confidence per voxel (f32 in `[0.5, 1]`).
//!
//! SPARSE may also be a contours file (`.json`, `docs/contours-format.md`):
//! then each label is interpolated from its own traced and drawn-empty
//! slices, along every axis with at least two of them combined into one
//! result (`docs/interpolation.md`, "Several orientations"), by the function the server's
//! export uses (`interslice_project::contour_files::interpolate`), so a
//! tracing gives the same label volume here and from the server. OUT is a
//! label volume on the file's grid.
use anyhow::{Context, Result, bail};
use interslice_core::{AnyVolume, Axis, LabelVolume, Volume};
use interslice_interp::drawn::{nonempty_slices, parse_drawn};
use interslice_interp::image::{Conditioned, intensity_f32};
use interslice_interp::{
    DEFAULT_METHOD, IMAGE_METHOD, Interpolator, by_name_with_image, interpolate_labels,
    interpolate_labels_with_confidence, methods,
};
use std::path::{Path, PathBuf};

/// Arguments of `interpolate`.
#[derive(clap::Args)]
pub struct Args {
    /// The sparse label volume (drawn slices carry the tracings), or a
    /// contours file (.json).
    #[arg(required_unless_present = "list")]
    pub sparse: Option<PathBuf>,
    #[command(flatten)]
    pub series: crate::series::SeriesArg,
    /// Output label volume; the format follows the extension.
    #[arg(long, required_unless_present = "list")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub tracing: TracingArgs,
    /// Also write the confidence per voxel (f32, 0.5 = a coin toss, 1 = sure) here.
    #[arg(long)]
    pub confidence: Option<PathBuf>,
    /// Print the available methods (the default first) and exit.
    #[arg(long)]
    pub list: bool,
    /// Most labels interpolated (each label is interpolated on its own, so an
    /// intensity image read as labels would run for minutes).
    #[arg(long, default_value_t = DEFAULT_MAX_LABELS)]
    pub max_labels: usize,
}

/// The options of a sparse tracing that `interpolate` and `advise` share.
#[derive(clap::Args)]
pub struct TracingArgs {
    /// Interpolation method (see `interpolate --list`); the default is the
    /// best measured one (`image-guided` when `--image` is given).
    #[arg(long)]
    pub method: Option<String>,
    /// The intensity volume of the cell, on SPARSE's grid, for the image methods.
    #[arg(long)]
    pub image: Option<PathBuf>,
    /// Axis the slices were drawn along.
    #[arg(long, default_value = "z")]
    pub axis: Axis,
    /// File listing the drawn slice indices, one integer a line (`#` comments allowed).
    #[arg(long)]
    pub drawn: Option<PathBuf>,
}

/// A sparse label volume read for `interpolate` or `advise`: the file's
/// volume (its voxel type is the output's), its labels, the method (the
/// image-aware one with `--image`) and the drawn slices.
pub struct SparseInput {
    pub volume: AnyVolume,
    pub sparse: LabelVolume,
    pub method: Box<dyn Interpolator>,
    pub image: Option<Conditioned>,
    pub drawn: Vec<usize>,
}

impl TracingArgs {
    /// Read `path` (through `series` for DICOM) and everything these
    /// options name; an error when more than `max_labels` labels are drawn.
    pub fn read(
        &self,
        path: &Path,
        series: &crate::series::SeriesArg,
        max_labels: usize,
    ) -> Result<SparseInput> {
        let volume = series
            .read_volume(path)
            .with_context(|| format!("reading {}", path.display()))?;
        let sparse = volume
            .to_labels()
            .with_context(|| format!("{} is not a label volume", path.display()))?;
        let image = match &self.image {
            Some(p) => Some(Conditioned::from(read_image(p, &sparse)?)),
            None => None,
        };
        let method = by_name_with_image(self.method.as_deref(), image.clone())?;
        let drawn = drawn_slices(&sparse, self.axis, self.drawn.as_deref())?;
        let labels = interslice_interp::labels::drawn_labels(&sparse, self.axis, &drawn).len();
        if labels > max_labels {
            bail!(
                "{} has {labels} labels on its drawn slices, more than --max-labels {max_labels} \
                 (is it an intensity image? pass --max-labels {labels} to interpolate every one)",
                path.display(),
            );
        }
        Ok(SparseInput {
            volume,
            sparse,
            method,
            image,
            drawn,
        })
    }
}

/// Default of `--max-labels` ([`interslice_interp::labels::DEFAULT_MAX_LABELS`]).
pub use interslice_interp::labels::DEFAULT_MAX_LABELS;

/// Run `interpolate`.
pub fn run(a: Args) -> Result<()> {
    if a.list {
        for m in methods() {
            let tag = if m.name() == DEFAULT_METHOD {
                " (default)"
            } else {
                ""
            };
            println!("{:<20} {}{tag}", m.name(), m.description());
        }
        println!(
            "{IMAGE_METHOD:<20} shape prior fused with the intensity likelihood of the drawn slices, \
             weight chosen by leave-one-out (needs --image; the default with it)"
        );
        return Ok(());
    }
    let (Some(sparse_path), Some(out)) = (a.sparse.clone(), a.out.clone()) else {
        bail!("interpolate needs SPARSE and --out (or --list)");
    };
    let started = std::time::Instant::now();
    if interslice_project::contour_files::is_contours_file(&sparse_path) {
        return interpolate_contours(&sparse_path, &out, &a);
    }
    let SparseInput {
        volume: input,
        sparse,
        method,
        drawn,
        ..
    } = a.tracing.read(&sparse_path, &a.series, a.max_labels)?;
    let axis = a.tracing.axis;
    let spin = crate::progress::spinner(&format!("interpolating with {}", method.name()));
    let (result, confidence) = if a.confidence.is_some() {
        let (l, c) = interpolate_labels_with_confidence(method.as_ref(), &sparse, axis, &drawn)
            .with_context(|| format!("method {}", method.name()))?;
        (l, Some(c))
    } else {
        let l = interpolate_labels(method.as_ref(), &sparse, axis, &drawn)
            .with_context(|| format!("method {}", method.name()))?;
        (l, None)
    };
    let written = same_type(&input, result)?;
    interslice_io::write_volume(&out, &written)
        .with_context(|| format!("writing {}", out.display()))?;
    if let (Some(p), Some(c)) = (&a.confidence, confidence) {
        interslice_io::write_volume(p, &AnyVolume::F32(c))
            .with_context(|| format!("writing {}", p.display()))?;
    }
    spin.finish_and_clear();
    println!(
        "{}: {} drawn slices along {}, {:.2} s -> {}",
        method.name(),
        drawn.len(),
        axis,
        started.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}

/// `interpolate CONTOURS.json --out OUT`: the label volume of a contours file.
fn interpolate_contours(path: &Path, out: &Path, a: &Args) -> Result<()> {
    let max_labels = a.max_labels;
    if a.tracing.image.is_some() || a.confidence.is_some() || a.tracing.drawn.is_some() {
        bail!(
            "--image, --confidence and --drawn apply to label volumes; a contours file \
             carries its drawn slices and every axis (rasterize it with `contours rasterize` \
             to use them)"
        );
    }
    let started = std::time::Instant::now();
    let file = interslice_project::contour_files::read(path)?;
    let labels: std::collections::BTreeSet<u16> = file
        .contours
        .iter()
        .map(|c| c.label)
        .chain(file.drawn_empty.iter().map(|d| d.label))
        .collect();
    if labels.len() > max_labels {
        bail!(
            "{} has {} labels, more than --max-labels {max_labels}",
            path.display(),
            labels.len()
        );
    }
    let method = interslice_project::methods::method_by_name(a.tracing.method.as_deref())?;
    let spin = crate::progress::spinner(&format!("interpolating with {}", method.name()));
    let name = path.display().to_string();
    let result = interslice_project::contour_files::interpolate(
        &file,
        &name,
        method.as_ref(),
        None,
        &interslice_core::Cancel::new(),
    )?;
    interslice_io::write_labels(out, &result)
        .with_context(|| format!("writing {}", out.display()))?;
    spin.finish_and_clear();
    println!(
        "{}: {} contours of {} label(s), {:.2} s -> {}",
        method.name(),
        file.contours.len(),
        labels.len(),
        started.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}

/// The intensity volume at `path` as f32; an error unless it lies on the
/// grid of `sparse`.
pub fn read_image(path: &Path, sparse: &LabelVolume) -> Result<Volume<f32>> {
    let img = interslice_io::read_volume(path)
        .with_context(|| format!("reading image {}", path.display()))?;
    img.geometry()
        .ensure_same_grid(sparse.geometry())
        .with_context(|| format!("image {} is not on the tracing's grid", path.display()))?;
    Ok(intensity_f32(&img))
}

/// The drawn slices: the `--drawn` file's indices, or the non-empty slices.
pub fn drawn_slices(sparse: &LabelVolume, axis: Axis, file: Option<&Path>) -> Result<Vec<usize>> {
    let count = sparse.slice_count(axis);
    let drawn = match file {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("reading drawn list {}", p.display()))?;
            parse_drawn(&text, count).with_context(|| p.display().to_string())?
        }
        None => nonempty_slices(sparse, axis),
    };
    if drawn.len() < 2 {
        bail!(
            "interpolation needs at least two drawn slices along {axis}, found {} \
             (drawn slices are those with a non-zero voxel, or listed with --drawn)",
            drawn.len()
        );
    }
    Ok(drawn)
}

/// The interpolated labels in the voxel type of the input (labels fit: they
/// come from the input).
fn same_type(input: &AnyVolume, labels: LabelVolume) -> Result<AnyVolume> {
    let (g, data) = labels.into_parts();
    Ok(match input {
        AnyVolume::U8(_) => AnyVolume::U8(Volume::from_vec(
            g,
            data.iter().map(|&x| x as u8).collect(),
        )?),
        AnyVolume::U16(_) => AnyVolume::U16(Volume::from_vec(g, data)?),
        AnyVolume::I16(_) => AnyVolume::I16(Volume::from_vec(
            g,
            data.iter().map(|&x| x as i16).collect(),
        )?),
        AnyVolume::F32(_) => AnyVolume::F32(Volume::from_vec(
            g,
            data.iter().map(|&x| f32::from(x)).collect(),
        )?),
    })
}
