//! Time to ground truth: what one user's tracing of one structure cost (traced
//! slices, time) and how good its interpolated result is expected to be (the
//! predicted Dice), so a study can report "minutes per cell at Dice ≥ 0.95".
//!
//! Used by `interslice variability` (its effort columns), the server's
//! `GET /api/cells/{cell}/summary` and, for the simulated tracer of
//! `interslice study`, [`minutes`].
//!
//! **The predicted Dice** ([`predicted_dice`]) is a leave-one-out estimate on
//! the tracer's own drawn slices, the only truth there is while tracing: an
//! inner drawn slice is dropped, predicted by the interpolation method from
//! the drawn slices around it, and compared with what was drawn. The
//! prediction spans the two gaps around the dropped slice, about twice the
//! gap the result interpolates across, so its error overstates the result's.
//! Interpolation of a smooth shape errs like a curve's chord: at a slice `t`
//! of a gap `[a, b]` the wrong voxels grow as `(t − a)(b − t)` (zero on the
//! drawn slices, largest in the middle). A held-out slice at distances `L₁`,
//! `L₂` from its neighbours has `e = c L₁ L₂` wrong voxels, which gives the
//! shape's rate `c`; over a gap of `L` slices of the result (one drawn,
//! `L − 1` interpolated) the mean wrong voxels per slice are then
//! `c (L² − 1) / 6`. Summed over the held-out slices and divided by their
//! areas (`Dice = 1 − |A Δ B| / (|A| + |B|)`), this is the expected Dice of
//! the result over the traced range; outside it both are empty. The plain
//! mean of the held-out slices' Dice is reported too (`loo_dice`): a lower
//! bound, measured across the doubled gaps.
use crate::error::ProjectError;
use crate::groundtruth::{StoredTracing, sparse_mask};
use interslice_core::{Axis, Cancel, Geometry, Mask};
use interslice_interp::loo::stack;
use interslice_interp::{Interpolator, SparseMask};
use interslice_store::{ContourQuery, Store};
use rayon::prelude::*;
use serde::Serialize;

/// At most this many inner drawn slices are held out (evenly chosen), so the
/// estimate costs a bounded number of small interpolations whatever the
/// number of drawn slices.
pub const MAX_HELD_OUT: usize = 12;

/// Drawn slices on each side of a held-out one that its prediction sees
/// (enough for the cubic and the choosing methods).
const NEIGHBOURS: usize = 2;

/// The leave-one-out estimate of a tracing's result.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LeaveOneOut {
    /// Inner drawn slices held out.
    pub held_out: usize,
    /// Mean Dice of the held-out slices against their drawing (across twice the gap).
    pub loo_dice: f64,
    /// Expected Dice of the interpolated result (see the module docs).
    pub predicted_dice: f64,
}

/// Up to `max` of the inner positions `1..n-1`, evenly spread.
fn held_positions(n: usize, max: usize) -> Vec<usize> {
    let inner = n.saturating_sub(2);
    if inner == 0 || max == 0 {
        return Vec::new();
    }
    let take = inner.min(max);
    let mut out: Vec<usize> = (0..take)
        .map(|i| 1 + (i * inner + inner / 2) / take)
        .map(|p| p.clamp(1, n - 2))
        .collect();
    out.dedup();
    out
}

/// The leave-one-out predicted Dice of interpolating `mask` (drawn on the
/// ascending slices `drawn` along `axis`) with `method`; `None` with fewer
/// than three drawn slices (no inner slice to hold out). Each held-out slice
/// is predicted from at most `NEIGHBOURS` drawn slices on each side,
/// stacked compactly (`interslice_interp::loo::stack`), so one estimate
/// costs at most [`MAX_HELD_OUT`] interpolations of five slices.
pub fn predicted_dice(
    mask: &Mask,
    axis: Axis,
    drawn: &[usize],
    method: &dyn Interpolator,
    cancel: &Cancel,
) -> Result<Option<LeaveOneOut>, ProjectError> {
    let n = drawn.len();
    if n < 3 || drawn.windows(2).any(|w| w[0] >= w[1]) {
        return Ok(None);
    }
    let held = held_positions(n, MAX_HELD_OUT);
    // (wrong voxels, |A| + |B|, L₁, L₂) of each held-out slice.
    let measured: Vec<(f64, f64, f64, f64)> = held
        .par_iter()
        .map(|&p| -> Result<(f64, f64, f64, f64), ProjectError> {
            cancel.check()?;
            let lo = p.saturating_sub(NEIGHBOURS);
            let hi = (p + NEIGHBOURS).min(n - 1);
            let real: Vec<usize> = drawn[lo..=hi].to_vec();
            let at = p - lo;
            let mut local = stack(mask, axis, &real)?;
            let (w, h) = local.slice_shape(axis);
            local.set_slice(axis, at, &vec![false; w * h])?;
            let kept: Vec<usize> = (0..real.len()).filter(|&i| i != at).collect();
            let stacked = method.for_stack(axis, &real)?;
            let out = stacked
                .as_deref()
                .unwrap_or(method)
                .interpolate(SparseMask::new(&local, axis, &kept).with_cancel(cancel))?;
            let truth = mask.slice(axis, drawn[p])?;
            let pred = out.slice(axis, at)?;
            let (mut wrong, mut sum) = (0u64, 0u64);
            for (&a, &b) in truth.iter().zip(&pred) {
                wrong += u64::from(a != b);
                sum += u64::from(a) + u64::from(b);
            }
            let l1 = (drawn[p] - drawn[p - 1]) as f64;
            let l2 = (drawn[p + 1] - drawn[p]) as f64;
            Ok((wrong as f64, sum as f64, l1, l2))
        })
        .collect::<Result<_, ProjectError>>()?;
    cancel.check()?;
    let dice = |wrong: f64, sum: f64| if sum > 0.0 { 1.0 - wrong / sum } else { 1.0 };
    let loo_dice = measured.iter().map(|&(e, s, _, _)| dice(e, s)).sum::<f64>() / held.len() as f64;
    // The expected wrong voxels per slice of the result near each held-out
    // slice: c (L² − 1) / 6 with c = e / (L₁ L₂) and L the mean of the two gaps.
    let (wrong, sum) = measured
        .iter()
        .fold((0.0, 0.0), |(w, s), &(e, area, l1, l2)| {
            let l = (l1 + l2) / 2.0;
            (w + e / (l1 * l2) * (l * l - 1.0) / 6.0, s + area)
        });
    Ok(Some(LeaveOneOut {
        held_out: held.len(),
        loo_dice,
        predicted_dice: dice(wrong, sum).clamp(0.0, 1.0),
    }))
}

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
    use interslice_core::phantom::{PhantomParams, generate};

    #[test]
    fn held_out_positions_are_inner_distinct_and_bounded() {
        assert!(held_positions(2, 12).is_empty());
        assert_eq!(held_positions(3, 12), [1]);
        assert_eq!(held_positions(6, 12), [1, 2, 3, 4]);
        let p = held_positions(100, 12);
        assert_eq!(p.len(), 12);
        assert!(p.windows(2).all(|w| w[0] < w[1]));
        assert!(p[0] >= 1 && p[11] <= 98);
    }

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&[]), None);
        assert_eq!(minutes(12, 45.0), 9.0);
    }

    /// On the phantom, traced every `k + 1` slices, the predicted Dice is
    /// within 0.05 of the true Dice of the interpolation against the phantom
    /// (k = 3: 9 drawn slices, k = 5: 6). With only four drawn slices (k = 9)
    /// two slices are held out and the estimate is rougher (0.07 too high).
    #[test]
    fn predicted_dice_is_close_to_the_true_dice_on_the_phantom() {
        let p = generate(&PhantomParams {
            size: 48,
            seed: 3,
            bits: 8,
            noise: 0.0,
        })
        .unwrap();
        let method = crate::methods::method_by_name(None).unwrap();
        let label = 1u16;
        let truth = p.labels.mask_of(label);
        let nonempty: Vec<usize> = (0..truth.slice_count(Axis::Z))
            .filter(|&z| truth.slice(Axis::Z, z).unwrap().iter().any(|&b| b))
            .collect();
        let (first, last) = (nonempty[0], *nonempty.last().unwrap());
        for (k, tolerance) in [(3usize, 0.05), (5, 0.05), (9, 0.1)] {
            let drawn = interslice_interp::protocol::drawn_for(first, last, k);
            let sparse = interslice_interp::protocol::sparse_of(&p.labels, Axis::Z, &drawn);
            let sparse = sparse.mask_of(label);
            let out = method
                .interpolate(SparseMask::new(&sparse, Axis::Z, &drawn))
                .unwrap();
            let true_dice = interslice_core::metrics::overlap_masks(&truth, &out)
                .unwrap()
                .dice()
                .unwrap();
            let e = predicted_dice(&sparse, Axis::Z, &drawn, method.as_ref(), &Cancel::new())
                .unwrap()
                .unwrap();
            eprintln!(
                "k={k}: {} drawn, true Dice {true_dice:.4}, predicted {:.4}, loo {:.4}",
                drawn.len(),
                e.predicted_dice,
                e.loo_dice
            );
            assert!(
                (e.predicted_dice - true_dice).abs() <= tolerance,
                "k={k}: true {true_dice:.4}, predicted {:.4}",
                e.predicted_dice
            );
            assert_eq!(e.held_out, (drawn.len() - 2).min(MAX_HELD_OUT));
        }
    }
}
