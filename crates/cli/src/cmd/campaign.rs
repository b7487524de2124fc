//! `interslice campaign simulate DIR [--tracers N] [--cells C] [--size S]
//! [--labels 1,2] [--seed X]`: a tracing campaign by simulated tracers, for
//! testing and demonstrating `interslice variability` without people.
//!
//! The project folder gets phantom cells (as `interslice demo` writes them,
//! with their exact labels in `DIR/ground_truth/`); then each simulated
//! tracer traces every cell into the project's database through the store,
//! as the web UI would: on every `skip + 1`-th slice along z between the
//! first and the last slice of each structure (both always drawn), the exact
//! outline is taken (outer boundaries, `trace::mask_polygons`), resampled to
//! a point every 2 pixels as a hand-placed polyline, and each point moved
//! along the outline's normal by the tracer's bias plus Gaussian noise
//! smoothed along the contour (a hand wobbles over a few points, it does not
//! jump independently at each one). Tracers differ in noise, bias and skip
//! ([`TRACERS`]); the first two also rate an Otsu segmentation of each cell.
//! Each contour records [`SECONDS_PER_CONTOUR`] of drawing time, so the
//! report's minutes per cell are those of a tracer of the 2014 study.
//! Everything is seeded: the same arguments give the same database content.
use anyhow::{Context, Result, bail};
use interslice_core::morph::Connectivity;
use interslice_core::phantom::cell_seed;
use interslice_core::segment::{SegmentMethod, SegmentParams, segment};
use interslice_core::trace::{mask_polygons, signed_area};
use interslice_core::{Axis, LabelVolume};
use interslice_store::{NewContour, SliceKey, Store};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::path::{Path, PathBuf};

/// Drawing time recorded per simulated contour (s): within the 30–60 s per
/// contour of the 2014 study, the default of `study --seconds-per-contour`.
pub const SECONDS_PER_CONTOUR: f64 = 45.0;

/// Arguments of `campaign`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub action: Action,
}

/// What to do.
#[derive(clap::Subcommand)]
pub enum Action {
    /// Write phantom cells and simulated tracers' contours into a project.
    Simulate(SimulateArgs),
}

/// Arguments of `campaign simulate`.
#[derive(clap::Args)]
pub struct SimulateArgs {
    /// The project folder (created; existing cells are kept).
    pub dir: PathBuf,
    /// Number of simulated tracers (1 to 6; their settings are fixed, see the docs).
    #[arg(long, default_value_t = 3)]
    pub tracers: usize,
    /// Number of phantom cells.
    #[arg(long, default_value_t = 3)]
    pub cells: u32,
    /// Voxels per side of each phantom cell.
    #[arg(long, default_value_t = 96)]
    pub size: usize,
    /// Labels to trace (1 cell, 2 nucleus, 3.. nucleoli).
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub labels: Vec<u16>,
    /// Seed of the contour noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// One simulated tracer.
#[derive(Debug, Clone, Copy)]
pub struct Tracer {
    /// User name in the database.
    pub name: &'static str,
    /// Standard deviation of the contour-point noise, pixels.
    pub noise: f64,
    /// Systematic offset along the outward normal, pixels (> 0 draws outside).
    pub bias: f64,
    /// Slices skipped between two drawn slices.
    pub skip: usize,
}

/// The simulated tracers, from careful to hasty.
pub const TRACERS: [Tracer; 6] = [
    Tracer {
        name: "tracer-a",
        noise: 0.3,
        bias: 0.0,
        skip: 2,
    },
    Tracer {
        name: "tracer-b",
        noise: 0.7,
        bias: 0.5,
        skip: 4,
    },
    Tracer {
        name: "tracer-c",
        noise: 1.0,
        bias: -0.5,
        skip: 6,
    },
    Tracer {
        name: "tracer-d",
        noise: 0.5,
        bias: 0.25,
        skip: 3,
    },
    Tracer {
        name: "tracer-e",
        noise: 1.5,
        bias: 0.0,
        skip: 8,
    },
    Tracer {
        name: "tracer-f",
        noise: 0.8,
        bias: -0.25,
        skip: 5,
    },
];

/// Distance between the points of a simulated hand-drawn contour, pixels.
const POINT_STEP: f64 = 2.0;
/// Half-width of the moving average that correlates the noise along a contour.
const NOISE_SMOOTHING: usize = 2;

/// Run the command.
pub fn run(a: Args) -> Result<()> {
    match a.action {
        Action::Simulate(s) => simulate(&s),
    }
}

fn simulate(a: &SimulateArgs) -> Result<()> {
    if !(1..=TRACERS.len()).contains(&a.tracers) {
        bail!(
            "--tracers must be 1 to {}, not {}",
            TRACERS.len(),
            a.tracers
        );
    }
    if a.cells == 0 {
        bail!("--cells must be at least 1");
    }
    if a.labels.is_empty() || a.labels.contains(&0) {
        bail!("--labels lists label ids >= 1 (1 cell, 2 nucleus, 3.. nucleoli)");
    }
    super::demo::write_cells(&a.dir, a.size, a.cells)?;
    let db = interslice_store::default_db_path(&a.dir);
    let store = Store::open(&db).with_context(|| format!("opening {}", db.display()))?;
    let known: Vec<u16> = store.labels()?.iter().map(|l| l.id).collect();
    if let Some(l) = a.labels.iter().find(|l| !known.contains(l)) {
        bail!("label {l} is not one of the project's labels {known:?}");
    }
    let cells = interslice_project::cells::scan(&a.dir)
        .with_context(|| format!("listing {}", a.dir.display()))?;
    for n in 1..=u64::from(a.cells) {
        let name = format!("cell_{n:03}");
        let Some(path) = cells.get(&name) else {
            bail!("{} has no cell {name}", a.dir.display());
        };
        let rel = path.strip_prefix(&a.dir).unwrap_or(path);
        store.upsert_cell(&name, &rel.to_string_lossy())?;
        let truth_path = a
            .dir
            .join("ground_truth")
            .join(format!("{name}_labels.nii.gz"));
        let truth = interslice_io::read_labels(&truth_path)
            .with_context(|| format!("reading {}", truth_path.display()))?;
        for (t, tracer) in TRACERS.iter().take(a.tracers).enumerate() {
            let user = store.ensure_user(tracer.name)?;
            if !store.drawn_labels(&name, user.id)?.is_empty() {
                eprintln!("{name}: {} has traced it already, kept", tracer.name);
                continue;
            }
            let seed = cell_seed(a.seed, n * 16 + t as u64);
            let count = trace_cell(&store, &name, user.id, &truth, &a.labels, tracer, seed)?;
            eprintln!("{name}: {} drew {count} contours", tracer.name);
        }
        rate_otsu(&store, &a.dir.join(rel), &name, &truth, a.tracers)?;
    }
    println!(
        "{} cells traced by {} simulated tracers in {}",
        a.cells,
        a.tracers,
        db.display()
    );
    Ok(())
}

/// The slices a tracer draws between `first` and `last`: every `skip + 1`-th
/// counted from `first`, and `last`.
fn drawn_slices(first: usize, last: usize, skip: usize) -> Vec<usize> {
    interslice_core::slice::every_nth_slice(first, last, skip + 1)
}

/// Draw one tracer's contours of `labels` on one cell; returns how many.
fn trace_cell(
    store: &Store,
    cell: &str,
    user_id: i64,
    truth: &LabelVolume,
    labels: &[u16],
    tracer: &Tracer,
    seed: u64,
) -> Result<usize> {
    let axis = Axis::Z;
    let (w, h) = truth.slice_shape(axis);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut count = 0;
    for &label in labels {
        let present: Vec<usize> = (0..truth.slice_count(axis))
            .filter(|&k| truth.slice(axis, k).is_ok_and(|s| s.contains(&label)))
            .collect();
        let (Some(&first), Some(&last)) = (present.first(), present.last()) else {
            continue;
        };
        for k in drawn_slices(first, last, tracer.skip) {
            let slice = truth.slice(axis, k)?;
            let mask: Vec<bool> = slice.iter().map(|&l| l == label).collect();
            let key = SliceKey {
                cell: cell.to_string(),
                user_id,
                label,
                axis,
                index: k,
            };
            let outlines: Vec<Vec<[f64; 2]>> = mask_polygons(&mask, w, h)
                .into_iter()
                .filter(|p| signed_area(p) > 0.0)
                .collect();
            if outlines.is_empty() {
                // A gap inside the structure's range: drawn, and empty.
                store.mark_empty(&key)?;
                continue;
            }
            for outline in outlines {
                let points = hand_drawn(&outline, tracer, w, h, &mut rng);
                if points.len() < 3 {
                    continue;
                }
                // Built as the API receives it, so optional fields keep their defaults.
                let contour: NewContour = serde_json::from_value(serde_json::json!({
                    "points": points,
                    "tool": "simulated",
                    "duration_ms": SECONDS_PER_CONTOUR * 1000.0,
                }))?;
                store.add_contour(&key, contour, None)?;
                count += 1;
            }
        }
    }
    Ok(count)
}

/// The outline resampled every [`POINT_STEP`] pixels, each point moved along
/// the outward normal by the tracer's bias and smoothed Gaussian noise, and
/// kept inside the slice.
fn hand_drawn(
    outline: &[[f64; 2]],
    tracer: &Tracer,
    w: usize,
    h: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<[f64; 2]> {
    let n = outline.len();
    let perimeter: f64 = (0..n).map(|i| dist(outline[i], outline[(i + 1) % n])).sum();
    let m = ((perimeter / POINT_STEP).round() as usize).max(4);
    let step = perimeter / m as f64;
    // Resample at equal arc length.
    let mut pts = Vec::with_capacity(m);
    let (mut seg, mut along) = (0usize, 0.0f64);
    for s in 0..m {
        let target = s as f64 * step;
        while along + dist(outline[seg], outline[(seg + 1) % n]) < target && seg + 1 < n {
            along += dist(outline[seg], outline[(seg + 1) % n]);
            seg += 1;
        }
        let (a, b) = (outline[seg], outline[(seg + 1) % n]);
        let l = dist(a, b).max(1e-12);
        let t = ((target - along) / l).clamp(0.0, 1.0);
        pts.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
    }
    // Noise correlated over a few points, rescaled to the tracer's σ.
    let white: Vec<f64> = match Normal::new(0.0, 1.0) {
        Ok(d) => (0..m).map(|_| d.sample(rng)).collect(),
        Err(_) => vec![0.0; m],
    };
    let win = 2 * NOISE_SMOOTHING + 1;
    let scale = tracer.noise * (win as f64).sqrt() / win as f64;
    let noise: Vec<f64> = (0..m)
        .map(|i| {
            (0..win)
                .map(|d| white[(i + m + d - NOISE_SMOOTHING) % m])
                .sum::<f64>()
                * scale
        })
        .collect();
    (0..m)
        .map(|i| {
            let (p, q) = (pts[(i + m - 1) % m], pts[(i + 1) % m]);
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            let l = dx.hypot(dy).max(1e-12);
            // Outward normal of a counter-clockwise outline.
            let (nx, ny) = (dy / l, -dx / l);
            let off = tracer.bias + noise[i];
            [
                (pts[i][0] + off * nx).clamp(0.0, w as f64),
                (pts[i][1] + off * ny).clamp(0.0, h as f64),
            ]
        })
        .collect()
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// An Otsu segmentation of the cell (largest component, holes filled) stored
/// with the cell, rated by the first two tracers: the score follows its Dice
/// against the exact cell (label >= 1), as a reviewer's judgement would.
fn rate_otsu(
    store: &Store,
    image: &Path,
    cell: &str,
    truth: &LabelVolume,
    tracers: usize,
) -> Result<()> {
    if !store.segmentations(cell)?.is_empty() {
        return Ok(());
    }
    let v = interslice_io::read_volume(image)
        .with_context(|| format!("reading {}", image.display()))?;
    let p = SegmentParams {
        method: SegmentMethod::Otsu,
        largest_component: true,
        connectivity: Connectivity::Face,
        fill_holes: true,
        ..Default::default()
    };
    let labels = segment(&v, &p, &interslice_core::Cancel::new())?;
    let params = serde_json::json!({
        "classes": p.classes, "smooth": p.smooth_sigma,
        "largest_component": p.largest_component, "fill_holes": p.fill_holes,
        "connectivity": p.connectivity.neighbours(),
    });
    let meta = store.save_segmentation(cell, "otsu", "otsu", &params, &labels, None)?;
    let c =
        interslice_core::metrics::overlap_masks(&truth.map(|l| l >= 1), &labels.map(|l| l >= 1))?;
    let dice = c.dice().unwrap_or(0.0);
    for (t, tracer) in TRACERS.iter().take(tracers.min(2)).enumerate() {
        let user = store.ensure_user(tracer.name)?;
        // The careful tracer is the stricter judge: one point less.
        let strict = u8::from(t == 0);
        let score = ((1.0 + 4.0 * dice).round() as u8)
            .saturating_sub(strict)
            .clamp(1, 5);
        let comment = format!("simulated rating: Dice {dice:.3} against the exact cell outline");
        store.add_rating(cell, user.id, &meta.id.to_string(), score, &comment)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drawn_slices_keep_both_ends() {
        assert_eq!(drawn_slices(3, 10, 2), vec![3, 6, 9, 10]);
        assert_eq!(drawn_slices(3, 9, 2), vec![3, 6, 9]);
        assert_eq!(drawn_slices(5, 5, 4), vec![5]);
    }

    #[test]
    fn noiseless_hand_drawing_follows_the_outline() {
        // A 10 x 6 rectangle, counter-clockwise: resampled points stay on it.
        let rect = [[2.0, 2.0], [12.0, 2.0], [12.0, 8.0], [2.0, 8.0]];
        let t = Tracer {
            name: "t",
            noise: 0.0,
            bias: 0.0,
            skip: 0,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let p = hand_drawn(&rect, &t, 20, 20, &mut rng);
        assert_eq!(p.len(), 16);
        assert!((signed_area(&p) - 60.0).abs() < 1e-9);
        // An outward bias of one pixel grows the area by about perimeter x 1.
        let out = Tracer { bias: 1.0, ..t };
        let q = hand_drawn(&rect, &out, 20, 20, &mut rng);
        let grown = signed_area(&q);
        assert!(grown > 60.0 + 25.0 && grown < 60.0 + 32.0 + 4.0, "{grown}");
    }
}
