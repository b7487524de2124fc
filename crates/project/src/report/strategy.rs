//! `study --strategy`: a simulated tracer who traces each structure (label)
//! on its own, as the tracing screen has one component traced at a time:
//! its outermost slices, then `budget` more slices chosen either uniformly
//! or by the advice (`interslice_interp::advise`), and the Dice of the
//! interpolation against the ground truth at every budget: on the skipped
//! slices of the structure and on the whole volume, per label and as the
//! mean over the labels; and the minutes the simulated tracer spent
//! (traced slices × seconds per contour / 60).
//!
//! The advised tracer knows its budget, as a tracer who set out to trace N
//! more slices does: before each slice it asks for the advice on the slices
//! it still has (`count` = what is left), traces the first, and asks again
//! with what it learnt, so the advice can spread the remaining slices over
//! the gaps instead of halving one gap after another.
use super::write_text;
use crate::error::ProjectError;
use interslice_core::{Axis, LabelVolume, Volume};
use interslice_interp::advise::advise;
use interslice_interp::protocol::{dice_on, sparse_of};
use interslice_interp::{by_name_with_image, interpolate_labels};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

/// How the simulated tracer chooses the slices after the outermost two.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strategy {
    /// Evenly spaced between the outermost slices.
    Uniform,
    /// The advice's best slice, asked again after each traced slice.
    Advised,
}

impl Strategy {
    /// The `--strategy` name.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Uniform => "uniform",
            Strategy::Advised => "advised",
        }
    }

    /// The strategy of a `--strategy` name.
    pub fn of_name(name: &str) -> Result<Strategy, ProjectError> {
        match name.trim() {
            "uniform" => Ok(Strategy::Uniform),
            "advised" => Ok(Strategy::Advised),
            other => Err(ProjectError::invalid(format!(
                "unknown strategy '{other}' (uniform or advised)"
            ))),
        }
    }
}

/// One strategy at one budget for one label.
#[derive(Debug, Clone, PartialEq)]
pub struct StrategyRow {
    /// The strategy.
    pub strategy: Strategy,
    /// The label traced.
    pub label: u16,
    /// Slices traced after the outermost two.
    pub budget: usize,
    /// Every traced slice, ascending.
    pub traced: Vec<usize>,
    /// Dice on the structure's skipped slices.
    pub dice_skipped: f64,
    /// Dice on the whole volume.
    pub dice_volume: f64,
}

/// What is simulated.
pub struct Simulation<'a> {
    /// The ground truth.
    pub gt: &'a LabelVolume,
    /// Axis of the traced slices.
    pub axis: Axis,
    /// The slices studied: each label's outermost slices are looked for
    /// between these.
    pub first: usize,
    /// See `first`.
    pub last: usize,
    /// The labels scored.
    pub labels: &'a [u16],
    /// The interpolation method's name (default as for `interpolate`).
    pub method: Option<&'a str>,
    /// The intensity volume for the image-aware method.
    pub image: Option<Arc<Volume<f32>>>,
}

/// `budget` slices evenly spaced strictly between `first` and `last`, with
/// the outermost two.
pub fn uniform_slices(first: usize, last: usize, budget: usize) -> Vec<usize> {
    let span = last - first;
    let mut s: Vec<usize> = (1..=budget)
        .map(|i| first + (span * i + budget.div_ceil(2)) / (budget + 1))
        .filter(|&x| x > first && x < last)
        .collect();
    s.push(first);
    s.push(last);
    s.sort_unstable();
    s.dedup();
    s
}

/// One label of the ground truth traced alone.
struct Structure {
    label: u16,
    /// The ground truth of this label only.
    gt: LabelVolume,
    first: usize,
    last: usize,
}

impl Simulation<'_> {
    /// The label alone and its outermost slices (None when it is absent).
    fn structure(&self, label: u16) -> Option<Structure> {
        let gt = self.gt.map(|v| if v == label { label } else { 0 });
        let present: Vec<usize> = (self.first..=self.last)
            .filter(|&s| {
                gt.slice(self.axis, s)
                    .is_ok_and(|sl| sl.iter().any(|&v| v != 0))
            })
            .collect();
        Some(Structure {
            label,
            first: *present.first()?,
            last: *present.last()?,
            gt,
        })
    }

    /// The slices a tracer with `budget` more slices traces following the
    /// advice, the outermost two included.
    fn advised(&self, s: &Structure, budget: usize) -> Result<Vec<usize>, ProjectError> {
        let mut traced = vec![s.first, s.last];
        traced.dedup();
        for left in (1..=budget).rev() {
            let sparse = sparse_of(&s.gt, self.axis, &traced);
            let a = advise(
                &sparse,
                self.axis,
                &traced,
                left,
                self.method,
                self.image.clone(),
            )?;
            let Some(next) = a.suggestions.first() else {
                break;
            };
            traced.push(next.slice);
            traced.sort_unstable();
        }
        Ok(traced)
    }

    /// Interpolate the structure's `traced` slices and score it.
    fn score(&self, s: &Structure, traced: &[usize]) -> Result<(f64, f64), ProjectError> {
        let method = by_name_with_image(self.method, self.image.clone())?;
        let sparse = sparse_of(&s.gt, self.axis, traced);
        let out = interpolate_labels(method.as_ref(), &sparse, self.axis, traced)?;
        let n = self.gt.slice_count(self.axis);
        let skipped: Vec<usize> = (s.first..=s.last).filter(|x| !traced.contains(x)).collect();
        let all: Vec<usize> = (0..n).collect();
        let (a, b) = (out.map(|v| v == s.label), s.gt.map(|v| v == s.label));
        Ok((
            dice_on(&a, &b, self.axis, &skipped),
            dice_on(&a, &b, self.axis, &all),
        ))
    }

    /// Every strategy at every budget, for every label.
    pub fn run(
        &self,
        strategies: &[Strategy],
        budgets: &[usize],
    ) -> Result<Vec<StrategyRow>, ProjectError> {
        let mut rows = Vec::new();
        for s in self.labels.iter().filter_map(|&l| self.structure(l)) {
            for &strategy in strategies {
                for &budget in budgets {
                    let traced = match strategy {
                        Strategy::Uniform => uniform_slices(s.first, s.last, budget),
                        Strategy::Advised => self.advised(&s, budget)?,
                    };
                    let (dice_skipped, dice_volume) = self.score(&s, &traced)?;
                    rows.push(StrategyRow {
                        strategy,
                        label: s.label,
                        budget,
                        traced,
                        dice_skipped,
                        dice_volume,
                    });
                }
            }
        }
        Ok(rows)
    }
}

/// Write `strategy.csv` and `strategy.md` (a table by budget) into `out`;
/// the simulated tracer spends `seconds_per_contour` on each traced slice.
pub fn write(
    out: &Path,
    rows: &[StrategyRow],
    seconds_per_contour: f64,
) -> Result<(), ProjectError> {
    let minutes = |r: &StrategyRow| super::effort::minutes(r.traced.len(), seconds_per_contour);
    let mut csv = String::from(
        "strategy,budget,traced_slices,dice_skipped,dice_volume,traced,minutes,label\n",
    );
    for r in rows {
        let traced: Vec<String> = r.traced.iter().map(usize::to_string).collect();
        let _ = writeln!(
            csv,
            "{},{},{},{:.6},{:.6},{},{:.3},{}",
            r.strategy.name(),
            r.budget,
            r.traced.len(),
            r.dice_skipped,
            r.dice_volume,
            traced.join(" "),
            minutes(r),
            r.label
        );
    }
    write_text(&out.join("strategy.csv"), &csv)?;
    let mut budgets: Vec<usize> = rows.iter().map(|r| r.budget).collect();
    budgets.sort_unstable();
    budgets.dedup();
    let mean = |s: Strategy, b: usize, label: Option<u16>, f: fn(&StrategyRow) -> f64| {
        let v: Vec<f64> = rows
            .iter()
            .filter(|r| r.strategy == s && r.budget == b && label.is_none_or(|l| l == r.label))
            .map(f)
            .collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let cell = |x: Option<f64>| x.map_or("—".to_string(), |x| format!("{x:.4}"));
    let mut md = format!(
        "# Which slices to trace: uniform against advised\n\n\
         Each structure is traced on its own: its outermost slices and `budget` more. \
         Dice of the interpolation on the structure's skipped slices and on the whole \
         volume, the mean over the labels; minutes at {seconds_per_contour} s per traced \
         slice.\n\n\
         | budget | traced | minutes | uniform (skipped) | advised (skipped) | uniform (volume) | advised (volume) |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let (u, a) = (Strategy::Uniform, Strategy::Advised);
    for &b in &budgets {
        let traced = rows
            .iter()
            .find(|r| r.budget == b)
            .map_or(0, |r| r.traced.len());
        let _ = writeln!(
            md,
            "| {b} | {traced} | {:.1} | {} | {} | {} | {} |",
            super::effort::minutes(traced, seconds_per_contour),
            cell(mean(u, b, None, |r| r.dice_skipped)),
            cell(mean(a, b, None, |r| r.dice_skipped)),
            cell(mean(u, b, None, |r| r.dice_volume)),
            cell(mean(a, b, None, |r| r.dice_volume)),
        );
    }
    let mut labels: Vec<u16> = rows.iter().map(|r| r.label).collect();
    labels.sort_unstable();
    labels.dedup();
    md.push_str(
        "\nPer label, Dice on the skipped slices:\n\n\
         | budget | label | uniform | advised |\n|---:|---:|---:|---:|\n",
    );
    for &b in &budgets {
        for &l in &labels {
            let _ = writeln!(
                md,
                "| {b} | {l} | {} | {} |",
                cell(mean(u, b, Some(l), |r| r.dice_skipped)),
                cell(mean(a, b, Some(l), |r| r.dice_skipped)),
            );
        }
    }
    write_text(&out.join("strategy.md"), &md)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_slices_are_evenly_spread_with_both_ends() {
        assert_eq!(uniform_slices(10, 40, 2), [10, 20, 30, 40]);
        assert_eq!(uniform_slices(0, 9, 0), [0, 9]);
        let s = uniform_slices(3, 60, 7);
        assert_eq!(s.len(), 9);
        assert!(s.windows(2).all(|w| w[1] > w[0] && w[1] - w[0] <= 8));
        // More slices than there are: every slice once.
        assert_eq!(uniform_slices(0, 3, 10), [0, 1, 2, 3]);
    }
}
