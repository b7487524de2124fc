//! `interslice study GROUND_TRUTH --out DIR [--image IMAGE] [--axis z] [--skips 0..9]
//! [--methods a,b,...] [--label N] [--seconds-per-contour S]`: the interpolation study of the 2014 paper, on
//! any fully traced label volume (`interslice_project::report::study` measures
//! each run and writes the report files). With `--image` (the intensity volume
//! on the ground truth's grid) the image-guided method is studied too, next to
//! the shape-only ones. The (method, k) runs go in parallel. The time to
//! ground truth of a tracer spending S seconds per traced slice is printed
//! (minutes = slices × S / 60, with the Dice) and written to `effort.csv`.
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use interslice_core::Axis;
use interslice_interp::drawn::nonempty_slices;
use interslice_interp::image::Conditioned;
use interslice_interp::{IMAGE_METHOD, Interpolator, by_name_with_image, methods};
use interslice_project::report::study::{
    Provenance, Row, StudyReport, effort_curve, measure, phantom_command, write,
};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `study`.
#[derive(clap::Args)]
pub struct Args {
    /// The fully traced label volume (the ground truth).
    pub ground_truth: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Axis along which slices are dropped.
    #[arg(long, default_value = "z")]
    pub axis: Axis,
    /// Numbers of skipped slices: a range `A..B` (inclusive) or a list `0,2,5`.
    #[arg(long, default_value = "0..9")]
    pub skips: String,
    /// Comma-separated methods (default: every registered method).
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// The intensity volume on the ground truth's grid: adds the image-guided method.
    #[arg(long)]
    pub image: Option<PathBuf>,
    /// Study only this label (default: every label of the ground truth). A number or a component's name.
    #[arg(long = "label", value_name = "L")]
    pub label_arg: Option<crate::label::LabelArg>,
    /// Instead of dropping slices: simulate a tracer who traces the outermost
    /// slices and then `--budget` more chosen by these strategies
    /// (`uniform`, `advised`, or `oracle`: the best slices found knowing the ground truth, the ceiling of any advice; slow), and compare the Dice (strategy.csv, strategy.md).
    #[arg(long, value_delimiter = ',')]
    pub strategy: Option<Vec<String>>,
    /// Slices traced after the outermost two, for `--strategy`: a range
    /// `A..B` (inclusive) or a list.
    #[arg(long, default_value = "4..12")]
    pub budget: String,
    /// Seconds the simulated tracer spends per traced slice (30–60 in the
    /// 2014 study): the minutes of the time-to-ground-truth curve.
    #[arg(long, default_value_t = 45, value_parser = clap::value_parser!(u32).range(1..=3600))]
    pub seconds_per_contour: u32,
    /// NSD tolerance in physical units.
    #[arg(long, default_value_t = interslice_core::metrics::DEFAULT_TOLERANCE)]
    pub tolerance: f64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Run `study`.
pub fn run(a: Args) -> Result<()> {
    let label = a
        .label_arg
        .as_ref()
        .map(|l| l.resolve(&[&a.ground_truth]))
        .transpose()?;
    let skips = parse_skips(&a.skips)?;
    let gt = interslice_io::read_labels(&a.ground_truth)
        .with_context(|| format!("reading {}", a.ground_truth.display()))?;
    let image = match &a.image {
        Some(p) => Some(Conditioned::from(super::interpolate::read_image(p, &gt)?)),
        None => None,
    };
    let chosen: Vec<Box<dyn Interpolator>> = match &a.methods {
        Some(names) => names
            .iter()
            .map(|n| by_name_with_image(Some(n.trim()), image.clone()).map_err(anyhow::Error::from))
            .collect::<Result<_>>()?,
        None => {
            let mut all = methods();
            if image.is_some() {
                all.insert(0, by_name_with_image(Some(IMAGE_METHOD), image.clone())?);
            }
            all
        }
    };
    if chosen.is_empty() {
        bail!("no methods to study");
    }
    let present: Vec<u16> = gt
        .label_counts()
        .iter()
        .map(|&(l, _)| l)
        .filter(|&l| l != 0)
        .collect();
    let labels = match label {
        Some(l) if present.contains(&l) => vec![l],
        Some(l) => bail!("label {l} is not in {}", a.ground_truth.display()),
        None if present.is_empty() => bail!("{} has no labels", a.ground_truth.display()),
        None => present,
    };
    let nonempty = nonempty_slices(&gt, a.axis);
    let (first, last) = match (nonempty.first(), nonempty.last()) {
        (Some(&f), Some(&l)) if l > f => (f, l),
        _ => bail!(
            "the ground truth needs objects on at least two slices along {}",
            a.axis
        ),
    };
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    if let Some(names) = &a.strategy {
        return run_strategies(&a, names, &gt, image, first, last, &labels);
    }

    let jobs: Vec<(usize, usize)> = (0..chosen.len())
        .flat_map(|m| skips.iter().map(move |&k| (m, k)))
        .collect();
    let bar = if a.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(jobs.len() as u64)
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} runs, {elapsed} elapsed, ~{eta} left {msg}",
        )
        .expect("valid template"),
    );
    let started = Instant::now();
    let results: Vec<Result<Vec<Row>>> = jobs
        .par_iter()
        .map(|&(m, k)| {
            let method = chosen[m].as_ref();
            let r = measure(method, &gt, a.axis, first, last, k, &labels, a.tolerance);
            bar.inc(1);
            bar.set_message(format!("({} k={k})", method.name()));
            r.with_context(|| format!("{} with {k} skipped", method.name()))
        })
        .collect();
    bar.finish_and_clear();
    let total = started.elapsed().as_secs_f64();
    let mut rows = Vec::new();
    for r in results {
        rows.extend(r?);
    }
    let names: Vec<&str> = chosen.iter().map(|m| m.name()).collect();
    let ctx = StudyReport {
        source: &a.ground_truth,
        provenance: provenance(&a, label),
        gt: &gt,
        axis: a.axis,
        labels: &labels,
        methods: &names,
        skips: &skips,
        rows: &rows,
        seconds: total,
        seconds_per_contour: f64::from(a.seconds_per_contour),
    };
    write(&a.out, &ctx)?;
    let shown = ctx.curve_method().unwrap_or_default();
    for (m, k, n, minutes, sk, vol) in effort_curve(&ctx) {
        if m == shown {
            println!(
                "{m:<12} k={k:<2}: {n:>3} traced slices, {minutes:>6.1} min at {} s/slice, Dice skipped {}, volume {}",
                a.seconds_per_contour,
                sk.map_or("–".into(), |d| format!("{d:.4}")),
                vol.map_or("–".into(), |d| format!("{d:.4}"))
            );
        }
    }
    eprintln!(
        "study: {} methods x {} skips x {} labels in {total:.1} s, results in {}",
        names.len(),
        skips.len(),
        labels.len(),
        a.out.display()
    );
    Ok(())
}

/// `A..B` (inclusive), `A..=B` or `a,b,c`.
pub fn parse_skips(s: &str) -> Result<Vec<usize>> {
    let bad = || anyhow::anyhow!("--skips '{s}': expected A..B or a comma list of integers");
    let mut out: Vec<usize> = if let Some((a, b)) = s.split_once("..") {
        let a: usize = a.trim().parse().map_err(|_| bad())?;
        let b: usize = b
            .trim()
            .trim_start_matches('=')
            .parse()
            .map_err(|_| bad())?;
        if b < a {
            return Err(bad());
        }
        (a..=b).collect()
    } else {
        s.split(',')
            .map(|x| x.trim().parse().map_err(|_| bad()))
            .collect::<Result<_>>()?
    };
    out.sort_unstable();
    out.dedup();
    if out.is_empty() {
        return Err(bad());
    }
    Ok(out)
}

/// The provenance of a study run with `a`.
fn provenance(a: &Args, label: Option<u16>) -> Provenance {
    let gt = &a.ground_truth;
    let name = gt
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_default();
    let dir = gt
        .parent()
        .and_then(|d| d.file_name())
        .map(|d| d.to_string_lossy().to_string())
        .unwrap_or_else(|| "phantom".into());
    let phantom = phantom_command(gt, &dir);
    let mut study = match &phantom {
        Some(_) => format!("interslice study {dir}/{name}"),
        None => format!("interslice study {name}"),
    };
    let _ = write!(study, " --out {}", a.out.display());
    if a.axis != Axis::Z {
        let _ = write!(study, " --axis {}", a.axis);
    }
    if a.skips != "0..9" {
        let _ = write!(study, " --skips {}", a.skips);
    }
    if let Some(m) = &a.methods {
        let _ = write!(study, " --methods {}", m.join(","));
    }
    if let Some(p) = &a.image {
        let _ = write!(study, " --image {}", p.display());
    }
    if let Some(l) = label {
        let _ = write!(study, " --label {l}");
    }
    if a.seconds_per_contour != 45 {
        let _ = write!(study, " --seconds-per-contour {}", a.seconds_per_contour);
    }
    if a.tolerance != interslice_core::metrics::DEFAULT_TOLERANCE {
        let _ = write!(study, " --tolerance {}", a.tolerance);
    }
    let commands = phantom.iter().cloned().chain([study]).collect();
    Provenance { phantom, commands }
}

/// `study --strategy`: uniform against advised slice choice at every budget.
fn run_strategies(
    a: &Args,
    names: &[String],
    gt: &interslice_core::LabelVolume,
    image: Option<Conditioned>,
    first: usize,
    last: usize,
    labels: &[u16],
) -> Result<()> {
    use interslice_project::report::strategy::{Simulation, Strategy, write};
    let strategies: Vec<Strategy> = names
        .iter()
        .map(|n| Strategy::of_name(n))
        .collect::<Result<_, _>>()?;
    let budgets = parse_skips(&a.budget).context("--budget")?;
    let method = a.methods.as_ref().and_then(|m| m.first()).map(|m| m.trim());
    let sim = Simulation {
        gt,
        axis: a.axis,
        first,
        last,
        labels,
        method,
        image,
    };
    let started = Instant::now();
    let rows = sim.run(&strategies, &budgets)?;
    let spc = f64::from(a.seconds_per_contour);
    write(&a.out, &rows, spc)?;
    for r in &rows {
        println!(
            "{:<8} budget {:>2}: {:>2} traced slices, {:>6.1} min at {} s/slice, Dice skipped {:.4}, volume {:.4}",
            r.strategy.name(),
            r.budget,
            r.traced.len(),
            interslice_project::report::effort::minutes(r.traced.len(), spc),
            a.seconds_per_contour,
            r.dice_skipped,
            r.dice_volume
        );
    }
    println!(
        "{:.1} s -> {}",
        started.elapsed().as_secs_f64(),
        a.out.join("strategy.md").display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skips_parse() {
        assert_eq!(parse_skips("0..3").unwrap(), vec![0, 1, 2, 3]);
        assert_eq!(parse_skips("0..=2").unwrap(), vec![0, 1, 2]);
        assert_eq!(parse_skips("5, 2,2").unwrap(), vec![2, 5]);
        assert!(parse_skips("3..1").is_err());
        assert!(parse_skips("a").is_err());
    }
}
