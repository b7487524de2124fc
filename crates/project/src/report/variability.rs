//! How much the tracers of a project disagree, and what they agree on
//! (`interslice variability`).
//!
//! For every cell of the project traced by at least two users, each user's
//! tracing is interpolated (`interslice_project::groundtruth::label_volume`, as the server does, one
//! label at a time, so a structure is whole: the cell includes its nucleus)
//! and measured: the physical volume per user, the mean and the sample
//! standard deviation across users (the original study's Tables 3.1 and
//! 3.2), the Dice of every pair of users, and the STAPLE consensus
//! (`interslice_project::consensus`, the same volume the server exports as
//! `user=consensus`) with each user's estimated sensitivity and specificity.
//! When the project holds the exact labels of a cell
//! (`DIR/ground_truth/<cell>_labels.*`, as `interslice demo` and `interslice
//! campaign simulate` write them), every tracing, the consensus and the
//! majority vote are also scored against them. Ratings of automated
//! segmentations stored with the cells are listed. Every tracing's effort
//! is reported with it (`super::effort`): traced slices, minutes spent and
//! the predicted Dice of its result, and the median minutes per cell of the
//! tracings predicted to reach Dice 0.95.
//!
//! Writes to OUT (default `DIR/variability/`): `volumes.csv`, `summary.csv`,
//! `pairwise_dice.csv`, `ratings.csv`, `report.md`, one strip plot
//! `volumes_label<L>.svg` per label; and the consensus label volume of each
//! cell to `--consensus-dir` (default `OUT/consensus/`).
use super::effort::{Effort, tracing_effort};
use crate::consensus::{LabelRaters, consensus_of, rater_masks};
use crate::error::{ProjectError, ResultExt};
use interslice_core::metrics::overlap_masks;
use interslice_core::morph::Connectivity;
use interslice_core::regions::whole_structure;
use interslice_core::staple::{StapleParams, majority_vote};
use interslice_core::{Geometry, LabelVolume, Mask};
use interslice_store::Store;
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What to measure and where the files go.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// The project folder.
    pub dir: PathBuf,
    /// Only this label.
    pub label: Option<u16>,
    /// Output folder (default DIR/variability).
    pub out: Option<PathBuf>,
    /// Interpolation method of the tracings (default: the default interpolator).
    pub method: Option<String>,
    /// Where the consensus label volumes go (default OUT/consensus).
    pub consensus_dir: Option<PathBuf>,
}

/// What a run measured.
#[derive(Debug, Clone)]
pub struct Summary {
    /// Structures measured (a label of a cell).
    pub structures: usize,
    /// Cells with a measured structure.
    pub cells: usize,
    /// The output folder.
    pub out: PathBuf,
}

/// One user's tracing of one structure.
struct UserRow {
    user: String,
    voxels: u64,
    volume: f64,
    sensitivity: f64,
    specificity: f64,
    dice_consensus: Option<f64>,
    dice_truth: Option<f64>,
    effort: Effort,
}

/// One structure of one cell.
struct LabelRow {
    cell: String,
    label: u16,
    name: String,
    users: Vec<UserRow>,
    mean: f64,
    sd: f64,
    consensus_volume: f64,
    majority_volume: f64,
    truth_volume: Option<f64>,
    pairwise: Vec<(String, String, Option<f64>)>,
    consensus_dice_truth: Option<f64>,
    majority_dice_truth: Option<f64>,
    iterations: usize,
}

/// A rating of a segmentation, with the segmentation's name.
struct RatingRow {
    cell: String,
    segmentation: String,
    method: String,
    user: String,
    score: u8,
    comment: String,
}

/// Mean and sample standard deviation (n − 1; 0 for a single value).
fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let sd = if x.len() > 1 {
        (x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    (mean, sd)
}

fn count(m: &Mask) -> u64 {
    m.data().iter().filter(|&&b| b).count() as u64
}

fn dice(a: &Mask, b: &Mask) -> Result<Option<f64>, ProjectError> {
    Ok(overlap_masks(a, b)?.dice())
}

/// The exact labels of a cell in `DIR/ground_truth/`, if the project has them.
fn truth_of(dir: &Path, cell: &str) -> Result<Option<LabelVolume>, ProjectError> {
    let Ok(rd) = std::fs::read_dir(dir.join("ground_truth")) else {
        return Ok(None);
    };
    let prefix = format!("{cell}_labels.");
    let mut found: Vec<PathBuf> = rd
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with(&prefix))
        })
        .collect();
    found.sort();
    match found.first() {
        Some(p) => Ok(Some(
            interslice_io::read_labels(p).context_with(|| format!("reading {}", p.display()))?,
        )),
        None => Ok(None),
    }
}

/// The whole structure of `label` in a painted label volume: the label with
/// its holes filled, so a nucleus includes its nucleoli and a cell its
/// nucleus, as a tracer outlines them.
fn structure(truth: &LabelVolume, label: u16) -> Mask {
    whole_structure(truth, label, Connectivity::Face)
}

/// Measure one label of one cell.
fn label_row(
    cell: &str,
    name: &str,
    g: &Geometry,
    r: &LabelRaters,
    consensus: &interslice_core::staple::Staple,
    truth: Option<&Mask>,
    efforts: Vec<Effort>,
) -> Result<LabelRow, ProjectError> {
    let vv = g.voxel_volume();
    let mut users = Vec::new();
    for (j, ((u, m), effort)) in r.users.iter().zip(&r.masks).zip(efforts).enumerate() {
        let voxels = count(m);
        users.push(UserRow {
            user: u.clone(),
            voxels,
            volume: voxels as f64 * vv,
            sensitivity: consensus.sensitivity[j],
            specificity: consensus.specificity[j],
            dice_consensus: dice(&consensus.consensus, m)?,
            dice_truth: truth.map(|t| dice(t, m)).transpose()?.flatten(),
            effort,
        });
    }
    let mut pairwise = Vec::new();
    for a in 0..r.masks.len() {
        for b in a + 1..r.masks.len() {
            pairwise.push((
                r.users[a].clone(),
                r.users[b].clone(),
                dice(&r.masks[a], &r.masks[b])?,
            ));
        }
    }
    let refs: Vec<&Mask> = r.masks.iter().collect();
    let mv = majority_vote(&refs)?;
    let vols: Vec<f64> = users.iter().map(|u| u.volume).collect();
    let (mean, sd) = mean_sd(&vols);
    Ok(LabelRow {
        cell: cell.to_string(),
        label: r.label,
        name: name.to_string(),
        users,
        mean,
        sd,
        consensus_volume: count(&consensus.consensus) as f64 * vv,
        majority_volume: count(&mv) as f64 * vv,
        truth_volume: truth.map(|t| count(t) as f64 * vv),
        pairwise,
        consensus_dice_truth: truth
            .map(|t| dice(t, &consensus.consensus))
            .transpose()?
            .flatten(),
        majority_dice_truth: truth.map(|t| dice(t, &mv)).transpose()?.flatten(),
        iterations: consensus.iterations,
    })
}

/// Measure every cell of the project traced by at least two users and write
/// the files; `progress` hears of each cell done.
pub fn run(
    store: &Store,
    a: &Options,
    progress: &mut dyn FnMut(&str),
) -> Result<Summary, ProjectError> {
    let method = crate::methods::method_by_name(a.method.as_deref())?;
    // A command runs to its end (Ctrl-C ends the process): nothing cancels it.
    let never = interslice_core::Cancel::new();
    let out = a.out.clone().unwrap_or_else(|| a.dir.join("variability"));
    let cdir = a
        .consensus_dir
        .clone()
        .unwrap_or_else(|| out.join("consensus"));
    let names = store.labels()?;
    let label_name = |l: u16| {
        names
            .iter()
            .find(|x| x.id == l)
            .map_or_else(|| format!("Label {l}"), |x| x.name.clone())
    };
    let cells =
        crate::cells::scan(&a.dir).context_with(|| format!("listing {}", a.dir.display()))?;
    let mut rows: Vec<LabelRow> = Vec::new();
    let mut ratings: Vec<RatingRow> = Vec::new();
    let mut unit = None;
    for (cell, path) in &cells {
        let segs = store.segmentations(cell).unwrap_or_default();
        for r in store.ratings(Some(cell)).unwrap_or_default() {
            let seg = segs.iter().find(|s| s.id.to_string() == r.segmentation);
            ratings.push(RatingRow {
                cell: cell.clone(),
                segmentation: seg.map_or_else(|| r.segmentation.clone(), |s| s.name.clone()),
                method: seg.map_or_else(|| "file".to_string(), |s| s.method.clone()),
                user: r.user,
                score: r.score,
                comment: r.comment,
            });
        }
        let tracers = store.tracers_of(cell)?;
        if tracers.len() < 2 {
            continue;
        }
        let volume =
            interslice_io::read_volume(path).context_with(|| format!("reading cell {cell}"))?;
        let g = volume.geometry().clone();
        drop(volume);
        unit.get_or_insert(g.unit);
        let raters = rater_masks(store, &g, cell, method.as_ref(), a.label, &never)
            .context_with(|| format!("cell {cell}"))?;
        let consensus = consensus_of(&g, &raters, StapleParams::default(), &never)
            .context_with(|| format!("cell {cell}"))?;
        if consensus.per_label.is_empty() {
            continue;
        }
        std::fs::create_dir_all(&cdir).context_with(|| format!("creating {}", cdir.display()))?;
        let cpath = cdir.join(format!("{cell}_consensus.nii.gz"));
        interslice_io::write_labels(&cpath, &consensus.labels)
            .context_with(|| format!("writing {}", cpath.display()))?;
        let truth = truth_of(&a.dir, cell)?;
        if let Some(t) = &truth {
            t.geometry()
                .ensure_same_grid(&g)
                .context_with(|| format!("the exact labels of {cell} are not on its grid"))?;
        }
        for lc in &consensus.per_label {
            let r = raters
                .iter()
                .find(|r| r.label == lc.label)
                .expect("every consensus label has raters");
            let t = truth.as_ref().map(|t| structure(t, lc.label));
            let efforts = r
                .users
                .iter()
                .map(|name| {
                    let id = tracers.iter().find(|u| &u.name == name).map_or(0, |u| u.id);
                    tracing_effort(store, &g, cell, id, lc.label, method.as_ref(), &never)
                })
                .collect::<Result<Vec<_>, _>>()
                .context_with(|| format!("cell {cell}"))?;
            rows.push(label_row(
                cell,
                &label_name(lc.label),
                &g,
                r,
                &lc.staple,
                t.as_ref(),
                efforts,
            )?);
        }
        progress(&format!(
            "{cell}: {} label(s), consensus -> {}",
            consensus.per_label.len(),
            cpath.display()
        ));
    }
    if rows.is_empty() {
        return Err(ProjectError::not_found(format!(
            "no cell of {} was traced by two users{}",
            a.dir.display(),
            a.label
                .map(|l| format!(" for label {l}"))
                .unwrap_or_default()
        )));
    }
    let unit = unit.unwrap_or(interslice_core::LengthUnit::Unknown);
    std::fs::create_dir_all(&out).context_with(|| format!("creating {}", out.display()))?;
    super::write_text(&out.join("volumes.csv"), &volumes_csv(&rows, unit.ascii()))?;
    super::write_text(&out.join("summary.csv"), &summary_csv(&rows, unit.ascii()))?;
    super::write_text(&out.join("pairwise_dice.csv"), &pairwise_csv(&rows))?;
    super::write_text(&out.join("ratings.csv"), &ratings_csv(&ratings))?;
    let labels: BTreeSet<u16> = rows.iter().map(|r| r.label).collect();
    let mut plots = Vec::new();
    for &l in &labels {
        let name = format!("volumes_label{l}.svg");
        let sel: Vec<&LabelRow> = rows.iter().filter(|r| r.label == l).collect();
        plot(&out.join(&name), &sel, unit.symbol())?;
        plots.push((l, name));
    }
    super::write_text(
        &out.join("report.md"),
        &report(&rows, &ratings, &plots, unit.symbol(), a),
    )?;
    Ok(Summary {
        structures: rows.len(),
        cells: rows.iter().map(|r| &r.cell).collect::<BTreeSet<_>>().len(),
        out,
    })
}

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map(|v| format!("{v:.digits$}")).unwrap_or_default()
}

/// A CSV field: quoted when it holds a comma, quote or line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn volumes_csv(rows: &[LabelRow], unit: &str) -> String {
    let mut s = format!(
        "cell,label,structure,user,voxels,volume_{unit}3,dice_vs_consensus,staple_sensitivity,staple_specificity,dice_vs_truth,traced_slices,empty_slices,minutes,predicted_dice\n"
    );
    for r in rows {
        for u in &r.users {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{:.3},{},{:.6},{:.6},{},{},{},{:.3},{}",
                field(&r.cell),
                r.label,
                field(&r.name),
                field(&u.user),
                u.voxels,
                u.volume,
                opt(u.dice_consensus, 6),
                u.sensitivity,
                u.specificity,
                opt(u.dice_truth, 6),
                u.effort.traced_slices,
                u.effort.empty_slices,
                u.effort.seconds() / 60.0,
                opt(u.effort.predicted_dice(), 6)
            );
        }
    }
    s
}

fn summary_csv(rows: &[LabelRow], unit: &str) -> String {
    let mut s = format!(
        "cell,label,structure,users,mean_{unit}3,sd_{unit}3,cv_percent,consensus_{unit}3,majority_{unit}3,truth_{unit}3,mean_pairwise_dice,min_pairwise_dice,consensus_dice_vs_truth,majority_dice_vs_truth,staple_iterations\n"
    );
    for r in rows {
        let d: Vec<f64> = r.pairwise.iter().filter_map(|p| p.2).collect();
        let (md, _) = mean_sd(&d);
        let min = d.iter().copied().fold(f64::INFINITY, f64::min);
        let _ = writeln!(
            s,
            "{},{},{},{},{:.3},{:.3},{:.2},{:.3},{:.3},{},{},{},{},{},{}",
            field(&r.cell),
            r.label,
            field(&r.name),
            r.users.len(),
            r.mean,
            r.sd,
            100.0 * r.sd / r.mean,
            r.consensus_volume,
            r.majority_volume,
            opt(r.truth_volume, 3),
            opt((!d.is_empty()).then_some(md), 6),
            opt(min.is_finite().then_some(min), 6),
            opt(r.consensus_dice_truth, 6),
            opt(r.majority_dice_truth, 6),
            r.iterations
        );
    }
    s
}

fn pairwise_csv(rows: &[LabelRow]) -> String {
    let mut s = String::from("cell,label,structure,user_a,user_b,dice\n");
    for r in rows {
        for (a, b, d) in &r.pairwise {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{}",
                field(&r.cell),
                r.label,
                field(&r.name),
                field(a),
                field(b),
                opt(*d, 6)
            );
        }
    }
    s
}

fn ratings_csv(ratings: &[RatingRow]) -> String {
    let mut s = String::from("cell,segmentation,method,user,score,comment\n");
    for r in ratings {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            field(&r.cell),
            field(&r.segmentation),
            field(&r.method),
            field(&r.user),
            r.score,
            field(&r.comment)
        );
    }
    s
}

/// A markdown table cell: pipes escaped, line breaks flattened.
fn md(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

fn report(
    rows: &[LabelRow],
    ratings: &[RatingRow],
    plots: &[(u16, String)],
    unit: &str,
    a: &Options,
) -> String {
    let users: BTreeSet<&str> = rows
        .iter()
        .flat_map(|r| r.users.iter().map(|u| u.user.as_str()))
        .collect();
    let labels: BTreeSet<u16> = rows.iter().map(|r| r.label).collect();
    let has_truth = rows.iter().any(|r| r.truth_volume.is_some());
    let mut s = String::from("# Inter-user variability\n\n");
    let _ = writeln!(
        s,
        "Generated by `interslice variability{}{}` from the tracings in the project's \
         database: each tracing interpolated with `{}`, volumes in {unit}³ \
         (voxels × voxel volume), mean and sample standard deviation (n − 1) across \
         users, CV = SD / mean. The consensus is STAPLE (Warfield et al. 2004) per \
         structure; sensitivity and specificity are STAPLE's estimates of each user \
         against it (specificity counts the whole volume's background, as in ITK).\n",
        a.label.map(|l| format!(" --label {l}")).unwrap_or_default(),
        a.method
            .as_deref()
            .map(|m| format!(" --method {m}"))
            .unwrap_or_default(),
        a.method
            .as_deref()
            .unwrap_or(interslice_interp::DEFAULT_METHOD)
    );
    for &l in &labels {
        let sel: Vec<&LabelRow> = rows.iter().filter(|r| r.label == l).collect();
        let name = &sel[0].name;
        let _ = writeln!(s, "## {} (label {l}): volume per user, {unit}³\n", md(name));
        let mut head = String::from("| cell |");
        let mut rule = String::from("|---|");
        for u in &users {
            let _ = write!(head, " {} |", md(u));
            rule.push_str("---:|");
        }
        head.push_str(" mean | SD | CV % | STAPLE consensus |");
        rule.push_str("---:|---:|---:|---:|");
        if has_truth {
            head.push_str(" exact |");
            rule.push_str("---:|");
        }
        let _ = writeln!(s, "{head}\n{rule}");
        for r in &sel {
            let mut line = format!("| {} |", md(&r.cell));
            for u in &users {
                match r.users.iter().find(|x| x.user == *u) {
                    Some(x) => {
                        let _ = write!(line, " {:.1} |", x.volume);
                    }
                    None => line.push_str(" – |"),
                }
            }
            let _ = write!(
                line,
                " {:.1} | {:.1} | {:.1} | {:.1} |",
                r.mean,
                r.sd,
                100.0 * r.sd / r.mean,
                r.consensus_volume
            );
            if has_truth {
                let _ = write!(line, " {} |", opt(r.truth_volume, 1));
            }
            let _ = writeln!(s, "{line}");
        }
        if let Some((_, p)) = plots.iter().find(|p| p.0 == l) {
            let _ = writeln!(s, "\n![{} volumes per user]({p})\n", md(name));
        }
        let _ = writeln!(s, "### STAPLE estimates and agreement\n");
        let mut head =
            String::from("| cell | user | sensitivity | specificity | Dice vs consensus |");
        let mut rule = String::from("|---|---|---:|---:|---:|");
        if has_truth {
            head.push_str(" Dice vs exact |");
            rule.push_str("---:|");
        }
        let _ = writeln!(s, "{head}\n{rule}");
        for r in &sel {
            for u in &r.users {
                let mut line = format!(
                    "| {} | {} | {:.4} | {:.6} | {} |",
                    md(&r.cell),
                    md(&u.user),
                    u.sensitivity,
                    u.specificity,
                    opt(u.dice_consensus, 4)
                );
                if has_truth {
                    let _ = write!(line, " {} |", opt(u.dice_truth, 4));
                }
                let _ = writeln!(s, "{line}");
            }
        }
        let _ = writeln!(s, "\nPairwise Dice between users:\n");
        let _ = writeln!(s, "| cell | pair | Dice |\n|---|---|---:|");
        for r in &sel {
            for (x, y, d) in &r.pairwise {
                let _ = writeln!(
                    s,
                    "| {} | {} / {} | {} |",
                    md(&r.cell),
                    md(x),
                    md(y),
                    opt(*d, 4)
                );
            }
        }
        if has_truth {
            let _ = writeln!(
                s,
                "\nConsensus against the exact labels (majority vote for comparison):\n"
            );
            let _ = writeln!(
                s,
                "| cell | STAPLE Dice | majority-vote Dice | STAPLE {unit}³ | majority {unit}³ |\n|---|---:|---:|---:|---:|"
            );
            for r in &sel {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {:.1} | {:.1} |",
                    md(&r.cell),
                    opt(r.consensus_dice_truth, 4),
                    opt(r.majority_dice_truth, 4),
                    r.consensus_volume,
                    r.majority_volume
                );
            }
        }
        s.push('\n');
    }
    let efforts: Vec<(&str, &str, &str, &Effort)> = rows
        .iter()
        .flat_map(|r| {
            r.users
                .iter()
                .map(|u| (r.cell.as_str(), u.user.as_str(), r.name.as_str(), &u.effort))
        })
        .collect();
    s.push_str(&super::effort::markdown(&efforts, md));
    let _ = writeln!(s, "## Ratings of automated segmentations\n");
    if ratings.is_empty() {
        let _ = writeln!(s, "No segmentation has been rated.");
    } else {
        let _ = writeln!(
            s,
            "| cell | segmentation | method | user | score (1–5) | comment |\n|---|---|---|---|---:|---|"
        );
        for r in ratings {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} |",
                md(&r.cell),
                md(&r.segmentation),
                md(&r.method),
                md(&r.user),
                r.score,
                md(&r.comment)
            );
        }
    }
    s
}

/// One Okabe-Ito colour per user (the first six of the palette), then grey.
const USER_COLOURS: &[(u8, u8, u8)] = super::COLOURS.split_at(6).0;

/// A strip plot: one column per cell, a dot per user, a black cross for the
/// STAPLE consensus and a grey bar for the exact volume when known.
fn plot(path: &Path, rows: &[&LabelRow], unit: &str) -> Result<(), ProjectError> {
    use plotters::prelude::*;
    let users: Vec<String> = rows
        .iter()
        .flat_map(|r| r.users.iter().map(|u| u.user.clone()))
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let mut vals: Vec<f64> = rows
        .iter()
        .flat_map(|r| r.users.iter().map(|u| u.volume))
        .collect();
    vals.extend(rows.iter().map(|r| r.consensus_volume));
    vals.extend(rows.iter().filter_map(|r| r.truth_volume));
    let (lo, hi) = vals
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let pad = ((hi - lo) * 0.08).max(hi.abs() * 0.01).max(1e-6);
    let n = rows.len() as f64;
    let err = |e: &dyn std::fmt::Display| ProjectError::internal(format!("plot: {e}"));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 440)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let title = format!("{}: volume per user", rows[0].name);
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..n - 0.5, (lo - pad)..(hi + pad))
            .map_err(|e| err(&e))?;
        let names: Vec<String> = rows.iter().map(|r| r.cell.clone()).collect();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_desc("cell")
            .y_desc(format!("volume ({unit}³)"))
            .y_label_formatter(&|y| format!("{y:.0}"))
            .x_labels(rows.len().max(2) * 2 + 1)
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 {
                    names.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .draw()
            .map_err(|e| err(&e))?;
        let truth: Vec<(f64, f64)> = rows
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.truth_volume.map(|t| (i as f64, t)))
            .collect();
        if !truth.is_empty() {
            let grey = RGBColor(150, 150, 150);
            chart
                .draw_series(truth.iter().map(|&(x, y)| {
                    PathElement::new(vec![(x - 0.35, y), (x + 0.35, y)], grey.stroke_width(3))
                }))
                .map_err(|e| err(&e))?
                .label("exact")
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(3))
                });
        }
        let k = users.len().max(1) as f64;
        for (ui, u) in users.iter().enumerate() {
            let (r, g, b) = USER_COLOURS.get(ui).copied().unwrap_or((100, 100, 100));
            let colour = RGBColor(r, g, b);
            let dx = (ui as f64 - (k - 1.0) / 2.0) * 0.12;
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .enumerate()
                .filter_map(|(i, row)| {
                    row.users
                        .iter()
                        .find(|x| &x.user == u)
                        .map(|x| (i as f64 + dx, x.volume))
                })
                .collect();
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 5, colour.filled())))
                .map_err(|e| err(&e))?
                .label(u.clone())
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour.filled()));
        }
        let cons: Vec<(f64, f64)> = rows
            .iter()
            .enumerate()
            .map(|(i, r)| (i as f64, r.consensus_volume))
            .collect();
        chart
            .draw_series(
                cons.iter()
                    .map(|&p| Cross::new(p, 7, BLACK.stroke_width(2))),
            )
            .map_err(|e| err(&e))?
            .label("STAPLE consensus")
            .legend(|(x, y)| Cross::new((x + 10, y), 6, BLACK.stroke_width(2)));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    super::write_text(path, &svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_standard_deviation() {
        let (m, s) = mean_sd(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(m, 5.0);
        assert!((s - (32.0f64 / 7.0).sqrt()).abs() < 1e-12);
        assert_eq!(mean_sd(&[3.0]), (3.0, 0.0));
    }

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(field("plain"), "plain");
        assert_eq!(field("a, b"), "\"a, b\"");
        assert_eq!(field("say \"x\""), "\"say \"\"x\"\"\"");
        assert_eq!(md("a|b\nc"), "a\\|b c");
    }
}
