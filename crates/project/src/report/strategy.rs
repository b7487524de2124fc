//! `study --strategy`: a simulated tracer who traces each structure (label)
//! on its own, as the tracing screen has one component traced at a time:
//! its outermost slices, then `budget` more slices chosen either uniformly
//! or by the advice (`interslice_interp::advise`), and the Dice of the
//! interpolation against the ground truth at every budget: on the skipped
//! slices of the structure and on the whole volume, per label and as the
//! mean over the labels; and the minutes the simulated tracer spent
//! (traced slices × seconds per contour / 60).
//!
//! `oracle` is the ceiling any advice could reach: a tracer who knows the
//! ground truth. At each budget it starts from the better (whole-volume
//! Dice) of a greedy pick — one slice at a time, the slice that raises the
//! whole-volume Dice most, every untraced slice tried — and uniform spacing,
//! then moves each traced slice one or two slices either way while that
//! raises the Dice (a local search). A greedy choice alone is not the best
//! set and fell behind uniform spacing at some budgets; starting from both
//! and refining, the oracle is never below uniform spacing. It is slow, and
//! only a yardstick.
//!
//! The advised tracer knows its budget, as a tracer who set out to trace N
//! more slices does: before each slice it asks for the advice on the slices
//! it still has (`count` = what is left), traces the first, and asks again
//! with what it learnt, so the advice can spread the remaining slices over
//! the gaps instead of halving one gap after another.
use super::write_text;
use crate::error::ProjectError;
use interslice_core::{Axis, LabelVolume};
use interslice_interp::advise::advise;
use interslice_interp::image::Conditioned;
use interslice_interp::protocol::{dice_on, sparse_of};
use interslice_interp::{by_name_with_image, interpolate_labels};
use std::fmt::Write as _;
use std::path::Path;

/// How the simulated tracer chooses the slices after the outermost two.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strategy {
    /// Evenly spaced between the outermost slices.
    Uniform,
    /// The advice's best slice, asked again after each traced slice.
    Advised,
    /// The best slices for the whole-volume Dice, knowing the truth.
    Oracle,
}

impl Strategy {
    /// The `--strategy` name.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Uniform => "uniform",
            Strategy::Advised => "advised",
            Strategy::Oracle => "oracle",
        }
    }

    /// The strategy of a `--strategy` name.
    pub fn of_name(name: &str) -> Result<Strategy, ProjectError> {
        match name.trim() {
            "uniform" => Ok(Strategy::Uniform),
            "advised" => Ok(Strategy::Advised),
            "oracle" => Ok(Strategy::Oracle),
            other => Err(ProjectError::invalid(format!(
                "unknown strategy '{other}' (uniform, advised or oracle)"
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
    pub image: Option<Conditioned>,
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

    /// The greedy slices for every budget up to `max`: the outermost two,
    /// then one at a time the untraced slice that raises the whole-volume
    /// Dice most (ties: the lower slice). Entry `b` holds `b` picks.
    fn greedy(&self, s: &Structure, max: usize) -> Result<Vec<Vec<usize>>, ProjectError> {
        let mut traced = vec![s.first, s.last];
        traced.dedup();
        let mut out = vec![traced.clone()];
        for _ in 0..max {
            let mut best: Option<(f64, usize)> = None;
            for c in s.first..=s.last {
                if traced.contains(&c) {
                    continue;
                }
                let mut t = traced.clone();
                t.push(c);
                t.sort_unstable();
                let d = self.score(s, &t)?.1;
                if best.is_none_or(|(bd, _)| d > bd) {
                    best = Some((d, c));
                }
            }
            if let Some((_, c)) = best {
                traced.push(c);
                traced.sort_unstable();
            }
            out.push(traced.clone());
        }
        Ok(out)
    }

    /// The oracle at `budget`: the better of the greedy slices and uniform
    /// spacing, refined by [`Simulation::refine`].
    fn oracle_at(
        &self,
        s: &Structure,
        greedy: &[usize],
        budget: usize,
    ) -> Result<Vec<usize>, ProjectError> {
        let uniform = uniform_slices(s.first, s.last, budget);
        let (g, u) = (self.score(s, greedy)?.1, self.score(s, &uniform)?.1);
        if g >= u {
            self.refine(s, greedy.to_vec(), g)
        } else {
            self.refine(s, uniform, u)
        }
    }

    /// Local search on the whole-volume Dice, from `traced` of Dice `best`:
    /// each inner traced slice is moved by one or two slices either way
    /// (staying between its neighbours) where that raises the Dice, until no
    /// move does (at most four passes over the slices).
    fn refine(
        &self,
        s: &Structure,
        mut traced: Vec<usize>,
        mut best: f64,
    ) -> Result<Vec<usize>, ProjectError> {
        for _ in 0..4 {
            let mut moved = false;
            for i in 1..traced.len().saturating_sub(1) {
                let (lo, here, hi) = (traced[i - 1], traced[i], traced[i + 1]);
                let moves = [
                    here + 1,
                    here + 2,
                    here.saturating_sub(1),
                    here.saturating_sub(2),
                ];
                for to in moves {
                    if to <= lo || to >= hi {
                        continue;
                    }
                    let mut t = traced.clone();
                    t[i] = to;
                    let d = self.score(s, &t)?.1;
                    if d > best {
                        (best, traced, moved) = (d, t, true);
                    }
                }
            }
            if !moved {
                break;
            }
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
        let max = budgets.iter().copied().max().unwrap_or(0);
        for s in self.labels.iter().filter_map(|&l| self.structure(l)) {
            let greedy = if strategies.contains(&Strategy::Oracle) {
                self.greedy(&s, max)?
            } else {
                Vec::new()
            };
            for &strategy in strategies {
                for &budget in budgets {
                    let traced = match strategy {
                        Strategy::Uniform => uniform_slices(s.first, s.last, budget),
                        Strategy::Advised => self.advised(&s, budget)?,
                        Strategy::Oracle => self.oracle_at(&s, &greedy[budget], budget)?,
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
    let mut present: Vec<Strategy> = Vec::new();
    for r in rows {
        if !present.contains(&r.strategy) {
            present.push(r.strategy);
        }
    }
    let names: Vec<&str> = present.iter().map(|s| s.name()).collect();
    let head =
        |what: &str| -> String { names.iter().map(|n| format!(" {n} ({what}) |")).collect() };
    let rule = "---:|".repeat(present.len());
    let mut md = format!(
        "# Which slices to trace: {}\n\n\
         Each structure is traced on its own: its outermost slices and `budget` more. \
         Dice of the interpolation on the structure's skipped slices and on the whole \
         volume, the mean over the labels; minutes at {seconds_per_contour} s per traced \
         slice.\n\n\
         | budget | traced | minutes |{}{}\n|---:|---:|---:|{rule}{rule}\n",
        names.join(" against "),
        head("skipped"),
        head("volume"),
    );
    for &b in &budgets {
        let traced = rows
            .iter()
            .find(|r| r.budget == b)
            .map_or(0, |r| r.traced.len());
        let _ = write!(
            md,
            "| {b} | {traced} | {:.1} |",
            super::effort::minutes(traced, seconds_per_contour)
        );
        for f in [
            |r: &StrategyRow| r.dice_skipped,
            |r: &StrategyRow| r.dice_volume,
        ] {
            for &s in &present {
                let _ = write!(md, " {} |", cell(mean(s, b, None, f)));
            }
        }
        md.push('\n');
    }
    let mut labels: Vec<u16> = rows.iter().map(|r| r.label).collect();
    labels.sort_unstable();
    labels.dedup();
    let _ = write!(
        md,
        "\nPer label, Dice on the skipped slices:\n\n| budget | label |{}\n|---:|---:|{rule}\n",
        names.iter().map(|n| format!(" {n} |")).collect::<String>()
    );
    for &b in &budgets {
        for &l in &labels {
            let _ = write!(md, "| {b} | {l} |");
            for &s in &present {
                let _ = write!(md, " {} |", cell(mean(s, b, Some(l), |r| r.dice_skipped)));
            }
            md.push('\n');
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
