//! `study --strategy`: a simulated tracer who traces the outermost slices of
//! the ground truth, then `budget` more slices chosen either uniformly or by
//! the advice (`interslice_interp::advise`, asked again after each traced
//! slice, as a tracer following the suggestion would), and the Dice of the
//! interpolation against the ground truth at every budget: on the skipped
//! slices and on the whole volume, the mean over the studied labels; and the
//! minutes the simulated tracer spent (traced slices × seconds per contour / 60).
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

/// One strategy at one budget.
#[derive(Debug, Clone, PartialEq)]
pub struct StrategyRow {
    /// The strategy.
    pub strategy: Strategy,
    /// Slices traced after the outermost two.
    pub budget: usize,
    /// Every traced slice, ascending.
    pub traced: Vec<usize>,
    /// Mean over the labels of the Dice on the skipped slices.
    pub dice_skipped: f64,
    /// Mean over the labels of the Dice on the whole volume.
    pub dice_volume: f64,
}

/// What is simulated.
pub struct Simulation<'a> {
    /// The ground truth.
    pub gt: &'a LabelVolume,
    /// Axis of the traced slices.
    pub axis: Axis,
    /// The outermost slices showing any label.
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

impl Simulation<'_> {
    /// The advised slices in the order a tracer following the advice traces
    /// them, at most `budget` (fewer when every slice is traced).
    fn advised_order(&self, budget: usize) -> Result<Vec<usize>, ProjectError> {
        let mut traced = vec![self.first, self.last];
        let mut order = Vec::new();
        for _ in 0..budget {
            let sparse = sparse_of(self.gt, self.axis, &traced);
            let a = advise(
                &sparse,
                self.axis,
                &traced,
                1,
                self.method,
                self.image.clone(),
            )?;
            let Some(s) = a.suggestions.first() else {
                break;
            };
            order.push(s.slice);
            traced.push(s.slice);
            traced.sort_unstable();
        }
        Ok(order)
    }

    /// Interpolate the ground truth's `traced` slices and score it.
    fn score(&self, traced: &[usize]) -> Result<(f64, f64), ProjectError> {
        let method = by_name_with_image(self.method, self.image.clone())?;
        let sparse = sparse_of(self.gt, self.axis, traced);
        let out = interpolate_labels(method.as_ref(), &sparse, self.axis, traced)?;
        let n = self.gt.slice_count(self.axis);
        let skipped: Vec<usize> = (self.first..=self.last)
            .filter(|s| !traced.contains(s))
            .collect();
        let all: Vec<usize> = (0..n).collect();
        let (mut sk, mut vol) = (0.0, 0.0);
        for &l in self.labels {
            let (a, b) = (out.map(|v| v == l), self.gt.map(|v| v == l));
            sk += dice_on(&a, &b, self.axis, &skipped);
            vol += dice_on(&a, &b, self.axis, &all);
        }
        let k = self.labels.len().max(1) as f64;
        Ok((sk / k, vol / k))
    }

    /// Every strategy at every budget.
    pub fn run(
        &self,
        strategies: &[Strategy],
        budgets: &[usize],
    ) -> Result<Vec<StrategyRow>, ProjectError> {
        let most = budgets.iter().copied().max().unwrap_or(0);
        let advised = if strategies.contains(&Strategy::Advised) {
            self.advised_order(most)?
        } else {
            Vec::new()
        };
        let mut rows = Vec::new();
        for &strategy in strategies {
            for &budget in budgets {
                let traced = match strategy {
                    Strategy::Uniform => uniform_slices(self.first, self.last, budget),
                    Strategy::Advised => {
                        let mut t = vec![self.first, self.last];
                        t.extend(advised.iter().take(budget));
                        t.sort_unstable();
                        t.dedup();
                        t
                    }
                };
                let (dice_skipped, dice_volume) = self.score(&traced)?;
                rows.push(StrategyRow {
                    strategy,
                    budget,
                    traced,
                    dice_skipped,
                    dice_volume,
                });
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
    let mut csv =
        String::from("strategy,budget,traced_slices,dice_skipped,dice_volume,traced,minutes\n");
    for r in rows {
        let traced: Vec<String> = r.traced.iter().map(usize::to_string).collect();
        let _ = writeln!(
            csv,
            "{},{},{},{:.6},{:.6},{},{:.3}",
            r.strategy.name(),
            r.budget,
            r.traced.len(),
            r.dice_skipped,
            r.dice_volume,
            traced.join(" "),
            minutes(r)
        );
    }
    write_text(&out.join("strategy.csv"), &csv)?;
    let mut budgets: Vec<usize> = rows.iter().map(|r| r.budget).collect();
    budgets.sort_unstable();
    budgets.dedup();
    let find = |s: Strategy, b: usize| rows.iter().find(|r| r.strategy == s && r.budget == b);
    let mut md = format!(
        "# Which slices to trace: uniform against advised\n\n\
         The outermost slices and `budget` more are traced; Dice of the interpolation \
         (mean over the labels) on the skipped slices and on the whole volume; minutes \
         at {seconds_per_contour} s per traced slice.\n\n\
         | budget | traced | minutes | uniform (skipped) | advised (skipped) | uniform (volume) | advised (volume) |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let cell = |r: Option<&StrategyRow>, f: fn(&StrategyRow) -> f64| {
        r.map_or("—".to_string(), |r| format!("{:.4}", f(r)))
    };
    for b in budgets {
        let (u, a) = (find(Strategy::Uniform, b), find(Strategy::Advised, b));
        let traced = u.or(a).map_or(0, |r| r.traced.len());
        let _ = writeln!(
            md,
            "| {b} | {traced} | {:.1} | {} | {} | {} | {} |",
            super::effort::minutes(traced, seconds_per_contour),
            cell(u, |r| r.dice_skipped),
            cell(a, |r| r.dice_skipped),
            cell(u, |r| r.dice_volume),
            cell(a, |r| r.dice_volume),
        );
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
