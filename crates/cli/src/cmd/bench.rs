//! `interslice bench [--data DIR] [--skips 1,3,5,9] [--methods a,b] [--masks m,n]
//! [--per-mask] [--json FILE] [--speed]`: the interpolation benchmark on the
//! development data.
//!
//! Every mask is run through the protocol of [`interslice_interp::protocol`]
//! (first and last non-empty slice and every `(k + 1)`-th slice drawn along
//! z, Dice on the skipped slices) with each method, the image-guided one on
//! the mask's own intensity volume. Masks are cropped to their box grown by a
//! margin (the interpolation of one mask does not see beyond it). The data
//! (`scripts/fetch-interp-data.sh` prints DIR): the noisy phantom (generated),
//! stardist's synthetic 3D nuclei (as one mask, and as a label volume scored
//! by the label-matched Dice), pyradiomics' CT and MR cases and ITK's T1
//! with its k-means classes, the MNI template's T1 with its grey and white
//! matter (the classes more likely than not), and twelve deep grey and medial
//! temporal structures of the AAL atlas, traced by hand on the T1 of one
//! subject ([`AAL_STRUCTURES`]); a family whose files are missing is skipped
//! with a note. `--speed` times the methods on phantom cells of 256×256×60 and
//! 197×233×189 voxels instead.
use anyhow::{Context, Result, bail};
use interslice_core::phantom::{PhantomParams, generate};
use interslice_core::{AnyVolume, Axis, LabelVolume, Mask, Volume};
use interslice_interp::ceiling::AreaCeiling;
use interslice_interp::image::walk::RandomWalk;
use interslice_interp::image::{Conditioned, ImageGuided, intensity_f32};
use interslice_interp::protocol::{bounding_box, crop, score, score_labels};
use interslice_interp::{Interpolator, by_name};
use serde::Serialize;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Arguments of `bench`.
#[derive(clap::Args)]
pub struct Args {
    /// Folder of the development data (printed by scripts/fetch-interp-data.sh).
    #[arg(long, default_value = "target/interp-data")]
    pub data: PathBuf,
    /// Numbers of skipped slices, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,3,5,9")]
    pub skips: Vec<usize>,
    /// Methods, comma-separated (`image-guided` and the image anchor
    /// `random-walk`, a 3D random walker seeded by the drawn slices, run where
    /// the mask has an image; `area-ceiling`, not a method but a bound read
    /// from the truth, on the masks of one structure).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "nearest,shape-based,shape-aligned,shape-area,shape-auto,image-guided,random-walk"
    )]
    pub methods: Vec<String>,
    /// Only these masks, comma-separated, as `--per-mask` names them (e.g.
    /// `brain1,T1-class3`); every mask whose data is there when not given.
    #[arg(long, value_delimiter = ',')]
    pub masks: Vec<String>,
    /// Also print one line per mask.
    #[arg(long)]
    pub per_mask: bool,
    /// Write every row as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Time the methods on large phantom volumes instead.
    #[arg(long)]
    pub speed: bool,
}

/// One mask or label volume of the benchmark.
struct Case {
    family: &'static str,
    name: String,
    truth: Truth,
    image: Option<Conditioned>,
}

/// What a case is traced from.
enum Truth {
    /// One structure.
    Mask(Mask),
    /// A segmentation with a label per object (every label interpolated on
    /// its own, scored by the label-matched Dice).
    Labels(LabelVolume),
}

/// One measured (mask, method, k).
#[derive(Serialize)]
struct Row {
    family: &'static str,
    mask: String,
    method: String,
    skip: usize,
    dice_skipped: f64,
    dice_whole: f64,
    seconds: f64,
}

/// Largest number of skipped slices accepted.
const MAX_SKIP: usize = 50;
/// Margin of the crop around a mask, in voxels.
const MARGIN: usize = 8;

/// Run `bench`.
pub fn run(a: Args) -> Result<()> {
    if a.skips.is_empty() || a.skips.iter().any(|&k| k == 0 || k > MAX_SKIP) {
        bail!("--skips: give numbers of skipped slices in 1..={MAX_SKIP}");
    }
    if a.speed {
        return speed(&a.methods);
    }
    let cases = selected(load_cases(&a.data)?, &a.masks)?;
    let mut rows = Vec::new();
    for c in &cases {
        for name in &a.methods {
            let Some(method) = method_on(name, c)? else {
                continue;
            };
            for &k in &a.skips {
                let scored = match &c.truth {
                    Truth::Mask(m) => score(method.as_ref(), m, Axis::Z, k),
                    Truth::Labels(l) => score_labels(method.as_ref(), l, Axis::Z, k),
                };
                let Some(s) = scored.with_context(|| format!("{} on {}", name, c.name))? else {
                    continue;
                };
                rows.push(Row {
                    family: c.family,
                    mask: c.name.clone(),
                    method: name.clone(),
                    skip: k,
                    dice_skipped: s.skipped,
                    dice_whole: s.whole,
                    seconds: s.seconds,
                });
            }
        }
        eprintln!("bench: {} done", c.name);
    }
    print_table(&rows, &a);
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&rows)?;
        interslice_io::raw::write_atomic(p, |w| w.write_all(text.as_bytes()))
            .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

/// The cases named in `masks` (all of them when it is empty); an error
/// naming the cases there are when one of `masks` is not among them.
fn selected(cases: Vec<Case>, masks: &[String]) -> Result<Vec<Case>> {
    if masks.is_empty() {
        return Ok(cases);
    }
    if let Some(missing) = masks.iter().find(|m| !cases.iter().any(|c| &c.name == *m)) {
        let names: Vec<&str> = cases.iter().map(|c| c.name.as_str()).collect();
        bail!(
            "--masks: no mask {missing} in the data here (there are: {})",
            names.join(", ")
        );
    }
    Ok(cases
        .into_iter()
        .filter(|c| masks.contains(&c.name))
        .collect())
}

/// The masks of every family whose data is there.
fn load_cases(dir: &Path) -> Result<Vec<Case>> {
    let mut cases = Vec::new();
    for seed in [1u64, 2] {
        let p = generate(&PhantomParams {
            size: 96,
            seed,
            bits: 8,
            noise: 0.10,
        })?;
        let image = Arc::new(intensity_f32(&p.intensity));
        for (name, min) in [("cell", 1u16), ("nucleus", 2)] {
            let mask = p.labels.map(|l| l >= min);
            cases.push(cropped(
                "noisy phantom",
                format!("phantom{seed}-{name}"),
                Truth::Mask(mask),
                Some(&image),
            )?);
        }
    }
    let sd = dir.join("stardist");
    if sd.join("mask3d.tif").is_file() {
        let labels = interslice_io::read_labels(&sd.join("mask3d.tif"))?;
        let img = intensity_f32(&interslice_io::read_volume(&sd.join("img3d.tif"))?);
        let image = Arc::new(img);
        cases.push(cropped(
            "stardist nuclei",
            "stardist-all".into(),
            Truth::Mask(labels.map(|l| l > 0)),
            Some(&image),
        )?);
        cases.push(cropped(
            "stardist nuclei, labelled",
            "stardist-labels".into(),
            Truth::Labels(labels),
            Some(&image),
        )?);
    } else {
        missing(&sd);
    }
    let pr = dir.join("pyradiomics");
    for (family, name) in [
        ("CT lung lesions", "lung1"),
        ("CT lung lesions", "lung2"),
        ("MR brain / breast", "brain1"),
        ("MR brain / breast", "brain2"),
        ("MR brain / breast", "breast1"),
    ] {
        let lp = pr.join(format!("{name}_label.nrrd"));
        if !lp.is_file() {
            missing(&lp);
            continue;
        }
        let labels = interslice_io::read_labels(&lp)?;
        let img = read_on_grid(&pr.join(format!("{name}_image.nrrd")), &labels)?;
        cases.push(cropped(
            family,
            name.into(),
            Truth::Mask(labels.map(|l| l > 0)),
            Some(&Arc::new(img)),
        )?);
    }
    let itk = dir.join("itk");
    if itk.join("T1_kmeans.nii.gz").is_file() {
        let labels = interslice_io::read_labels(&itk.join("T1_kmeans.nii.gz"))?;
        let img = Arc::new(read_on_grid(&itk.join("T1.nii.gz"), &labels)?);
        for (l, _) in labels.label_counts().into_iter().filter(|&(l, _)| l > 0) {
            cases.push(cropped(
                "T1 k-means classes",
                format!("T1-class{l}"),
                Truth::Mask(labels.mask_of(l)),
                Some(&img),
            )?);
        }
    } else {
        missing(&itk);
    }
    let mni = dir.join("mni");
    if mni.join("wm.nii.gz").is_file() {
        let t1 = interslice_io::read_volume(&mni.join("t1.nii.gz"))?;
        let img = Arc::new(intensity_f32(&t1));
        for (class, name) in [("gm", "mni-grey"), ("wm", "mni-white")] {
            let path = mni.join(format!("{class}.nii.gz"));
            let mask = tissue_of(&interslice_io::read_volume(&path)?);
            if mask.dims() != img.dims() {
                bail!("{}: dims differ from the MNI T1's", path.display());
            }
            cases.push(cropped(
                "MNI grey / white matter",
                name.into(),
                Truth::Mask(mask),
                Some(&img),
            )?);
        }
    } else {
        missing(&mni);
    }
    let aal = dir.join("aal");
    if aal.join("aal.nii.gz").is_file() {
        let labels = interslice_io::read_labels(&aal.join("aal.nii.gz"))?;
        let img = Arc::new(read_on_grid(&aal.join("ch2.nii.gz"), &labels)?);
        for (id, name) in AAL_STRUCTURES {
            cases.push(cropped(
                "AAL structures traced by hand on a T1",
                format!("aal-{name}"),
                Truth::Mask(labels.mask_of(id)),
                Some(&img),
            )?);
        }
    } else {
        missing(&aal);
    }
    Ok(cases)
}

/// Says on stderr that a family's data is not at `path`, and how to get it.
fn missing(path: &Path) {
    eprintln!(
        "bench: no {} (run scripts/fetch-interp-data.sh)",
        path.display()
    );
}

/// The structures of the AAL atlas (Tzourio-Mazoyer et al. 2002, labels of
/// `aal.nii.gz`) benchmarked on the T1 they were delineated on: the deep
/// grey and medial temporal structures of both sides, small structures
/// traced by hand on a T1 with weak contrast at parts of their boundary
/// (the held-out family the random walker loses on).
pub const AAL_STRUCTURES: [(u16, &str); 12] = [
    (37, "hippocampus-l"),
    (38, "hippocampus-r"),
    (41, "amygdala-l"),
    (42, "amygdala-r"),
    (71, "caudate-l"),
    (72, "caudate-r"),
    (73, "putamen-l"),
    (74, "putamen-r"),
    (75, "pallidum-l"),
    (76, "pallidum-r"),
    (77, "thalamus-l"),
    (78, "thalamus-r"),
];

/// A tissue class of the MNI template: the voxels whose probability map
/// (0..255 for 0..1) says it more likely than not (at most one class each,
/// since the maps sum to at most 1).
fn tissue_of(prob: &AnyVolume) -> Mask {
    intensity_f32(prob).map(|p| p > 127.5)
}

/// The intensity volume at `path`, which must share the labels' dims.
fn read_on_grid(path: &Path, labels: &LabelVolume) -> Result<Volume<f32>> {
    let img = intensity_f32(&interslice_io::read_volume(path)?);
    if img.dims() != labels.dims() {
        bail!(
            "{}: dims {:?} differ from its labels' {:?}",
            path.display(),
            img.dims(),
            labels.dims()
        );
    }
    Ok(img)
}

/// The method `name` on `case`: on its image for the image methods, on
/// its truth for the bound `area-ceiling` (one structure only); `None`
/// where the case has no image or truth for it (skipped).
fn method_on(name: &str, case: &Case) -> Result<Option<Box<dyn Interpolator>>> {
    Ok(match (name, case.image.as_ref(), &case.truth) {
        ("image-guided", Some(img), _) => Some(Box::new(ImageGuided::new(img.clone()))),
        ("random-walk", Some(img), _) => Some(Box::new(RandomWalk::new(img.clone()))),
        ("image-guided" | "random-walk", None, _) => None,
        ("area-ceiling", _, Truth::Mask(m)) => Some(Box::new(AreaCeiling::new(m.clone()))),
        ("area-ceiling", _, Truth::Labels(_)) => None,
        (n, _, _) => Some(by_name(n)?),
    })
}

/// A case cropped to its foreground's box grown by [`MARGIN`].
fn cropped(
    family: &'static str,
    name: String,
    truth: Truth,
    image: Option<&Arc<Volume<f32>>>,
) -> Result<Case> {
    let foreground = match &truth {
        Truth::Mask(m) => bounding_box(m, MARGIN),
        Truth::Labels(l) => bounding_box(&l.map(|v| v > 0), MARGIN),
    };
    let bbox = foreground.with_context(|| format!("{name}: empty mask"))?;
    Ok(Case {
        family,
        name,
        truth: match truth {
            Truth::Mask(m) => Truth::Mask(crop(&m, bbox)?),
            Truth::Labels(l) => Truth::Labels(crop(&l, bbox)?),
        },
        image: match image {
            Some(i) => Some(Conditioned::from(crop(i, bbox)?)),
            None => None,
        },
    })
}

/// Mean of the rows matching `f`.
fn mean(rows: &[Row], f: impl Fn(&Row) -> bool, v: impl Fn(&Row) -> f64) -> Option<f64> {
    let xs: Vec<f64> = rows.iter().filter(|r| f(r)).map(v).collect();
    (!xs.is_empty()).then(|| xs.iter().sum::<f64>() / xs.len() as f64)
}

fn print_table(rows: &[Row], a: &Args) {
    let ks: Vec<String> = a.skips.iter().map(|k| format!("k={k:<4}")).collect();
    println!(
        "| family (masks) | method | {} | whole k={} | s/run |",
        ks.join(" | "),
        a.skips[a.skips.len() / 2]
    );
    println!("|---|---|{}---|---|", "---|".repeat(a.skips.len()));
    let mut families: Vec<&str> = rows.iter().map(|r| r.family).collect();
    families.dedup();
    for fam in families {
        let mut masks: Vec<&str> = rows
            .iter()
            .filter(|r| r.family == fam)
            .map(|r| r.mask.as_str())
            .collect();
        masks.dedup();
        for m in &a.methods {
            let sel = |r: &Row| r.family == fam && &r.method == m;
            if let Some(cells) = dice_cells(rows, a, sel) {
                let secs = mean(rows, sel, |r| r.seconds).unwrap_or(0.0);
                println!("| {fam} ({}) | {m} | {cells} | {secs:.3} |", masks.len());
            }
        }
        if a.per_mask {
            for mask in &masks {
                for m in &a.methods {
                    let sel = |r: &Row| r.mask == *mask && &r.method == m;
                    if let Some(cells) = dice_cells(rows, a, sel) {
                        println!("|   {mask} | {m} | {cells} | |");
                    }
                }
            }
        }
    }
}

/// The Dice cells of a table row: the skipped slices' mean Dice at each k,
/// then the whole volume's at the middle k; None when no row is selected.
fn dice_cells(rows: &[Row], a: &Args, sel: impl Fn(&Row) -> bool) -> Option<String> {
    if !rows.iter().any(&sel) {
        return None;
    }
    let cell = |x: Option<f64>| x.map_or("   -  ".to_string(), |v| format!("{v:.4}"));
    let whole_k = a.skips[a.skips.len() / 2];
    let mut cells: Vec<String> = a
        .skips
        .iter()
        .map(|&k| cell(mean(rows, |r| sel(r) && r.skip == k, |r| r.dice_skipped)))
        .collect();
    cells.push(cell(mean(
        rows,
        |r| sel(r) && r.skip == whole_k,
        |r| r.dice_whole,
    )));
    Some(cells.join(" | "))
}

/// Time the methods (k = 5) on phantom cells of the two sizes of the speed targets.
fn speed(methods: &[String]) -> Result<()> {
    let p = generate(&PhantomParams {
        size: 256,
        seed: 3,
        bits: 8,
        noise: 0.05,
    })?;
    let image = intensity_f32(&p.intensity);
    let mask = p.labels.map(|l| l >= 1);
    println!("| volume | method | seconds (k=5) | Dice skipped |");
    println!("|---|---|---|---|");
    for dims in [[256usize, 256, 60], [197, 233, 189]] {
        // A box of `dims` centred on the cell.
        let bbox: [[usize; 2]; 3] = std::array::from_fn(|a| {
            let lo = (256 - dims[a]) / 2;
            [lo, lo + dims[a]]
        });
        let m = crop(&mask, bbox)?;
        let case = Case {
            family: "speed",
            name: "cell".into(),
            truth: Truth::Mask(m.clone()),
            image: Some(Conditioned::from(crop(&image, bbox)?)),
        };
        for name in methods {
            let method = method_on(name, &case)?.context("the case has an image and a truth")?;
            let s =
                score(method.as_ref(), &m, Axis::Z, 5)?.context("the cell shows on the crop")?;
            println!(
                "| {}×{}×{} | {name} | {:.3} | {:.4} |",
                dims[0], dims[1], dims[2], s.seconds, s.skipped
            );
        }
    }
    Ok(())
}
