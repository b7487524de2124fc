//! Which slice to trace next: the undrawn slices ranked by how many wrong
//! voxels tracing them is expected to correct.
//!
//! **The error model.** Between two drawn slices `a < b` the interpolation
//! is exact at both ends and least sure in the middle. The expected number
//! of wrong voxels on an undrawn slice `t` of the gap is modelled as
//! `ρ · (t − a)(b − t) / (b − a)`, the variance profile of a random walk
//! pinned at both ends (a Brownian bridge): the further from a drawn slice,
//! the more the shape may have wandered. `ρ` is the gap's *rate*, in wrong
//! voxels per slice. Summed over the gap the expected error is about
//! `ρ L² / 6` (`L = b − a`); drawing slice `s` splits the gap into `L₁ + L₂`
//! and leaves `ρ (L₁² + L₂²) / 6`, so the **gain** of drawing `s` is
//! `ρ L₁ L₂ / 3` voxels: largest at the middle of the gap, and largest in
//! the gaps where the shape is hardest to predict.
//!
//! **The rate of a gap** comes from the tracer's own slices:
//! * leave-one-out (see [`crate::loo`]): each interior drawn slice is
//!   predicted from its drawn neighbours by the method that will fill the
//!   gaps (so with an image, the image-aware one); the prediction's wrong
//!   voxels `e` at the middle of a span `L'` give `ρ = 4e / L'`. A gap takes
//!   the mean rate of the held-out slices at its two ends.
//! * the change between the gap's own two slices, `|A Δ B|`: the shape's
//!   first derivative. Interpolation recovers a steady change, so only a
//!   share of it counts: `ρ ≥ |A Δ B| / (4L)`, which is what decides the
//!   outermost gaps (no held-out slice on one side) and a tracing of only
//!   two slices.
//!
//! **The bulge of a slice.** A rate is one number per gap, but a round
//! structure changes fastest towards its ends. The drawn areas give each
//! skipped slice `t` a second estimate, `κ(t)` wrong voxels per slice², from
//! how the cross-section bulges there (`bulge_density`: zero for a cone or
//! a cylinder, large near a pole). A skipped slice of a (sub-)gap `[p, q]`
//! counts `max(ρ / (q − p), κ(t)) (t − p)(q − t)` wrong voxels: the larger
//! of the two, so slices go first to the ends of a round structure, and a
//! cone's tip, which the shape methods follow, draws none.
//!
//! **The level.** The model ranks the gaps; how wrong the result is overall
//! is the leave-one-out estimate of [`crate::predict`] (the predicted Dice
//! the tracing summary shows too, one definition for both), pooled over the
//! labels. The model's own total, `E` expected wrong voxels over a structure
//! of `V` voxels (the drawn areas integrated along the axis, trapezoid rule),
//! `1 − E / (2V)`, is scaled to that level, and every gain with it: the
//! predicted rise of Dice from one more slice is `gain / (2V)` times that
//! scale, which the "done when" hint compares with the user's threshold.
//! With two drawn slices there is nothing to hold out, and the model's own
//! `1 − E / (2V)` is the predicted Dice.
//!
//! Several labels share the drawn slices: a gap's rate is the sum of the
//! labels' rates (and bulges), `V` the sum of their volumes. The N slices
//! are an allocation (`allocate`): on a structure of a few slices the slices
//! next to its ends first (`caps_first`), then each slice to the gap whose
//! expected error it lowers most, spread evenly in its gap.
use crate::area_profile::{fit_slices, parabola};
use crate::auto::field_of_pieces;
use crate::image::conditioned::Conditioned;
use crate::labels::{DrawnLabels, sorted_drawn};
use crate::loo::Compact;
use crate::predict::{LeaveOneOut, estimate, held_out_errors};
use crate::{InterpError, Interpolator, SparseMask, by_name_with_image};
use interslice_core::{Axis, LabelVolume, Mask};
use rayon::prelude::*;
use serde::Serialize;

/// One suggested slice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Suggestion {
    /// Slice index along the drawn axis.
    pub slice: usize,
    /// Wrong voxels tracing it is expected to correct.
    pub gain_voxels: f64,
    /// The expected rise of the result's Dice from tracing it.
    pub dice_gain: f64,
    /// The drawn (or already suggested) slices around it.
    pub between: [usize; 2],
}

/// What `advise` answers: the suggestions and the predicted quality now.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Advice {
    /// Axis of the slices.
    pub axis: Axis,
    /// Drawn slices the advice starts from.
    pub drawn: Vec<usize>,
    /// Best slice first: on a structure of a few slices the slices next to
    /// its ends come first by rule (`caps_first`), whatever their gain.
    pub suggestions: Vec<Suggestion>,
    /// Predicted Dice of the interpolation of the current tracing.
    pub predicted_dice: f64,
    /// Voxels of the traced structures (the drawn areas integrated).
    pub volume_voxels: f64,
}

/// A gap between two drawn slices: its rate (wrong voxels per slice) and
/// the bulge of the structure's cross-section on each of its slices.
#[derive(Debug, Clone)]
struct Gap {
    a: usize,
    b: usize,
    rate: f64,
    /// [`bulge_density`] on the slices `a..=b` (index `t − a`).
    bulge: Vec<f64>,
}

impl Gap {
    /// A gap without bulge: the rate alone.
    #[cfg(test)]
    fn flat(a: usize, b: usize, rate: f64) -> Gap {
        Gap {
            a,
            b,
            rate,
            bulge: vec![0.0; b - a + 1],
        }
    }

    /// Expected wrong voxels over the gap with `n` more slices evenly spaced
    /// in it (at the slices of [`Gap::spread`]): over the sub-gaps `[p, q]`,
    /// each skipped slice `t` counts `max(ρ / (q − p), κ(t)) (t − p)(q − t)`,
    /// `κ` the bulge. Without bulge that is `ρ (L² − 1) / 6` per sub-gap of
    /// `L` slices (a sub-gap of one slice has no undrawn slice, so no error).
    fn error_with(&self, n: usize) -> f64 {
        let mut cuts = self.spread(n);
        cuts.sort_unstable();
        let mut prev = self.a;
        let mut sum = 0.0;
        for c in cuts.into_iter().chain([self.b]) {
            let flat = self.rate / (c - prev) as f64;
            for t in prev + 1..c {
                let bridge = ((t - prev) * (c - t)) as f64;
                sum += flat.max(self.bulge[t - self.a]) * bridge;
            }
            prev = c;
        }
        sum
    }

    /// The slices of `n` evenly spaced in the gap, the one nearest its middle
    /// first (then outwards, lower first on ties).
    fn spread(&self, n: usize) -> Vec<usize> {
        let l = self.b - self.a;
        let mut s: Vec<usize> = (1..=n)
            .map(|j| self.a + (l * j + n.div_ceil(2)) / (n + 1))
            .filter(|&x| x > self.a && x < self.b)
            .collect();
        s.dedup();
        let mid2 = self.a + self.b;
        s.sort_by_key(|&x| ((2 * x).abs_diff(mid2), x));
        s
    }
}

/// A slice of the allocation: its index, its gain in the model (wrong
/// voxels) and the gap it splits.
type Pick = (usize, f64, [usize; 2]);

/// Where `count` more slices do the most good: on a short structure the
/// slices next to its ends come first ([`caps_first`]); then every gap gets the
/// slices it needs to leave no sub-gap wider than [`widest_allowed`], then
/// the rest go one at a time, each to the gap whose error it lowers most
/// (without bulge the error of a gap falls convexly with its slices, and
/// this allocation is optimal), and each gap's slices are spread evenly in it. With equal rates
/// and no bulge this is uniform
/// spacing; where the shape is harder to predict, the slices gather. Answers
/// the slices with their gain (the drop of the error they make in the
/// allocation) and their gap: the caps first, then the rest best first.
fn allocate(gaps: &[Gap], count: usize) -> Vec<Pick> {
    let widest = widest_allowed(gaps, count);
    let (mut caps, gaps) = if widest == 2 {
        caps_first(gaps, count)
    } else {
        (Vec::new(), gaps.to_vec())
    };
    let gaps = &gaps[..];
    let mut n = vec![0usize; gaps.len()];
    let mut gains: Vec<Vec<f64>> = vec![Vec::new(); gaps.len()];
    let mut left = count - caps.len();
    for (i, g) in gaps.iter().enumerate() {
        let need = (g.b - g.a).div_ceil(widest) - 1;
        for _ in 0..need.min(left) {
            gains[i].push(g.error_with(n[i]) - g.error_with(n[i] + 1));
            n[i] += 1;
            left -= 1;
        }
    }
    for _ in 0..left {
        let best = gaps
            .iter()
            .enumerate()
            .filter(|(i, g)| n[*i] + 1 < g.b - g.a)
            .map(|(i, g)| (i, g.error_with(n[i]) - g.error_with(n[i] + 1)))
            .max_by(|x, y| x.1.total_cmp(&y.1).then(y.0.cmp(&x.0)));
        let Some((i, gain)) = best else { break };
        n[i] += 1;
        gains[i].push(gain);
    }
    let mut out: Vec<Pick> = gaps
        .iter()
        .zip(&n)
        .zip(&gains)
        .flat_map(|((g, &k), gains)| {
            g.spread(k)
                .into_iter()
                .zip(gains.iter().copied())
                .map(move |(s, gain)| (s, gain, [g.a, g.b]))
        })
        .collect();
    out.sort_by(|x, y| y.1.total_cmp(&x.1).then(x.0.cmp(&y.0)));
    caps.extend(out);
    caps
}

/// The caps first: on a structure short enough that the slices to place
/// can leave no two undrawn slices side by side ([`widest_allowed`] is 2),
/// the slice next to each outermost drawn slice is traced before the rest
/// (first the lower end, then the upper; where that gap holds two or more
/// undrawn slices and slices are left to place). Answers those slices with
/// their gain in the model and their gap, and the gaps with the end gaps
/// cut at them.
///
/// Why: a round structure's cross-section changes fastest next to its ends,
/// and on a structure of a few slices the rates and the bulge rest on two
/// or three held-out slices and blunt end areas, too few to see it; the
/// model's choice there left the slice next to an end untraced and lost to
/// uniform spacing (stardist's nuclei of 3–11 slices: slices 2 and 8 of
/// nuclei on 1–7 and 8–15 left, Dice 0.05–0.13 below uniform spacing on
/// the nucleus). On `study --strategy` over the ten development sets
/// (`docs/interpolation.md`) it took stardist's nuclei from 0.0029–0.0042
/// behind uniform spacing at budgets 4–6 to 0.0012–0.0061 ahead, and brain1
/// at budget 4 from 0.19 behind to level; it changes nothing on structures
/// longer than about twice the budget.
fn caps_first(gaps: &[Gap], count: usize) -> (Vec<Pick>, Vec<Gap>) {
    let mut caps = Vec::new();
    let mut gaps = gaps.to_vec();
    let Some(last) = gaps.len().checked_sub(1) else {
        return (caps, gaps);
    };
    for (i, lower) in [(0, true), (last, false)] {
        let g = &gaps[i];
        if caps.len() >= count || g.b - g.a < 3 {
            continue;
        }
        let s = if lower { g.a + 1 } else { g.b - 1 };
        let (a, b) = if lower { (s, g.b) } else { (g.a, s) };
        let cut = Gap {
            a,
            b,
            rate: g.rate,
            bulge: g.bulge[a - g.a..=b - g.a].to_vec(),
        };
        caps.push((s, g.error_with(0) - cut.error_with(0), [g.a, g.b]));
        gaps[i] = cut;
    }
    (caps, gaps)
}

/// The widest gap (in slices) the allocation of `count` slices over `gaps`
/// may leave: 2 where `count` slices can leave every undrawn slice between
/// two drawn ones, else any. The error model decides where slices gather,
/// but on a structure of a few slices it rests on two or three held-out
/// slices, and two undrawn slices side by side cost far more than the
/// model's choice of which single slices to leave gains: with 9 slices and
/// 4 to place, the model alone traced three neighbours at one end and left
/// two untraced together at the other (stardist's nuclei). On
/// `study --strategy` over the ten development sets this took the advice on
/// stardist's nuclei at budget 4 from 0.0087 behind uniform spacing to
/// 0.0029 behind and changed nothing on longer structures. A quarter of
/// slack on every gap (never wider than the narrowest reachable plus a
/// quarter) did the same there, but took the gathering from longer
/// structures, where the model earns it (a gap three times as hard as its
/// twin gets three of four slices, not two).
fn widest_allowed(gaps: &[Gap], count: usize) -> usize {
    let needed: usize = gaps.iter().map(|g| (g.b - g.a).div_ceil(2) - 1).sum();
    if needed <= count { 2 } else { usize::MAX }
}

/// The per-gap rates, the bulge per slice ([`bulge_density`]), the volume
/// and the leave-one-out estimate ([`crate::predict::estimate`]) of one
/// label's tracing.
fn label_rates(
    mask: &Mask,
    axis: Axis,
    drawn: &[usize],
    method: &dyn Interpolator,
) -> Result<LabelModel, InterpError> {
    let slices: Vec<Vec<bool>> = drawn
        .iter()
        .map(|&d| mask.slice(axis, d).map_err(InterpError::from))
        .collect::<Result<_, _>>()?;
    let areas: Vec<f64> = slices
        .iter()
        .map(|s| s.iter().filter(|&&x| x).count() as f64)
        .collect();
    let volume: f64 = drawn
        .windows(2)
        .zip(areas.windows(2))
        .map(|(d, a)| (a[0] + a[1]) / 2.0 * (d[1] - d[0]) as f64)
        .sum::<f64>()
        .max(areas.iter().copied().fold(0.0, f64::max));
    // Rates of the held-out slices (index into `drawn`), and from the same
    // predictions the level of the error (`crate::predict`).
    let mut held_rate = vec![None; drawn.len()];
    let mut errors = Vec::new();
    if drawn.len() >= 3 {
        let input = SparseMask::new(mask, axis, drawn);
        let compact = Compact::of(&input)?;
        for (pos, e) in held_out_errors(&compact, method, &input)? {
            let span = compact.reach(pos) as f64 * 2.0;
            held_rate[pos] = Some(4.0 * e.wrong / span.max(1.0));
            errors.push(e);
        }
    }
    let mut rates = (0..drawn.len() - 1)
        .map(|g| {
            let l = (drawn[g + 1] - drawn[g]) as f64;
            let change = slices[g]
                .iter()
                .zip(&slices[g + 1])
                .filter(|(x, y)| x != y)
                .count() as f64;
            let ends: Vec<f64> = [held_rate[g], held_rate[g + 1]]
                .into_iter()
                .flatten()
                .collect();
            let loo = if ends.is_empty() {
                0.0
            } else {
                ends.iter().sum::<f64>() / ends.len() as f64
            };
            loo.max(change / (4.0 * l))
        })
        .collect::<Vec<f64>>();
    let mut bulge = bulge_density(drawn, &areas);
    let (u, v) = axis.in_plane();
    let dims = mask.geometry().dims;
    if field_of_pieces(&slices, dims[u], dims[v]) {
        // Held-out slices of a field of pieces say little about which gap
        // is harder (see `field_of_pieces`): every gap gets the mean rate
        // and no bulge, and the slices spread as evenly as they can.
        let mean = rates.iter().sum::<f64>() / rates.len().max(1) as f64;
        rates.iter_mut().for_each(|r| *r = mean);
        bulge.iter_mut().for_each(|k| *k = 0.0);
    }
    Ok(LabelModel {
        rates,
        bulge,
        volume,
        loo: estimate(&errors),
    })
}

/// What [`label_rates`] learns of one label.
struct LabelModel {
    rates: Vec<f64>,
    bulge: Vec<f64>,
    volume: f64,
    loo: Option<LeaveOneOut>,
}

/// The bulge of a structure's cross-section on every slice from the first
/// drawn slice to the last (index `t − drawn[0]`): the wrong voxels per
/// slice² its shape alone predicts there.
///
/// A leave-one-out rate is one number per gap, measured between drawn
/// slices; but a round structure changes fastest towards its ends, where an
/// end gap has a held-out slice on one side only. Seen as a disc of radius
/// `r` whose area `A = πr²` the interpolation carries along its chord, the
/// wrong area on a skipped slice `t` of a gap `[a, b]` is the perimeter
/// times the radius's departure from the chord, `2πr · |r''| (t − a)(b −
/// t) / 2`, and `π r r'' = A''/2 − A'²/(4A)`: zero for a cone (`A ∝ z²`) or
/// a cylinder, growing without bound towards a pole (`A ∝ R² − z²`). `A` is
/// the parabola through the areas of the gap's two slices and the drawn
/// slice beyond the end nearer `t` (the other one when that shows nothing).
/// Gaps with a drawn slice that does not show the structure (it ends inside
/// the gap, a cone to a point) have none.
fn bulge_density(drawn: &[usize], areas: &[f64]) -> Vec<f64> {
    let (first, last) = (drawn[0], drawn[drawn.len() - 1]);
    let mut out = vec![0.0; last - first + 1];
    let n = drawn.len();
    let shows = |i: usize| areas[i] > 0.0;
    for g in 0..n - 1 {
        if !shows(g) || !shows(g + 1) {
            continue;
        }
        let (a, b) = (drawn[g], drawn[g + 1]);
        let floor = areas[g].min(areas[g + 1]) / 2.0;
        for t in a + 1..b {
            let Some(fit) = fit_slices(g, n, t - a <= b - t, shows) else {
                continue;
            };
            let (area, slope, curve) = parabola(
                fit.map(|i| drawn[i] as f64),
                fit.map(|i| areas[i]),
                t as f64,
            );
            out[t - first] = (curve / 2.0 - slope * slope / (4.0 * area.max(floor))).abs();
        }
    }
    out
}

/// Rank the undrawn slices of `sparse` between its outermost drawn slices:
/// the `count` best to trace next, best first (see the module docs for the
/// model). `method` (a registry name, default as for interpolation; the
/// image-aware one with `image`) is the one that will fill the gaps: its
/// leave-one-out errors calibrate the model. Errors with fewer than two
/// drawn slices or an image on another grid.
pub fn advise(
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
    count: usize,
    method: Option<&str>,
    image: Option<Conditioned>,
) -> Result<Advice, InterpError> {
    let drawn = sorted_drawn(sparse, axis, drawn)?;
    if let Some(img) = &image {
        img.geometry().ensure_same_grid(sparse.geometry())?;
    }
    // The leave-one-out runs on the stack of the drawn slices, so an image
    // goes with them stacked the same way (`Interpolator::for_stack`).
    let whole = by_name_with_image(method, image)?;
    let stacked = whole.for_stack(axis, &drawn)?;
    let method = stacked.as_deref().unwrap_or(whole.as_ref());
    if drawn.len() < 2 {
        return Err(InterpError::Input(format!(
            "advice needs at least two drawn slices along {axis}, got {}: trace the first \
             and the last slice the structure shows on, then ask again",
            drawn.len()
        )));
    }
    let traced = DrawnLabels::read(sparse, axis, &drawn);
    let per_label: Vec<LabelModel> = traced
        .labels()
        .par_iter()
        .map(|&l| label_rates(&traced.traced_mask(l), axis, &drawn, method))
        .collect::<Result<_, _>>()?;
    let volume: f64 = per_label.iter().map(|m| m.volume).sum();
    let first = drawn[0];
    let gaps: Vec<Gap> = drawn
        .windows(2)
        .enumerate()
        .map(|(g, w)| Gap {
            a: w[0],
            b: w[1],
            rate: per_label.iter().map(|m| m.rates[g]).sum(),
            bulge: (w[0]..=w[1])
                .map(|t| per_label.iter().map(|m| m.bulge[t - first]).sum())
                .collect(),
        })
        .collect();
    let scale = if volume > 0.0 {
        1.0 / (2.0 * volume)
    } else {
        0.0
    };
    let error: f64 = gaps.iter().map(|g| g.error_with(0)).sum();
    let model_loss = error * scale;
    // The leave-one-out level, pooled over the labels (all or none have one:
    // they share the drawn slices).
    let levels: Vec<(f64, f64)> = per_label
        .iter()
        .filter_map(|m| m.loo.map(|l| l.pooled))
        .collect();
    let (predicted_dice, level) = if levels.len() == per_label.len() && !levels.is_empty() {
        let (wrong, areas) = levels
            .iter()
            .fold((0.0, 0.0), |(w, a), &(x, y)| (w + x, a + y));
        let loss = if areas > 0.0 { wrong / areas } else { 0.0 };
        let level = if model_loss > 0.0 {
            loss / model_loss
        } else {
            1.0
        };
        ((1.0 - loss).clamp(0.0, 1.0), level)
    } else {
        ((1.0 - model_loss).clamp(0.0, 1.0), 1.0)
    };
    let suggestions = allocate(&gaps, count)
        .into_iter()
        .map(|(slice, gain, g)| Suggestion {
            slice,
            gain_voxels: gain * level,
            dice_gain: gain * level * scale,
            between: g,
        })
        .collect();
    Ok(Advice {
        axis,
        drawn,
        suggestions,
        predicted_dice,
        volume_voxels: volume,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{Geometry, LengthUnit, Volume};

    /// The advice reports the leave-one-out predicted Dice of
    /// [`crate::predict`] (the one the tracing summary shows), and on slices
    /// drawn unevenly, as a tracer following the advice draws them, it is
    /// close to the true Dice.
    #[test]
    fn the_predicted_dice_is_the_leave_one_out_one_and_near_the_truth() {
        use interslice_core::phantom::{PhantomParams, generate};
        let p = generate(&PhantomParams {
            size: 64,
            seed: 1,
            bits: 8,
            noise: 0.0,
        })
        .unwrap();
        // The nucleus with its nucleoli.
        let nucleus: LabelVolume = p.labels.map(|v| u16::from(v >= 2));
        let truth = nucleus.map(|v| v > 0);
        let nonempty = crate::drawn::nonempty_slices(&nucleus, Axis::Z);
        let (first, last) = (nonempty[0], *nonempty.last().unwrap());
        let n = last - first;
        let drawn = vec![first, first + n / 7, first + n / 2, first + 4 * n / 5, last];
        let sparse = crate::protocol::sparse_of(&nucleus, Axis::Z, &drawn);
        let a = advise(&sparse, Axis::Z, &drawn, 1, None, None).unwrap();
        let method = crate::by_name(crate::DEFAULT_METHOD).unwrap();
        let m = sparse.map(|v| v > 0);
        let loo = crate::predict::predicted_dice(
            &m,
            Axis::Z,
            &drawn,
            method.as_ref(),
            &interslice_core::Cancel::new(),
        )
        .unwrap()
        .unwrap();
        assert_eq!(a.predicted_dice, loo.predicted_dice);
        let out = method
            .interpolate(SparseMask::new(&m, Axis::Z, &drawn))
            .unwrap();
        let true_dice = interslice_core::metrics::overlap_masks(&truth, &out)
            .unwrap()
            .dice()
            .unwrap();
        eprintln!("true {true_dice:.4}, predicted {:.4}", a.predicted_dice);
        assert!(
            (a.predicted_dice - true_dice).abs() <= 0.03,
            "true {true_dice:.4}, predicted {:.4}",
            a.predicted_dice
        );
    }

    /// The bulge is nothing on a cone or a cylinder (their areas, `πk²z²`
    /// and constant, are carried exactly by a chord of the radius) and, on
    /// a ball, `π r |r''| = π R² / r²`: least at the equator, rising towards
    /// the poles.
    #[test]
    fn the_bulge_is_nothing_on_a_cone_and_grows_towards_a_balls_poles() {
        use std::f64::consts::PI;
        let drawn = [2usize, 6, 10, 14, 18];
        let cone: Vec<f64> = drawn
            .iter()
            .map(|&z| PI * (0.5 * z as f64).powi(2))
            .collect();
        assert!(bulge_density(&drawn, &cone).iter().all(|&k| k < 1e-9));
        let cylinder = vec![300.0; drawn.len()];
        assert!(bulge_density(&drawn, &cylinder).iter().all(|&k| k == 0.0));
        // A ball of radius 9 about z = 10 (areas of its exact sections).
        let r2 = |z: f64| 81.0 - (z - 10.0) * (z - 10.0);
        let ball: Vec<f64> = drawn.iter().map(|&z| PI * r2(z as f64)).collect();
        let k = bulge_density(&drawn, &ball);
        for t in [3usize, 5, 8, 12, 15, 17] {
            let want = PI * 81.0 / r2(t as f64);
            let got = k[t - drawn[0]];
            assert!(
                (got - want).abs() < 1e-9 * want,
                "slice {t}: {got} against {want}"
            );
        }
        assert!(k[3 - 2] > k[5 - 2] && k[5 - 2] > k[8 - 2]);
        // A drawn slice without the structure: the gaps beside it have none.
        let mut cut = ball.clone();
        cut[4] = 0.0;
        let k = bulge_density(&drawn, &cut);
        assert!(k[15 - 2..].iter().all(|&x| x == 0.0));
    }

    /// Equal rates spread the slices evenly, like uniform spacing; a gap
    /// with a higher rate gets more of them; the error falls convexly.
    #[test]
    fn slices_go_where_the_error_drops_most_and_spread_in_their_gap() {
        let g = Gap::flat(10, 40, 3.0);
        let drops: Vec<f64> = (0..5)
            .map(|n| g.error_with(n) - g.error_with(n + 1))
            .collect();
        assert!(drops.windows(2).all(|w| w[0] > w[1]), "{drops:?}");
        // One gap, three slices: its quarter points, the middle first.
        let s: Vec<usize> = allocate(&[g], 3).iter().map(|x| x.0).collect();
        assert_eq!(s, [25, 18, 33]);
        // A gap three times as hard gets more slices than its equal twin.
        let easy = Gap::flat(0, 20, 1.0);
        let hard = Gap::flat(20, 40, 3.0);
        let a = allocate(&[easy, hard], 4);
        let in_hard = a.iter().filter(|x| x.0 > 20).count();
        assert!(in_hard >= 3, "{a:?}");
        assert!(a.windows(2).all(|w| w[0].1 >= w[1].1));
        // No more slices than the gaps hold.
        let tiny = Gap::flat(3, 5, 1.0);
        assert_eq!(
            allocate(&[tiny], 5).iter().map(|x| x.0).collect::<Vec<_>>(),
            [4]
        );
    }

    /// A cone along z (radius grows linearly, then a ball-like cap): a shape
    /// whose cross-section changes fast near its tip.
    fn traced(drawn: &[usize]) -> (LabelVolume, LabelVolume) {
        let g = Geometry::new([48, 48, 40], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut full: LabelVolume = Volume::zeros(g);
        for z in 0..40usize {
            let r = if z < 30 {
                2.0 + 0.6 * z as f64
            } else {
                20.0 * (1.0 - ((z - 29) as f64 / 11.0).powi(2)).max(0.0).sqrt()
            };
            for y in 0..48usize {
                for x in 0..48usize {
                    let (dx, dy) = (x as f64 - 23.5, y as f64 - 23.5);
                    if dx * dx + dy * dy <= r * r {
                        full.set(x, y, z, 1);
                    }
                }
            }
        }
        let sparse = crate::protocol::sparse_of(&full, Axis::Z, drawn);
        (full, sparse)
    }

    #[test]
    fn no_two_undrawn_slices_are_left_together_where_spacing_avoids_it() {
        // All the error is in the first gap (3 slices), none in the second
        // (5): the model alone puts two of three slices in the first.
        let gaps = [Gap::flat(0, 3, 100.0), Gap::flat(3, 8, 0.0)];
        let mut cuts: Vec<usize> = allocate(&gaps, 3).iter().map(|s| s.0).collect();
        cuts.extend([0, 3, 8]);
        cuts.sort_unstable();
        assert!(cuts.windows(2).all(|w| w[1] - w[0] <= 2), "{cuts:?}");
        // With too few slices to do that, the model decides alone.
        assert_eq!(widest_allowed(&gaps, 2), usize::MAX);
        let hard_first = allocate(&gaps, 2).iter().filter(|s| s.0 < 3).count();
        assert_eq!(hard_first, 2);
    }

    #[test]
    fn on_a_short_structure_the_slices_next_to_its_ends_come_first() {
        // Nine slices, four to place: enough to leave no two undrawn slices
        // together, so the caps go first, lower end first, then the rest
        // spread in what is left.
        let gaps = [Gap::flat(0, 8, 10.0)];
        let plan: Vec<usize> = allocate(&gaps, 4).iter().map(|s| s.0).collect();
        assert_eq!(plan[..2], [1, 7], "{plan:?}");
        let mut cuts = plan.clone();
        cuts.extend([0, 8]);
        cuts.sort_unstable();
        cuts.dedup();
        assert_eq!(cuts.len(), 6, "{plan:?}");
        assert!(cuts.windows(2).all(|w| w[1] - w[0] <= 2), "{cuts:?}");
        // One or two slices cannot leave every undrawn slice alone: the
        // model decides, the middle of the gap first.
        assert_eq!(allocate(&gaps, 1)[0].0, 4);
        let two: Vec<usize> = allocate(&gaps, 2).iter().map(|s| s.0).collect();
        assert!(!two.contains(&1) && !two.contains(&7), "{two:?}");
    }

    /// On a field of pieces (here 16 tubes per slice, ending at different
    /// depths) every gap gets the same rate and no bulge: the held-out
    /// slices say little about which gap is harder. One object keeps its
    /// own rates.
    #[test]
    fn a_field_of_pieces_gets_one_rate_for_every_gap() {
        let g = Geometry::new([64, 64, 40], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut field: Mask = Volume::zeros(g.clone());
        let mut ball: Mask = Volume::zeros(g);
        for z in 0..40usize {
            for y in 0..64usize {
                for x in 0..64usize {
                    let (i, j) = (x / 16, y / 16);
                    let (dx, dy) = ((x % 16) as f64 - 8.0, (y % 16) as f64 - 8.0);
                    let ends = 4 + 2 * (i + 4 * j) % 32;
                    field.set(
                        x,
                        y,
                        z,
                        z >= ends.min(20) && z < 36 && dx * dx + dy * dy <= 9.0,
                    );
                    let (bx, by, bz) = (x as f64 - 32.0, y as f64 - 32.0, z as f64 - 20.0);
                    ball.set(x, y, z, bx * bx + by * by + bz * bz <= 17.0f64.powi(2));
                }
            }
        }
        let method = crate::by_name(crate::DEFAULT_METHOD).unwrap();
        let drawn: Vec<usize> = (4..=36).step_by(4).collect();
        let f = label_rates(&field, Axis::Z, &drawn, method.as_ref()).unwrap();
        assert!(
            f.rates.iter().all(|&r| r == f.rates[0] && r > 0.0),
            "{:?}",
            f.rates
        );
        assert!(f.bulge.iter().all(|&k| k == 0.0));
        let drawn: Vec<usize> = (3..=37).step_by(4).collect();
        let b = label_rates(&ball, Axis::Z, &drawn, method.as_ref()).unwrap();
        assert!(b.rates.iter().any(|&r| r != b.rates[0]), "{:?}", b.rates);
    }

    #[test]
    fn suggestions_are_undrawn_distinct_inside_and_best_first() {
        let drawn = [0, 10, 20, 30, 39];
        let (_, sparse) = traced(&drawn);
        let a = advise(&sparse, Axis::Z, &drawn, 8, None, None).unwrap();
        assert_eq!(a.suggestions.len(), 8);
        let mut seen = std::collections::BTreeSet::new();
        for s in &a.suggestions {
            assert!(!drawn.contains(&s.slice) && s.slice > 0 && s.slice < 39);
            assert!(seen.insert(s.slice), "slice {} twice", s.slice);
            assert!(s.between[0] < s.slice && s.slice < s.between[1]);
        }
        // Greedy gains never rise: each gap's best gain is at most its parent's.
        assert!(
            a.suggestions
                .windows(2)
                .all(|w| w[1].gain_voxels <= w[0].gain_voxels + 1e-9)
        );
        assert!(
            a.predicted_dice > 0.5 && a.predicted_dice < 1.0,
            "{}",
            a.predicted_dice
        );
    }

    #[test]
    fn the_first_suggestion_goes_where_the_shape_changes_fastest() {
        // The cap (30..39) shrinks from radius 20 to 0; the cone changes slowly.
        let drawn = [0, 10, 20, 30, 39];
        let (_, sparse) = traced(&drawn);
        let a = advise(&sparse, Axis::Z, &drawn, 1, None, None).unwrap();
        assert_eq!(a.suggestions[0].between, [30, 39], "{:?}", a.suggestions);
    }

    /// A rod that runs straight, then bends ever faster: the shape methods
    /// follow the straight part exactly across any gap and misplace the
    /// bend between drawn slices, so slices belong in the bend. (On a
    /// round cap the choice of `shape-auto` among its candidates moves with
    /// the layout: `shape-area` follows the cap's area from three drawn
    /// slices, and evenly spaced slices, which bisection cannot reach, win.)
    #[test]
    fn advised_slices_beat_the_same_number_of_uniform_ones() {
        let g = Geometry::new([80, 32, 40], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut full: LabelVolume = Volume::zeros(g);
        for z in 0..40usize {
            let cx = 20.0 + 0.1 * (z as f64 - 20.0).max(0.0).powi(2);
            for y in 0..32usize {
                for x in 0..80usize {
                    let (dx, dy) = (x as f64 - cx, y as f64 - 15.5);
                    if dx * dx + dy * dy <= 64.0 {
                        full.set(x, y, z, 1);
                    }
                }
            }
        }
        let method = crate::by_name(crate::DEFAULT_METHOD).unwrap();
        let truth = full.map(|v| v == 1);
        let dice_of = |drawn: &[usize]| {
            let sparse = crate::protocol::sparse_of(&full, Axis::Z, drawn);
            let out = crate::interpolate_labels(method.as_ref(), &sparse, Axis::Z, drawn).unwrap();
            let skipped: Vec<usize> = (0..40).filter(|s| !drawn.contains(s)).collect();
            crate::protocol::dice_on(&out.map(|v| v == 1), &truth, Axis::Z, &skipped)
        };
        // The advice is re-asked after each traced slice, as a tracer would.
        let mut advised = vec![0usize, 39];
        for _ in 0..4 {
            let sparse_now = crate::protocol::sparse_of(&full, Axis::Z, &advised);
            let a = advise(&sparse_now, Axis::Z, &advised, 1, None, None).unwrap();
            advised.push(a.suggestions[0].slice);
            advised.sort_unstable();
        }
        let uniform = [0, 8, 16, 24, 32, 39];
        assert_eq!(advised.len(), uniform.len());
        let (da, du) = (dice_of(&advised), dice_of(&uniform));
        eprintln!("advised {advised:?}: {da:.4}, uniform: {du:.4}");
        assert!(da > du, "advised {advised:?}: {da:.4}, uniform: {du:.4}");
    }

    #[test]
    fn with_an_image_the_advice_comes_from_the_image_aware_method() {
        let drawn = [0, 10, 20, 30, 39];
        let (full, sparse) = traced(&drawn);
        let image = Conditioned::from(full.map(|v| if v == 1 { 180.0f32 } else { 30.0 }));
        let a = advise(&sparse, Axis::Z, &drawn, 3, None, Some(image)).unwrap();
        assert_eq!(a.suggestions.len(), 3);
        assert!(a.predicted_dice > 0.5 && a.predicted_dice <= 1.0);
        // An image on another grid is refused.
        let g =
            interslice_core::Geometry::new([8, 8, 8], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let small = Conditioned::from(Volume::filled(g, 1.0f32));
        assert!(advise(&sparse, Axis::Z, &drawn, 3, None, Some(small)).is_err());
    }

    #[test]
    fn fewer_than_two_drawn_slices_is_an_error_that_says_what_to_do() {
        let (_, sparse) = traced(&[5]);
        let e = advise(&sparse, Axis::Z, &[5], 3, None, None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("at least two drawn slices") && e.contains("trace"),
            "{e}"
        );
    }
}
