//! Gaps across which a traced outline jumps, and how they are filled.
//!
//! Two consecutive drawn outlines that share next to nothing are not one
//! outline moving a little from slice to slice: a blend of their distance
//! maps shrinks both towards nothing in the middle of the gap and puts what
//! is left between them, where neither was traced. Between such slices each
//! outline **fades in place**: on a skipped slice a fraction `t` of the way
//! from A to B, the deepest `(1 − w(t))` of A's area and the deepest `w(t)`
//! of B's (by their signed distance maps), together, `w` the [`Fade`]'s
//! weight: eased towards the nearer drawn outline for the shape alone,
//! on the straight line for the prior an image reads. The union's area follows the
//! line between the two drawn areas, and each piece stays where it was
//! traced — the answer of ITK's morphological contour interpolation to
//! regions without a partner on the other slice (an unmatched region is
//! interpolated with an empty one; Zukić et al. 2016), which beat copying
//! the nearer slice on the development data's jumping outline (brain1 of
//! `interslice bench`, below).
use crate::auto::field_of_pieces;
use crate::slices::{Plane, centroid};
use crate::{InterpError, SparseMask};
use interslice_core::morph::Connectivity;
use interslice_core::regions::label_2d;

/// Two consecutive drawn outlines that share less than this share of the
/// smaller one have jumped: each fades in place across the gap between
/// them ([`jumping_gaps`], [`fade`]).
pub const APART: f64 = 0.4;

/// Share of the larger outline's area the smaller must hold for two drawn
/// outlines apart to count as one outline that jumped ([`jumping_gaps`]).
pub const ALIKE: f64 = 0.25;

/// The gaps (index `i`: between drawn slices `i` and `i + 1`) across which
/// the outline jumps: both drawn slices show the structure and share less
/// than [`APART`] of the smaller outline (`|A ∩ B| / min(|A|, |B|)`), and
/// the smaller holds at least [`ALIKE`] of the larger's area (a tapering
/// tip is no jump). An outline that grows or shrinks keeps the smaller one
/// inside the larger (a cone: share 1, blended) however different their
/// areas. A drawn-empty slice is no jump: the structure ends there, and
/// `shape-aligned` caps it. Nor is an outline that moves little per slice
/// and far across a wide gap (`slow_drift`, [`SLOW_STEP`]), or one that drifts steadily
/// ([`drifting_gaps`]).
///
/// Decided from the tracing alone, whatever the leave-one-out chose: with
/// two drawn slices there is nothing to hold out, and with more the
/// held-out slices, twice the gap apart, jump for every method. Set on the
/// development data's tracings of two slices (the thick-slice CT and MR
/// lesions of `interslice bench` at large skips): leaving the blend was
/// better at shares of 0.00 and 0.18 (brain1, lung2), the blend at 0.81
/// and 0.88 (breast1, lung1). Applied per gap wherever more slices are
/// drawn it changes only brain1 (6.5 mm slices, the outline jumping by up
/// to 20 pixels), at k = 1–4 on the skipped slices: blended 0.5233 /
/// 0.3697 / 0.3581 / 0.3023, the nearer slice copied 0.5649 / 0.4726 /
/// 0.4141 / 0.4550, faded in place ([`fade`], on the straight line)
/// 0.6342 / 0.5059 / 0.4563 / 0.4675, eased ([`Fade::Eased`]) 0.6342 /
/// 0.5176 / 0.4590 / 0.4799 (ITK's morphological contour interpolation:
/// 0.6341 / 0.5277 / 0.4793 / 0.4775). With two drawn slices (k ≥ 5)
/// the eased fade gives 0.4364, the copy 0.4358.
///
/// Not on a field of pieces ([`field_of_pieces`]): there the whole slice's
/// share says nothing about pieces that do not correspond anyway, and
/// copying lost on the T1 k-means classes (class 2 −0.004 to −0.011 at
/// k = 1–7, class 3 −0.018 at k = 2 and 3, class 4 −0.016 at k = 1).
pub fn jumping_gaps(input: &SparseMask<'_>) -> Result<Vec<usize>, InterpError> {
    Ok(apart_gaps(input)?
        .into_iter()
        .filter_map(|(i, drift)| (!drift).then_some(i))
        .collect())
}

/// The gaps across which an outline drifts steadily: consecutive drawn
/// outlines apart as in [`jumping_gaps`], the outline's centroid moving
/// per slice as it does across a neighbouring gap (within
/// [`DRIFT_TOLERANCE`]): a tube tilted against the slices, which
/// `shape-aligned` follows, not a jump.
///
/// Why: a tube drifting by its radius or more between drawn slices shares
/// next to nothing from one drawn outline to the next, yet it is one
/// outline moving; faded in place it broke in the middle of every gap. On
/// tubes of radius 4–5 tilted by 1–2 pixels a slice, ending between drawn
/// slices drawn every 3rd or 4th slice, the default went from 0.78 / 0.76
/// / 0.76 to 0.91 / 0.86 / 0.91 on the skipped slices (`shape-aligned`
/// alone the same; `shape-auto` keeps its leave-one-out there rather than
/// `shape-area`'s rule, `auto::FEW_HELD_OUT`); no mask of `interslice
/// bench` has such a drift and none changed.
pub fn drifting_gaps(input: &SparseMask<'_>) -> Result<Vec<usize>, InterpError> {
    Ok(apart_gaps(input)?
        .into_iter()
        .filter_map(|(i, drift)| drift.then_some(i))
        .collect())
}

/// The gaps between consecutive drawn slices of `input` whose outlines
/// share less than [`APART`] of the smaller, the smaller holding at least
/// [`ALIKE`] of the larger's area (none on a field of pieces), and that do
/// not drift slowly ([`slow_drift`]), each with
/// whether the outline drifts steadily across it ([`steady_drift`]).
fn apart_gaps(input: &SparseMask<'_>) -> Result<Vec<(usize, bool)>, InterpError> {
    let slices: Vec<Vec<bool>> = input
        .drawn
        .iter()
        .map(|&d| input.mask.slice(input.axis, d))
        .collect::<Result<_, _>>()?;
    let (width, height) = input.mask.slice_shape(input.axis);
    if field_of_pieces(&slices, width, height) {
        return Ok(Vec::new());
    }
    let apart: Vec<usize> = slices
        .windows(2)
        .enumerate()
        .filter(|(_, pair)| {
            let (shared, smaller, larger) = overlap_counts(&pair[0], &pair[1]);
            smaller > 0
                && (shared as f64) < APART * smaller as f64
                && smaller as f64 >= ALIKE * larger as f64
        })
        .map(|(i, _)| i)
        .collect();
    if apart.is_empty() {
        // The usual case on every label the default fills: no centroids.
        return Ok(Vec::new());
    }
    let steps = drift_steps(&slices, input.drawn, width, height);
    let plane = Plane::of(input);
    Ok(apart
        .into_iter()
        .filter(|&i| !slow_drift(&slices[i], &slices[i + 1], steps[i], &plane))
        .map(|i| (i, steady_drift(&steps, i)))
        .collect())
}

/// Whether an outline of at most [`SLOW_PIECES`] pieces on both drawn
/// slices `a` and `b` moves, per slice, less than [`SLOW_STEP`] of its
/// equivalent radius (the mean of the two, physical units): it went far
/// across a wide gap by moving a little on every slice, as the hand-traced
/// hippocampus, caudate and amygdala do along their curve, and a blend
/// follows it where a fade leaves it in two places.
fn slow_drift(a: &[bool], b: &[bool], step: Option<[f64; 2]>, plane: &Plane) -> bool {
    let Some(step) = step else { return false };
    let (width, height) = (plane.width, plane.height);
    let few = |m: &[bool]| label_2d(m, width, height, Connectivity::Full).1.len() <= SLOW_PIECES;
    let radius = |m: &[bool]| plane.equivalent_radius(m.iter().filter(|&&x| x).count() as f64);
    let moved = (step[0] * plane.spacing[0]).hypot(step[1] * plane.spacing[1]);
    few(a) && few(b) && moved < SLOW_STEP * 0.5 * (radius(a) + radius(b))
}

/// Pieces (8-connected) an outline may have on each of two drawn slices
/// for its centroid's step to say how far it moved (`slow_drift`): on
/// stardist's nuclei traced as one binary mask (8.8 pieces a slice) the
/// whole slice's centroid says nothing of any nucleus, and counting them
/// as drifting cost `shape-auto` 0.003 and `image-guided` 0.016 at k = 8;
/// the caudate shows as two pieces on some axial slices.
pub const SLOW_PIECES: usize = 2;

/// Share of an outline's equivalent radius below which its centroid's
/// step per slice makes it a slow drift, not a jump (`slow_drift`).
///
/// Set on `interslice bench`: the AAL family's hippocampus, caudate and
/// amygdala (1 mm slices) move 0.15–0.25 of their radius a slice along
/// their curve, the development data's jumping outline (brain1, 6.5 mm
/// slices) 0.5 or more. Faded in place, the hippocampi at k = 9 scored
/// 0.698 / 0.703 where `shape-area` alone scored 0.757 / 0.793. With this
/// bar, `shape-auto` over k = 1..9 went up by 0.47 in total (hippocampus
/// left / right at k = 9 0.6982 / 0.7027 → 0.7571 / 0.7928, caudate left
/// at k = 8 0.8680 → 0.8910, amygdala right at k = 9 0.7592 → 0.7824; one
/// loss over 0.004, hippocampus left at k = 5, −0.015) and no mask outside
/// the AAL family moved. Bars from 0.3 to 0.5 gave the same within
/// 0.004; 0.2 lost 0.08 of it, 0.15 half of it.
pub const SLOW_STEP: f64 = 0.3;

/// Whether the outline's centroid moves across gap `i` per slice as it
/// does across a neighbouring gap (`steps`: [`drift_steps`]), within
/// [`DRIFT_TOLERANCE`] of its step.
fn steady_drift(steps: &[Option<[f64; 2]>], i: usize) -> bool {
    let Some(s) = steps[i] else { return false };
    let near =
        |j: usize| {
            steps.get(j).copied().flatten().is_some_and(|t| {
                (s[0] - t[0]).hypot(s[1] - t[1]) <= DRIFT_TOLERANCE * s[0].hypot(s[1])
            })
        };
    (i > 0 && near(i - 1)) || near(i + 1)
}

/// How far an outline that drifts may stray from its neighbouring gap's
/// step, as a share of its own step, and still be one drift.
pub const DRIFT_TOLERANCE: f64 = 0.5;

/// Per gap between consecutive drawn `slices` (at `drawn`), the step of
/// the outline's centroid per slice (pixels, in-plane), where both show it.
fn drift_steps(
    slices: &[Vec<bool>],
    drawn: &[usize],
    width: usize,
    height: usize,
) -> Vec<Option<[f64; 2]>> {
    let whole = [0, width - 1, 0, height - 1];
    let c: Vec<Option<[f64; 2]>> = slices.iter().map(|s| centroid(s, width, whole)).collect();
    (0..slices.len().saturating_sub(1))
        .map(|i| {
            let (a, b) = (c[i]?, c[i + 1]?);
            let g = (drawn[i + 1] - drawn[i]) as f64;
            Some([(b[0] - a[0]) / g, (b[1] - a[1]) / g])
        })
        .collect()
}

/// How the share of each outline that a skipped slice keeps follows its
/// place `t` in the gap ([`fade`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fade {
    /// The far outline's share eased in, `w(t) = t²(3 − 2t)` (smoothstep):
    /// level with the straight line in the middle of the gap, nearer the
    /// copy of the nearer drawn outline next to it. `shape-auto`'s result,
    /// where the shape alone must say where the structure is: on a skipped
    /// slice next to a drawn one the structure is more often still there
    /// than moved on. On the development data's jumping outline (brain1 of
    /// `interslice bench`, skipped slices) the straight line gave 0.6342 /
    /// 0.5059 / 0.4563 / 0.4675 at k = 1–4 and 0.4323 at k ≥ 5,
    /// eased 0.6342 / 0.5176 / 0.4590 / 0.4799 / 0.4364 (`nearest`, the
    /// copy everywhere: 0.6348 / 0.4726 / 0.4373 / 0.4550 / 0.4358); a
    /// steeper easing
    /// (`t³ / (t³ + (1 − t)³)`) 0.6342 / 0.5052 / 0.4702 / 0.4707 / 0.4466.
    /// No other mask of the benchmark moved by more than 0.0001.
    Eased,
    /// `w(t) = t`: the union's area on the line between the two drawn
    /// areas, and both outlines' cores on every skipped slice, so an image
    /// can pick where the structure is. `image-guided`'s prior where the
    /// image is read (its walk or fusion): eased there, brain1 at k = 4
    /// lost 0.017 (0.6133 → 0.5961, below the walker anchor's 0.6138) and
    /// at k ≥ 5 0.005.
    Linear,
}

impl Fade {
    /// The far outline's share on a skipped slice a fraction `t` of the way.
    fn weight(self, t: f64) -> f64 {
        match self {
            Fade::Eased => t * t * (3.0 - 2.0 * t),
            Fade::Linear => t,
        }
    }
}

/// The `gap − 1` skipped slices between two drawn outlines `gap` slices
/// apart, given as their signed distance maps `from` and `to` (the maps the
/// shape methods already hold, [`crate::sdf::SdfCache`]), each outline
/// fading in place: slice `s` holds the deepest `1 − w` of `from` and the
/// deepest `w` of `to`, `w` the `profile`'s weight at `s / gap`.
pub fn fade(from: &[f32], to: &[f32], gap: usize, profile: Fade) -> Vec<Vec<bool>> {
    let (depths_from, depths_to) = (inside_depths(from), inside_depths(to));
    (1..gap)
        .map(|s| {
            let t = profile.weight(s as f64 / gap as f64);
            let mut slice = deepest(from, &depths_from, 1.0 - t);
            for (o, x) in slice.iter_mut().zip(deepest(to, &depths_to, t)) {
                *o |= x;
            }
            slice
        })
        .collect()
}

/// The values of the signed distance map `d` inside its outline, deepest
/// (most negative) first: sorted once for every share [`deepest`] cuts.
fn inside_depths(d: &[f32]) -> Vec<f32> {
    let mut inside: Vec<f32> = d.iter().copied().filter(|&v| v < 0.0).collect();
    inside.sort_unstable_by(f32::total_cmp);
    inside
}

/// The deepest `share` of the outline whose signed distance map is `d`
/// (`depths`: its [`inside_depths`]): the level set of `d` at the share's
/// cut, so the pixels at that distance (a ring of a disc) are all kept and
/// the area is the share or a ring more.
/// Cutting at the level whose area is nearest the share instead lost on the
/// development data's jumping outline (brain1 of `interslice bench` at
/// k = 1–4: 0.6280 / 0.4839 / 0.4531 / 0.4584 against 0.6342 / 0.5059 /
/// 0.4563 / 0.4675; at k ≥ 5 0.3953 against 0.4323).
fn deepest(d: &[f32], depths: &[f32], share: f64) -> Vec<bool> {
    let keep = (share * depths.len() as f64).round() as usize;
    if keep == 0 {
        return vec![false; d.len()];
    }
    let level = depths[keep - 1];
    d.iter().map(|&v| v < 0.0 && v <= level).collect()
}

/// Pixels two outlines share, and the areas of the smaller and the larger.
pub fn overlap_counts(a: &[bool], b: &[bool]) -> (usize, usize, usize) {
    let area = |m: &[bool]| m.iter().filter(|&&x| x).count();
    let shared = a.iter().zip(b).filter(|&(&x, &y)| x && y).count();
    let (x, y) = (area(a), area(b));
    (shared, x.min(y), x.max(y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sdf::signed_distance;
    use crate::slices::Plane;
    use interslice_core::{Axis, Geometry, LengthUnit, Mask, Volume};

    fn disc(cx: f64, r: f64) -> Vec<bool> {
        (0..32 * 64)
            .map(|i| {
                let (x, y) = ((i % 64) as f64 - cx, (i / 64) as f64 - 15.5);
                x * x + y * y <= r * r
            })
            .collect()
    }

    /// The 64 × 32 plane of [`disc`], unit pixels.
    fn plane() -> Plane {
        Plane {
            width: 64,
            height: 32,
            spacing: [1.0, 1.0],
            slice_spacing: 1.0,
        }
    }

    #[test]
    fn each_outline_fades_in_place_with_the_area_of_the_line_between() {
        let plane = plane();
        let (a, b) = (disc(14.0, 8.0), disc(46.0, 6.0));
        let area = |m: &[bool]| m.iter().filter(|&&x| x).count() as f64;
        let (da, db) = (signed_distance(&a, &plane), signed_distance(&b, &plane));
        let slices = fade(&da, &db, 4, Fade::Linear);
        assert_eq!(slices.len(), 3);
        for (s, slice) in slices.iter().enumerate() {
            let t = (s + 1) as f64 / 4.0;
            let on = |m: &[bool]| slice.iter().zip(m).filter(|&(&x, &y)| x && y).count() as f64;
            // Nothing outside the two outlines; each part at least its
            // share, and a level set of its distance map (every pixel of the
            // outline deeper than a kept one is kept).
            assert_eq!(on(&a) + on(&b), area(slice));
            assert!(on(&a) >= ((1.0 - t) * area(&a)).round(), "{s}");
            assert!(on(&b) >= (t * area(&b)).round(), "{s}");
            for d in [&da, &db] {
                let cut = (0..d.len())
                    .filter(|&i| slice[i] && d[i] < 0.0)
                    .map(|i| d[i])
                    .fold(f32::NEG_INFINITY, f32::max);
                assert!((0..d.len()).all(|i| slice[i] || d[i] > cut || d[i] >= 0.0));
            }
            // The deepest part: the centre pixel of each disc is kept.
            assert!(slice[15 * 64 + 14] && slice[15 * 64 + 46]);
        }
        // A shrinks from slice to slice and B grows.
        let part = |m: &[bool], of: &[bool]| m.iter().zip(of).filter(|&(&x, &y)| x && y).count();
        assert!(part(&slices[0], &a) > part(&slices[2], &a));
        assert!(part(&slices[0], &b) < part(&slices[2], &b));
    }

    #[test]
    fn the_eased_fade_keeps_the_nearer_outline_longer_and_meets_the_line_midway() {
        let plane = plane();
        let (a, b) = (disc(14.0, 8.0), disc(46.0, 8.0));
        let (da, db) = (signed_distance(&a, &plane), signed_distance(&b, &plane));
        let (eased, line) = (
            fade(&da, &db, 6, Fade::Eased),
            fade(&da, &db, 6, Fade::Linear),
        );
        let on = |m: &[bool], of: &[bool]| m.iter().zip(of).filter(|&(&x, &y)| x && y).count();
        // Next to A (t = 1/6: w = 0.074 against 0.167) less of B and at
        // least as much of A (its outer rings are coarse steps).
        assert!(on(&eased[0], &b) < on(&line[0], &b));
        assert!(on(&eased[0], &a) >= on(&line[0], &a));
        // Next to B the mirror image.
        assert!(on(&eased[4], &a) < on(&line[4], &a));
        assert!(on(&eased[4], &b) >= on(&line[4], &b));
        // Midway the same slice.
        assert_eq!(eased[2], line[2]);
        // Symmetric: equal discs give equal shares at t and 1 − t.
        for s in 0..5 {
            assert_eq!(on(&eased[s], &a), on(&eased[4 - s], &b), "slice {s}");
        }
    }

    #[test]
    fn overlap_counts_are_shared_smaller_and_larger() {
        let (a, b) = (disc(20.0, 6.0), disc(23.0, 4.0));
        let (shared, smaller, larger) = overlap_counts(&a, &b);
        assert!(shared > 0 && shared <= smaller && smaller < larger);
        assert_eq!(overlap_counts(&b, &a), (shared, smaller, larger));
    }

    /// A 64 × 32 × 13 mask holding a disc of radius 4 centred at `cx(z)` on
    /// every slice.
    fn tube(cx: impl Fn(usize) -> f64) -> Mask {
        tube_of(13, 4.0, cx)
    }

    /// A 64 × 32 × `depth` mask holding a disc of radius `r` centred at
    /// `cx(z)` on every slice.
    fn tube_of(depth: usize, r: f64, cx: impl Fn(usize) -> f64) -> Mask {
        let g = Geometry::new([64, 32, depth], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for z in 0..depth {
            m.set_slice(Axis::Z, z, &disc(cx(z), r)).unwrap();
        }
        m
    }

    #[test]
    fn an_outline_drifting_steadily_is_no_jump() {
        let drawn = [0usize, 4, 8, 12];
        let gaps = |m: &Mask, drawn: &[usize]| {
            let input = SparseMask::new(m, Axis::Z, drawn);
            (
                jumping_gaps(&input).unwrap(),
                drifting_gaps(&input).unwrap(),
            )
        };
        // 1.5 pixels a slice: 6 between drawn slices, farther than the
        // radius, the same step across every gap.
        let tilted = tube(|z| 10.0 + 1.5 * z as f64);
        assert_eq!(gaps(&tilted, &drawn), (vec![], vec![0, 1, 2]));
        // Drawn on two slices only: no neighbouring gap to tell a drift.
        assert_eq!(gaps(&tilted, &[0, 4]), (vec![0], vec![]));
        // Back and forth: jumps.
        let zigzag = tube(|z| if (z / 4) % 2 == 0 { 14.0 } else { 22.0 });
        assert_eq!(gaps(&zigzag, &drawn), (vec![0, 1, 2], vec![]));
    }

    #[test]
    fn an_outline_that_moves_little_per_slice_is_no_jump_however_far_it_goes() {
        // A curve: a fifth of the radius a slice, then a twentieth; drawn
        // every 12th slice the first gap shares nothing (12 pixels moved,
        // radius 5) and its step is no neighbour's (no steady drift).
        let drawn = [0usize, 12, 24];
        let bend = |slope: f64| {
            move |z: usize| 8.0 + slope * z.min(12) as f64 + 0.25 * z.saturating_sub(12) as f64
        };
        let curved = tube_of(25, 5.0, bend(1.0));
        let input = SparseMask::new(&curved, Axis::Z, &drawn);
        assert!(apart_gaps(&input).unwrap().is_empty());
        // The same curve on an outline half as wide moves 0.4 of its
        // radius a slice: a jump.
        let thin = tube_of(25, 2.5, bend(1.0));
        let input = SparseMask::new(&thin, Axis::Z, &drawn);
        assert_eq!(jumping_gaps(&input).unwrap(), vec![0]);
        // And so does the wide one moving twice as fast.
        let fast = tube_of(25, 5.0, bend(2.0));
        let input = SparseMask::new(&fast, Axis::Z, &drawn);
        assert_eq!(jumping_gaps(&input).unwrap(), vec![0]);
    }
}
