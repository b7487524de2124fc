//! Time to ground truth: what one user's tracing of one structure cost (traced
//! slices, time) and how good its interpolated result is expected to be (the
//! predicted Dice), so a study can report "minutes per cell at Dice ≥ 0.95".
//!
//! Used by `interslice variability` (its effort columns), the server's
//! `GET /api/cells/{cell}/summary` and, for the simulated tracer of
//! `interslice study`, [`minutes`].
//!
//! **The predicted Dice** is the leave-one-out estimate of
//! [`interslice_interp::predict`], the one the advice reports too.
use crate::error::ProjectError;
use crate::groundtruth::{StoredTracing, sparse_mask};
use interslice_core::{Axis, Cancel, Geometry};
use interslice_interp::Interpolator;
pub use interslice_interp::predict::LeaveOneOut;
use interslice_interp::predict::predicted_dice;
use interslice_store::{ContourQuery, Store};
use serde::Serialize;

/// Slices drawn of one label along one axis.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct AxisSlices {
    /// Slices with contours.
    pub traced: usize,
    /// Slices marked empty.
    pub empty: usize,
}

/// What one user's tracing of one label of a cell cost and is expected to give.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Effort {
    /// The label.
    pub label: u16,
    /// The axis the result is interpolated along (most drawn slices; ties z, y, x).
    pub axis: Axis,
    /// Slices with contours, over every axis.
    pub traced_slices: usize,
    /// Slices marked empty, over every axis.
    pub empty_slices: usize,
    /// Per axis, x, y, z.
    pub per_axis: [AxisSlices; 3],
    /// Sum of the recorded drawing times of the label's contours (s).
    pub contour_seconds: f64,
    /// The user's recorded tracing time on the cell, every label (s).
    pub cell_seconds: f64,
    /// The leave-one-out estimate along `axis`; `None` with fewer than three drawn slices.
    pub estimate: Option<LeaveOneOut>,
}

impl Effort {
    /// The time spent: the cell's recorded time (what the tracing screen
    /// counts, pauses excluded), or the contours' drawing time when no time
    /// was recorded.
    pub fn seconds(&self) -> f64 {
        if self.cell_seconds > 0.0 {
            self.cell_seconds
        } else {
            self.contour_seconds
        }
    }

    /// The predicted Dice of the result, when there is an estimate.
    pub fn predicted_dice(&self) -> Option<f64> {
        self.estimate.map(|e| e.predicted_dice)
    }
}

/// The effort and predicted Dice of `user_id`'s tracing of `label` on `cell`
/// (see the module docs); `method` is the interpolation method of the result.
pub fn tracing_effort(
    store: &Store,
    geometry: &Geometry,
    cell: &str,
    user_id: i64,
    label: u16,
    method: &dyn Interpolator,
    cancel: &Cancel,
) -> Result<Effort, ProjectError> {
    let mut per_axis = [AxisSlices::default(); 3];
    let mut best: Option<(Axis, usize)> = None;
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        let drawn = store.drawn(cell, user_id, label, axis)?;
        let empty = drawn.iter().filter(|d| d.empty).count();
        per_axis[axis.dim()] = AxisSlices {
            traced: drawn.len() - empty,
            empty,
        };
        // Ties go to the later axis, as `groundtruth::label_volume` chooses.
        if !drawn.is_empty() && best.is_none_or(|(_, n)| drawn.len() >= n) {
            best = Some((axis, drawn.len()));
        }
    }
    let contour_seconds = store
        .contours(&ContourQuery {
            cell: cell.to_string(),
            user_id,
            axis: None,
            index: None,
            label: Some(label),
        })?
        .iter()
        .filter_map(|c| c.duration_ms)
        .sum::<f64>()
        / 1000.0;
    let cell_seconds = store.time_spent(cell, user_id)?;
    let axis = best.map_or(Axis::Z, |b| b.0);
    let estimate = match best {
        Some((axis, n)) if n >= 3 => {
            let tracing = StoredTracing {
                store,
                cell,
                user_id,
            };
            let (mask, drawn) = sparse_mask(&tracing, geometry, label, axis)?;
            predicted_dice(&mask, axis, &drawn, method, cancel)?
        }
        _ => None,
    };
    Ok(Effort {
        label,
        axis,
        traced_slices: per_axis.iter().map(|a| a.traced).sum(),
        empty_slices: per_axis.iter().map(|a| a.empty).sum(),
        per_axis,
        contour_seconds,
        cell_seconds,
        estimate,
    })
}

/// Minutes a simulated tracer spends on `slices` slices at `seconds_per_contour`.
pub fn minutes(slices: usize, seconds_per_contour: f64) -> f64 {
    slices as f64 * seconds_per_contour / 60.0
}

/// The median of `x` (mean of the middle two for an even count); `None` when empty.
pub fn median(x: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    Some(if v.len() % 2 == 1 {
        v[m]
    } else {
        (v[m - 1] + v[m]) / 2.0
    })
}

/// The Dice a tracing is counted as ground truth at, in the reports.
pub const TARGET_DICE: f64 = 0.95;

/// The "Time to ground truth" section of a report: a row per (cell, user,
/// structure) and the median minutes per cell of the tracings (a cell by a
/// user) whose every structure is predicted to reach [`TARGET_DICE`]. A
/// tracing's minutes are the cell's recorded time, or the sum of its
/// structures' contour times when none was recorded. `md` escapes a table cell.
pub fn markdown(rows: &[(&str, &str, &str, &Effort)], md: fn(&str) -> String) -> String {
    use std::fmt::Write as _;
    let mut s = String::from(
        "## Time to ground truth\n\nPer tracing: slices traced (and marked empty), minutes \
         spent (the recorded tracing time of the cell, or the contours' drawing time) and the \
         predicted Dice of the interpolated result (leave-one-out on the drawn slices).\n\n\
         | cell | user | structure | traced slices | empty slices | minutes | predicted Dice |\n\
         |---|---|---|---:|---:|---:|---:|\n",
    );
    // (cell, user) → (seconds, all structures reach the target).
    let mut cells: Vec<((&str, &str), f64, bool)> = Vec::new();
    for &(cell, user, name, e) in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.1} | {} |",
            md(cell),
            md(user),
            md(name),
            e.traced_slices,
            e.empty_slices,
            e.seconds() / 60.0,
            e.predicted_dice()
                .map_or("–".to_string(), |d| format!("{d:.4}"))
        );
        let reaches = e.predicted_dice().is_some_and(|d| d >= TARGET_DICE);
        match cells.iter_mut().find(|c| c.0 == (cell, user)) {
            Some(c) => {
                if e.cell_seconds <= 0.0 {
                    c.1 += e.contour_seconds;
                }
                c.2 &= reaches;
            }
            None => cells.push(((cell, user), e.seconds(), reaches)),
        }
    }
    let reached: Vec<f64> = cells.iter().filter(|c| c.2).map(|c| c.1 / 60.0).collect();
    let _ = writeln!(
        s,
        "\nMinutes per cell at predicted Dice ≥ {TARGET_DICE}: {} ({} of {} tracings of a cell \
         reach it in every structure).\n",
        median(&reached).map_or("none reached".to_string(), |m| format!("median {m:.1}")),
        reached.len(),
        cells.len()
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&[]), None);
        assert_eq!(minutes(12, 45.0), 9.0);
    }
}
