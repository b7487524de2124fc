//! `interslice evaluate GROUND_TRUTH SEGMENTATION [--label N] [--json] [--tolerance T]`:
//! overlap and border-distance metrics of a segmentation against a ground
//! truth (conventions in docs/metrics.md).
//!
//! With `--label N`, voxels equal to N are foreground and `--json` prints one
//! object. Without it, every non-zero label present in either volume is
//! evaluated, plus `foreground` (the union of all labels), and `--json` prints
//! `{"labels": {"1": {...}, ...}, "foreground": {...}}`.
use crate::series::SeriesArg;
use anyhow::{Context, Result, bail};
use interslice_core::metrics::{
    AllReport, DEFAULT_TOLERANCE, LabelReport, Metrics, evaluate_all_and_foreground, evaluate_label,
};
use interslice_core::{LabelVolume, LengthUnit};
use std::path::{Path, PathBuf};

/// Arguments of `evaluate`.
#[derive(clap::Args)]
pub struct Args {
    /// The reference label volume (any supported format).
    pub ground_truth: PathBuf,
    /// The label volume to measure, on the same grid.
    pub segmentation: PathBuf,
    #[command(flatten)]
    pub series: crate::series::SeriesArg,
    /// Evaluate only the voxels equal to N (for 0/1 masks, N = 1). A number or a component's name.
    #[arg(long = "label", value_name = "L")]
    pub label_arg: Option<crate::label::LabelArg>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// NSD (surface Dice) tolerance, in the files' physical units.
    #[arg(
        long,
        value_name = "T",
        default_value_t = DEFAULT_TOLERANCE,
        allow_negative_numbers = true
    )]
    pub tolerance: f64,
}

fn read(path: &Path, series: &SeriesArg, what: &str) -> Result<LabelVolume> {
    series
        .read_labels(path)
        .with_context(|| format!("reading the {what}"))
}

/// Err when the two volumes are not on one grid or carry different units.
fn check_geometry(gt: &LabelVolume, seg: &LabelVolume) -> Result<()> {
    let (a, b) = (gt.geometry(), seg.geometry());
    a.ensure_same_grid(b)
        .context("ground truth and segmentation differ")?;
    if a.unit != b.unit && a.unit != LengthUnit::Unknown && b.unit != LengthUnit::Unknown {
        bail!(
            "ground truth and segmentation differ: unit {} vs {}",
            a.unit.symbol(),
            b.unit.symbol()
        );
    }
    Ok(())
}

/// Run the command.
pub fn run(a: Args) -> Result<()> {
    let label = a
        .label_arg
        .as_ref()
        .map(|l| l.resolve(&[&a.ground_truth, &a.segmentation]))
        .transpose()?;
    if !(a.tolerance.is_finite() && a.tolerance >= 0.0) {
        bail!(
            "--tolerance must be a finite number >= 0, got {}",
            a.tolerance
        );
    }
    let spin = crate::progress::spinner("measuring");
    let series = a
        .series
        .for_inputs(&[a.ground_truth.as_path(), a.segmentation.as_path()])?;
    let (gt, seg) = rayon::join(
        || read(&a.ground_truth, &series[0], "ground truth"),
        || read(&a.segmentation, &series[1], "segmentation"),
    );
    let (gt, seg) = (gt?, seg?);
    check_geometry(&gt, &seg)?;

    if let Some(label) = label {
        let m = evaluate_label(&gt, &seg, label, a.tolerance)?;
        spin.finish_and_clear();
        if m.tp + m.fp + m.fn_ == 0 {
            // Still a valid answer (both masks empty: ratios and distances
            // are null), but most often a mistyped label: say so on stderr.
            eprintln!(
                "warning: label {label} is in neither volume; its metrics are those of two empty masks"
            );
        }
        if a.json {
            let out = LabelReport { label, metrics: &m };
            println!("{}", serde_json::to_string_pretty(&out)?);
        } else {
            print!("{}", table(&[(format!("label {label}"), &m)]));
        }
        return Ok(());
    }

    let (all, fg) = evaluate_all_and_foreground(&gt, &seg, a.tolerance)?;
    spin.finish_and_clear();
    if a.json {
        let out = AllReport {
            labels: all.iter().map(|(l, m)| (*l, m)).collect(),
            foreground: &fg,
        };
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        let mut cols: Vec<(String, &Metrics)> =
            all.iter().map(|(l, m)| (format!("label {l}"), m)).collect();
        if all.len() != 1 {
            cols.push(("foreground".into(), &fg));
        }
        if all.is_empty() {
            println!("no label in either volume (both are all background)");
        }
        print!("{}", table(&cols));
    }
    Ok(())
}

/// A number for people: 6 significant digits, integers without a fraction.
fn fmt_num(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e15 {
        return format!("{x:.0}");
    }
    let digits = 6 - 1 - x.abs().log10().floor() as i32;
    if (0..=12).contains(&digits) {
        let s = format!("{x:.*}", digits as usize);
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{x:.5e}")
    }
}

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "-".to_string(), fmt_num)
}

/// Metrics as rows, one column per evaluated label.
fn table(cols: &[(String, &Metrics)]) -> String {
    let Some((_, first)) = cols.first() else {
        return String::new();
    };
    let u = &first.unit;
    type Row = (String, fn(&Metrics) -> String);
    let rows: Vec<Row> = vec![
        ("TP (voxels)".into(), |m| m.tp.to_string()),
        ("FP (voxels)".into(), |m| m.fp.to_string()),
        ("FN (voxels)".into(), |m| m.fn_.to_string()),
        ("TN (voxels)".into(), |m| m.tn.to_string()),
        ("Dice".into(), |m| fmt_opt(m.dice)),
        ("Jaccard".into(), |m| fmt_opt(m.jaccard)),
        ("sensitivity".into(), |m| fmt_opt(m.sensitivity)),
        ("specificity".into(), |m| fmt_opt(m.specificity)),
        ("precision".into(), |m| fmt_opt(m.precision)),
        ("volume similarity".into(), |m| fmt_opt(m.volume_similarity)),
        (format!("volume GT ({u}³)"), |m| fmt_num(m.volume_gt)),
        (format!("volume seg ({u}³)"), |m| fmt_num(m.volume_seg)),
        (format!("HD ({u})"), |m| fmt_opt(m.hd)),
        (format!("HD95, max of directed ({u})"), |m| fmt_opt(m.hd95)),
        (format!("HD95, pooled ({u})"), |m| fmt_opt(m.hd95_pooled)),
        (format!("ASSD, pooled ({u})"), |m| fmt_opt(m.assd)),
        (format!("MASD, mean of means ({u})"), |m| fmt_opt(m.masd)),
        (format!("NSD @ {} {u}", fmt_num(first.tolerance)), |m| {
            fmt_opt(m.nsd)
        }),
        ("border voxels GT".into(), |m| m.border_gt.to_string()),
        ("border voxels seg".into(), |m| m.border_seg.to_string()),
    ];
    let head = "metric".to_string();
    let w0 = rows
        .iter()
        .map(|r| r.0.chars().count())
        .max()
        .unwrap_or(0)
        .max(head.len());
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|(_, f)| cols.iter().map(|(_, m)| f(m)).collect())
        .collect();
    let widths: Vec<usize> = (0..cols.len())
        .map(|c| {
            cells
                .iter()
                .map(|r| r[c].chars().count())
                .chain([cols[c].0.chars().count()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let pad = |s: &str, w: usize| format!("{s}{}", " ".repeat(w - s.chars().count()));
    let mut out = pad(&head, w0);
    for (c, (name, _)) in cols.iter().enumerate() {
        out += &format!("  {name:>w$}", w = widths[c]);
    }
    out.push('\n');
    for ((name, _), r) in rows.iter().zip(&cells) {
        out += &pad(name, w0);
        for (c, v) in r.iter().enumerate() {
            out += &format!("  {v:>w$}", w = widths[c]);
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::fmt_num;

    #[test]
    fn numbers_for_people() {
        assert_eq!(fmt_num(3.0), "3");
        assert_eq!(fmt_num(0.8227), "0.8227");
        assert_eq!(fmt_num(0.92421299203), "0.924213");
        assert_eq!(fmt_num(17.349351572897472), "17.3494");
        assert_eq!(fmt_num(1234.5678), "1234.57");
        assert_eq!(fmt_num(1e-9 + 1e-12), "1.00100e-9");
    }
}
