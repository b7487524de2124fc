//! The interpolation study of the 2014 paper (`interslice study`), on any
//! fully traced label volume: one measured run and the report files. With `--image` (the intensity volume on the
//! ground truth's grid) the image-guided method is studied too, next to the
//! shape-only ones.
//!
//! For every number of skipped slices `k`, the drawn slices are the first and
//! last non-empty slices along the axis and every `(k + 1)`-th slice from the
//! first; every other slice is erased. Each method interpolates every label of
//! that sparse volume (each label on its own, as `interpolate` does), and each
//! studied label of the result is measured against the ground truth with the
//! core metrics (overlap and border distances). The (method, k) runs go in
//! parallel.
//!
//! DIR receives `results.csv` and `results.json` (one row per method, k and
//! label), one SVG plot per metric (`dice.svg`, ...: the metric against the
//! number of skipped slices, one line per method, the mean over the studied
//! labels) and `summary.md`.
//!
//! The time to ground truth of a simulated tracer who spends a fixed time
//! per traced slice (`--seconds-per-contour`, 30–60 s in the 2014 study):
//! `effort.csv` and a section of `summary.md` give, per method and k, the
//! traced slices, the minutes (slices × seconds / 60) and the Dice on the
//! skipped slices and on the whole volume, so the reader sees the minutes a
//! cell takes at Dice ≥ 0.95.
use crate::error::{ProjectError, ResultExt};
use interslice_core::metrics::{Metrics, evaluate_label};
use interslice_core::{Axis, LabelVolume};
use interslice_interp::protocol::{dice_on, drawn_for, sparse_of};
use interslice_interp::{IMAGE_METHOD, Interpolator, default_method, interpolate_labels};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// One measured (method, skip, label).
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Method name.
    pub method: String,
    /// Slices skipped between drawn slices.
    pub skip: usize,
    /// The label measured.
    pub label: u16,
    /// Number of drawn slices.
    pub drawn: usize,
    /// Wall time of the interpolation of all labels (s), shared by the rows of one run.
    pub seconds: f64,
    /// Every metric of the label.
    pub metrics: Metrics,
    /// Dice on the skipped slices only (between the first and last drawn).
    pub dice_skipped: f64,
}

/// The metrics plotted and tabulated: (key, title, higher is better).
pub const PLOTTED: &[(&str, &str, bool)] = &[
    ("dice", "Dice", true),
    ("jaccard", "Jaccard", true),
    ("sensitivity", "Sensitivity", true),
    ("specificity", "Specificity", true),
    ("hd95", "HD95", false),
    ("assd", "ASSD", false),
];

/// Drop every slice but `drawn_for(first, last, k)` along `axis`,
/// interpolate every label with `method` and measure each of `labels`.
#[allow(clippy::too_many_arguments)]
pub fn measure(
    method: &dyn Interpolator,
    gt: &LabelVolume,
    axis: Axis,
    first: usize,
    last: usize,
    k: usize,
    labels: &[u16],
    tolerance: f64,
) -> Result<Vec<Row>, ProjectError> {
    let drawn = drawn_for(first, last, k);
    let sparse = sparse_of(gt, axis, &drawn);
    let t = Instant::now();
    let out = interpolate_labels(method, &sparse, axis, &drawn)?;
    let seconds = t.elapsed().as_secs_f64();
    drop(sparse);
    let skipped: Vec<usize> = (first..=last).filter(|s| !drawn.contains(s)).collect();
    labels
        .iter()
        .map(|&l| {
            let (a, b) = (out.map(|v| v == l), gt.map(|v| v == l));
            Ok(Row {
                dice_skipped: dice_on(&a, &b, axis, &skipped),
                method: method.name().to_string(),
                skip: k,
                label: l,
                drawn: drawn.len(),
                seconds,
                metrics: evaluate_label(gt, &out, l, tolerance)?,
            })
        })
        .collect()
}

/// Everything the report files are written from.
pub struct StudyReport<'a> {
    /// The ground truth file.
    pub source: &'a Path,
    /// How to regenerate the ground truth (when it is a phantom) and the study.
    pub provenance: Provenance,
    /// The ground truth.
    pub gt: &'a LabelVolume,
    /// The axis slices were dropped along.
    pub axis: Axis,
    /// The studied labels.
    pub labels: &'a [u16],
    /// The studied methods.
    pub methods: &'a [&'a str],
    /// The numbers of skipped slices.
    pub skips: &'a [usize],
    /// Every measured row.
    pub rows: &'a [Row],
    /// Wall time of the whole study (s).
    pub seconds: f64,
    /// The simulated tracer's time per traced slice (s).
    pub seconds_per_contour: f64,
}

impl StudyReport<'_> {
    /// The method `interpolate` uses on this cell without `--method`: the
    /// image method when the study has the cell's image, the shape default
    /// otherwise.
    pub fn default_method(&self) -> &'static str {
        default_method(self.methods.contains(&IMAGE_METHOD))
    }

    /// The method whose time-to-ground-truth curve is shown: the default
    /// when it was studied, else the first studied method.
    pub fn curve_method(&self) -> Option<&str> {
        let default = self.default_method();
        (self.methods.iter().find(|&&m| m == default))
            .or(self.methods.first())
            .copied()
    }
}

/// A metric of a row by its JSON key (`None` for null).
fn metric(r: &Row, key: &str) -> Option<f64> {
    let m = &r.metrics;
    match key {
        "dice" => m.dice,
        "dice_skipped" => Some(r.dice_skipped),
        "jaccard" => m.jaccard,
        "sensitivity" => m.sensitivity,
        "specificity" => m.specificity,
        "precision" => m.precision,
        "volume_similarity" => m.volume_similarity,
        "hd" => m.hd,
        "hd95" => m.hd95,
        "assd" => m.assd,
        "nsd" => m.nsd,
        _ => None,
    }
}

/// Per method, the metric at each skip averaged over the studied labels
/// (`None` where any label's value is null).
fn mean_series(ctx: &StudyReport<'_>, key: &str) -> Vec<(String, Vec<Option<f64>>)> {
    ctx.methods
        .iter()
        .map(|&m| {
            let vals = ctx
                .skips
                .iter()
                .map(|&k| {
                    let vs: Option<Vec<f64>> = ctx
                        .rows
                        .iter()
                        .filter(|r| r.method == m && r.skip == k)
                        .map(|r| metric(r, key))
                        .collect();
                    vs.filter(|v| !v.is_empty())
                        .map(|v| v.iter().sum::<f64>() / v.len() as f64)
                })
                .collect();
            (m.to_string(), vals)
        })
        .collect()
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.6}")).unwrap_or_default()
}

fn csv(rows: &[Row]) -> String {
    let keys = [
        "dice",
        "jaccard",
        "sensitivity",
        "specificity",
        "precision",
        "volume_similarity",
        "hd",
        "hd95",
        "assd",
        "nsd",
    ];
    let mut s = format!(
        "method,skip,label,drawn_slices,seconds,{}\n",
        keys.join(",")
    );
    for r in rows {
        let _ = write!(
            s,
            "{},{},{},{},{:.4}",
            r.method, r.skip, r.label, r.drawn, r.seconds
        );
        for k in keys {
            let _ = write!(s, ",{}", fmt_opt(metric(r, k)));
        }
        s.push('\n');
    }
    s
}

fn json(ctx: &StudyReport<'_>) -> Result<String, ProjectError> {
    let g = ctx.gt.geometry();
    let v = serde_json::json!({
        "ground_truth": ctx.source.file_name().map(|f| f.to_string_lossy().to_string()),
        "dims": g.dims,
        "spacing": g.spacing,
        "unit": g.unit.symbol(),
        "axis": ctx.axis,
        "labels": ctx.labels,
        "methods": ctx.methods,
        "default_method": ctx.default_method(),
        "skips": ctx.skips,
        "seconds": ctx.seconds,
        "seconds_per_contour": ctx.seconds_per_contour,
        "rows": ctx.rows,
    });
    serde_json::to_string_pretty(&v).map_err(|e| ProjectError::internal(e.to_string()))
}

/// One SVG: the metric against the number of skipped slices, a line per
/// method, the `default` one drawn thicker.
fn plot(
    title: &str,
    series: &[(String, Vec<Option<f64>>)],
    skips: &[usize],
    default: &str,
) -> Result<String, ProjectError> {
    use plotters::prelude::*;
    let vals: Vec<f64> = series
        .iter()
        .flat_map(|(_, v)| v.iter().flatten().copied())
        .collect();
    let (mut lo, mut hi) = vals
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-3);
    let (lo, hi) = (lo - pad, hi + pad);
    let x0 = *skips.first().unwrap_or(&0) as f64;
    let x1 = (*skips.last().unwrap_or(&1) as f64).max(x0 + 1.0);
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (720, 480)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| ProjectError::internal(format!("plot: {e}"));
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{title} vs slices skipped"), ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0 - 0.2..x1 + 0.2, lo..hi)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("slices skipped between drawn slices")
        .y_desc(title)
        .x_labels(skips.len().min(12))
        .x_label_formatter(&|x| format!("{x:.0}"))
        .draw()
        .map_err(|e| err(&e))?;
    for (i, (name, v)) in series.iter().enumerate() {
        // Past the palette: grey.
        let (r, g, b) = super::COLOURS.get(i).copied().unwrap_or((128, 128, 128));
        let colour = RGBColor(r, g, b);
        let pts: Vec<(f64, f64)> = skips
            .iter()
            .zip(v)
            .filter_map(|(&k, y)| y.map(|y| (k as f64, y)))
            .collect();
        let width = if name == default { 3 } else { 2 };
        chart
            .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(width)))
            .map_err(|e| err(&e))?
            .label(name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    drop(chart);
    drop(root);
    Ok(svg)
}

/// Where the ground truth came from and the commands that regenerate the study.
pub struct Provenance {
    /// The `interslice phantom` command that wrote the ground truth, when the
    /// `phantom.json` next to it says so.
    pub phantom: Option<String>,
    /// The commands that regenerate the study (the phantom's first).
    pub commands: Vec<String>,
}

/// The phantom command recorded in the `phantom.json` next to `gt` (written
/// by `interslice phantom` with its parameters), if `gt` is one of its label
/// volumes; `dir` stands for the phantom's output folder.
pub fn phantom_command(gt: &Path, dir: &str) -> Option<String> {
    let name = gt.file_name()?.to_string_lossy().to_string();
    let text = std::fs::read_to_string(gt.parent()?.join("phantom.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    if v.get("generator")?.as_str()? != "interslice phantom" {
        return None;
    }
    let ours = v
        .get("cells")?
        .as_array()?
        .iter()
        .any(|c| c.get("labels").and_then(|l| l.as_str()) == Some(name.as_str()));
    if !ours {
        return None;
    }
    let p = v.get("params")?;
    let mut cmd = format!(
        "interslice phantom --out {dir} --count {} --size {} --seed {}",
        p.get("count")?.as_u64()?,
        p.get("size")?.as_u64()?,
        p.get("seed")?.as_u64()?
    );
    // Only the label volume matters here; intensity options when not default.
    if let Some(b) = p.get("bits").and_then(|b| b.as_u64()).filter(|&b| b != 8) {
        let _ = write!(cmd, " --bits {b}");
    }
    if let Some(n) = p
        .get("noise")
        .and_then(|n| n.as_f64())
        .filter(|&n| (n - 0.02).abs() > 1e-12)
    {
        let _ = write!(cmd, " --noise {n}");
    }
    Some(cmd)
}

/// The markdown summary: the setup, a table per plotted metric (mean over the
/// studied labels, best per column in bold), per-label Dice and timings.
fn summary(ctx: &StudyReport<'_>) -> String {
    let g = ctx.gt.geometry();
    let mut s = String::new();
    let _ = writeln!(s, "# Interpolation study\n");
    let _ = writeln!(
        s,
        "Ground truth `{}`{}: {}x{}x{} voxels, spacing {} x {} x {} {}; slices dropped along {}; \
         labels {:?}. For k skipped slices the drawn slices are the first and last non-empty \
         slices and every (k+1)-th slice from the first. Values are the mean over the labels. \
         Best per column in **bold**; the default method is `{}`.\n",
        ctx.source
            .file_name()
            .map(|f| f.to_string_lossy().to_string())
            .unwrap_or_default(),
        ctx.provenance
            .phantom
            .as_ref()
            .map(|c| format!(" (the label volume written by `{c}`)"))
            .unwrap_or_default(),
        g.dims[0],
        g.dims[1],
        g.dims[2],
        g.spacing[0],
        g.spacing[1],
        g.spacing[2],
        g.unit.symbol(),
        ctx.axis,
        ctx.labels,
        ctx.default_method()
    );
    let _ = writeln!(
        s,
        "Regenerate with (release build):\n\n```\n{}\n```\n",
        ctx.provenance.commands.join("\n")
    );
    for &(key, title, higher) in PLOTTED {
        let series = mean_series(ctx, key);
        let _ = writeln!(s, "## {title}\n\n![{title}]({key}.svg)\n");
        table(&mut s, &series, ctx.skips, higher);
    }
    if ctx.labels.len() > 1 {
        let _ = writeln!(s, "## Dice per label\n");
        for &l in ctx.labels {
            let _ = writeln!(s, "### Label {l}\n");
            let series: Vec<(String, Vec<Option<f64>>)> = ctx
                .methods
                .iter()
                .map(|&m| {
                    let v = ctx
                        .skips
                        .iter()
                        .map(|&k| {
                            ctx.rows
                                .iter()
                                .find(|r| r.method == m && r.skip == k && r.label == l)
                                .and_then(|r| r.metrics.dice)
                        })
                        .collect();
                    (m.to_string(), v)
                })
                .collect();
            table(&mut s, &series, ctx.skips, true);
        }
    }
    effort_section(&mut s, ctx);
    let _ = writeln!(
        s,
        "## Time\n\nMean interpolation time per run (all labels), in seconds:\n"
    );
    let _ = writeln!(s, "| method | seconds |\n|---|---:|");
    for &m in ctx.methods {
        let t: Vec<f64> = ctx
            .rows
            .iter()
            .filter(|r| r.method == m && r.label == ctx.labels[0])
            .map(|r| r.seconds)
            .collect();
        let mean = t.iter().sum::<f64>() / t.len().max(1) as f64;
        let _ = writeln!(s, "| {m} | {mean:.3} |");
    }
    let _ = writeln!(
        s,
        "\nWhole study (interpolation and metrics, runs in parallel): {:.1} s.",
        ctx.seconds
    );
    s
}

/// One point of the time-to-ground-truth curve: (method, k, traced slices,
/// minutes, Dice on the skipped slices, Dice on the whole volume), the Dice
/// the mean over the studied labels.
pub type EffortPoint = (String, usize, usize, f64, Option<f64>, Option<f64>);

/// The time-to-ground-truth curve of every method (see the module docs).
pub fn effort_curve(ctx: &StudyReport<'_>) -> Vec<EffortPoint> {
    let skipped = mean_series(ctx, "dice_skipped");
    let volume = mean_series(ctx, "dice");
    let mut out = Vec::new();
    for (m, (name, sk)) in skipped.iter().enumerate() {
        for (c, &k) in ctx.skips.iter().enumerate() {
            let Some(drawn) = ctx
                .rows
                .iter()
                .find(|r| r.method == *name && r.skip == k)
                .map(|r| r.drawn)
            else {
                continue;
            };
            let minutes = super::effort::minutes(drawn, ctx.seconds_per_contour);
            out.push((name.clone(), k, drawn, minutes, sk[c], volume[m].1[c]));
        }
    }
    out
}

fn effort_csv(ctx: &StudyReport<'_>) -> String {
    let mut s = String::from(
        "method,skip,traced_slices,seconds_per_contour,minutes,dice_skipped,dice_volume\n",
    );
    for (m, k, n, minutes, sk, vol) in effort_curve(ctx) {
        let _ = writeln!(
            s,
            "{m},{k},{n},{},{minutes:.3},{},{}",
            ctx.seconds_per_contour,
            fmt_opt(sk),
            fmt_opt(vol)
        );
    }
    s
}

/// The summary's "Time to ground truth" section: per method, the fewest
/// minutes that reach Dice ≥ 0.95 on the whole volume, then the default
/// method's curve (or the first studied method's).
fn effort_section(s: &mut String, ctx: &StudyReport<'_>) {
    let target = super::effort::TARGET_DICE;
    let curve = effort_curve(ctx);
    let _ = writeln!(
        s,
        "## Time to ground truth\n\nA simulated tracer spends {} s per traced slice; minutes = \
         traced slices × {} / 60 (`effort.csv`). Fewest minutes per cell at Dice ≥ {target} \
         (whole volume, mean over the labels):\n\n| method | minutes | traced slices | k |\n|---|---:|---:|---:|",
        ctx.seconds_per_contour, ctx.seconds_per_contour
    );
    for &m in ctx.methods {
        let best = curve
            .iter()
            .filter(|p| p.0 == m && p.5.is_some_and(|d| d >= target))
            .min_by(|a, b| a.3.total_cmp(&b.3));
        match best {
            Some(p) => {
                let _ = writeln!(s, "| {m} | {:.1} | {} | {} |", p.3, p.2, p.1);
            }
            None => {
                let _ = writeln!(s, "| {m} | not reached | – | – |");
            }
        }
    }
    if let Some(m) = ctx.curve_method() {
        let _ = writeln!(
            s,
            "\nThe curve of `{m}`:\n\n| k | traced slices | minutes | Dice (skipped) | Dice (volume) |\n|---:|---:|---:|---:|---:|"
        );
        for p in curve.iter().filter(|p| p.0 == m) {
            let _ = writeln!(
                s,
                "| {} | {} | {:.1} | {} | {} |",
                p.1,
                p.2,
                p.3,
                p.4.map_or("–".into(), |d| format!("{d:.4}")),
                p.5.map_or("–".into(), |d| format!("{d:.4}"))
            );
        }
    }
    s.push('\n');
}

/// A markdown table, methods as rows, skips as columns, best in bold.
fn table(s: &mut String, series: &[(String, Vec<Option<f64>>)], skips: &[usize], higher: bool) {
    let _ = write!(s, "| method |");
    for k in skips {
        let _ = write!(s, " k={k} |");
    }
    let _ = write!(s, "\n|---|");
    for _ in skips {
        let _ = write!(s, "---:|");
    }
    s.push('\n');
    let best: Vec<Option<f64>> = (0..skips.len())
        .map(|c| {
            let it = series.iter().filter_map(|(_, v)| v[c]);
            if higher {
                it.reduce(f64::max)
            } else {
                it.reduce(f64::min)
            }
        })
        .collect();
    for (name, v) in series {
        let _ = write!(s, "| {name} |");
        for (c, x) in v.iter().enumerate() {
            match x {
                Some(x) if Some(*x) == best[c] => {
                    let _ = write!(s, " **{x:.4}** |");
                }
                Some(x) => {
                    let _ = write!(s, " {x:.4} |");
                }
                None => {
                    let _ = write!(s, " – |");
                }
            }
        }
        s.push('\n');
    }
    s.push('\n');
}

/// Write the report files into `out` (each atomically): `results.csv`,
/// `results.json`, `effort.csv`, one SVG per plotted metric and `summary.md`.
pub fn write(out: &Path, ctx: &StudyReport<'_>) -> Result<(), ProjectError> {
    super::write_text(&out.join("results.csv"), &csv(ctx.rows))?;
    super::write_text(&out.join("results.json"), &json(ctx)?)?;
    super::write_text(&out.join("effort.csv"), &effort_csv(ctx))?;
    for &(key, title, _) in PLOTTED {
        let series = mean_series(ctx, key);
        let unit = if matches!(key, "hd95" | "assd") {
            format!(" ({})", ctx.gt.geometry().unit.symbol())
        } else {
            String::new()
        };
        let path = out.join(format!("{key}.svg"));
        let svg = plot(
            &format!("{title}{unit}"),
            &series,
            ctx.skips,
            ctx.default_method(),
        )
        .context_with(|| format!("writing {}", path.display()))?;
        super::write_text(&path, &svg)?;
    }
    super::write_text(&out.join("summary.md"), &summary(ctx))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drawn_keeps_first_and_last() {
        assert_eq!(drawn_for(2, 9, 2), vec![2, 5, 8, 9]);
        assert_eq!(drawn_for(0, 4, 0), vec![0, 1, 2, 3, 4]);
        assert_eq!(drawn_for(0, 6, 2), vec![0, 3, 6]);
    }
}
