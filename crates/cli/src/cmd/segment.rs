//! `interslice segment IN --method M --out OUT [--classes K] [--smooth σ]
//! [--largest-component [--connectivity 6|26]] [--fill-holes] [--json]`:
//! an automated segmentation by an intensity threshold (Otsu, Rosin,
//! k-means, multi-class Otsu), the thing the ground truth exists to judge.
//!
//! Integer volumes are thresholded on native bins (one per grey level), so a
//! threshold is a grey level and foreground is `v > t`, exactly the
//! convention of the scikit-image references (`docs/segmentation.md`).
//! The output is a label volume on the input's grid: 0 background, 1 the
//! foreground (two classes) or 1..K-1 the classes above each threshold.
use anyhow::{Context, Result, bail};
use interslice_core::morph::Connectivity;
use interslice_core::segment::{SegmentMethod, SegmentParams, segment_detailed};
use std::path::PathBuf;

/// Arguments of `segment`.
#[derive(clap::Args)]
pub struct Args {
    /// The intensity volume (8- or 16-bit; i16 and f32 are accepted too).
    pub input: PathBuf,
    #[command(flatten)]
    pub series: crate::series::SeriesArg,
    /// Thresholding method: otsu, rosin, kmeans or multi-otsu.
    #[arg(long, value_parser = parse_method)]
    pub method: SegmentMethod,
    /// The label volume to write (format from the extension).
    #[arg(long)]
    pub out: PathBuf,
    /// Classes including background: 2 for otsu and rosin; 2..=5 for
    /// kmeans (default 2) and multi-otsu (default 3).
    #[arg(long, value_name = "K")]
    pub classes: Option<usize>,
    /// Gaussian smoothing before thresholding, σ in the volume's physical unit.
    #[arg(
        long,
        value_name = "SIGMA",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub smooth: f64,
    /// Keep only the largest connected component of the foreground.
    #[arg(long)]
    pub largest_component: bool,
    /// Neighbours that connect for --largest-component: 6 (faces) or 26.
    #[arg(long, value_parser = parse_connectivity, default_value = "6")]
    pub connectivity: Connectivity,
    /// Fill holes: background not connected (by faces) to the volume's border.
    #[arg(long)]
    pub fill_holes: bool,
    /// Print the thresholds and class volumes as JSON.
    #[arg(long)]
    pub json: bool,
}

fn parse_method(s: &str) -> Result<SegmentMethod, String> {
    SegmentMethod::parse(s).map_err(|e| e.to_string())
}

fn parse_connectivity(s: &str) -> Result<Connectivity, String> {
    Connectivity::parse(s).map_err(|e| e.to_string())
}

/// The parameters the arguments ask for, with the method's default classes.
fn params(a: &Args) -> SegmentParams {
    let classes = a.classes.unwrap_or(match a.method {
        SegmentMethod::MultiOtsu => 3,
        _ => 2,
    });
    SegmentParams {
        method: a.method,
        classes,
        smooth_sigma: a.smooth,
        largest_component: a.largest_component,
        connectivity: a.connectivity,
        fill_holes: a.fill_holes,
    }
}

/// Run the command.
pub fn run(a: Args) -> Result<()> {
    let p = params(&a);
    p.validate()?;
    if a.connectivity == Connectivity::Full && !a.largest_component {
        bail!("--connectivity only matters with --largest-component");
    }
    let v = a
        .series
        .read_volume(&a.input)
        .with_context(|| format!("reading {}", a.input.display()))?;
    let seg = segment_detailed(&v, &p, &interslice_core::Cancel::new())
        .with_context(|| format!("segmenting {}", a.input.display()))?;
    interslice_io::write_labels(&a.out, &seg.labels)
        .with_context(|| format!("writing {}", a.out.display()))?;
    if a.json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            #[serde(flatten)]
            summary: interslice_core::segment::SegmentSummary,
            out: &'a str,
        }
        let out = Out {
            summary: seg.summary(&p),
            out: &a.out.display().to_string(),
        };
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        let ts: Vec<String> = seg.thresholds.iter().map(|t| format!("{t}")).collect();
        println!(
            "{}: threshold{} {} (foreground v > t)",
            p.method,
            if ts.len() > 1 { "s" } else { "" },
            ts.join(", ")
        );
        let unit = seg.labels.geometry().unit.ascii();
        for (i, (n, vol)) in seg.voxels.iter().zip(seg.volumes()).enumerate() {
            println!("  label {}: {n} voxels, {vol:.3} {unit}^3", i + 1);
        }
        println!("wrote {}", a.out.display());
    }
    Ok(())
}
