//! `shape-area`: signed-distance blending whose skipped slices hold the area
//! the drawn slices' area profile says they hold.
//!
//! A blend of two outlines decides *where* a skipped slice's boundary lies
//! but says little of *how much* it holds: between outlines that do not
//! overlap (pieces of a tissue class that move, split and join) the blend
//! shrinks each towards nothing in the middle of the gap, and along a round
//! structure it follows a line where the area follows a curve. Here each
//! skipped slice of a gap whose two drawn slices show the structure is cut
//! from the blended distance field `(1 − t) d_A + t d_B` at the level that
//! holds the area of the drawn slices' area profile: the parabolas through
//! the gap's two drawn areas and the one beyond either end, blended across
//! the gap, or the one parabola where only one end has a drawn slice beyond
//! it that shows the structure ([`crate::area_profile::profile_area`]): the blend says where, the profile how much (the
//! way `image-guided` raises a diluted walk to its prior's area). Where no
//! third drawn slice shows the structure the profile is not known: between
//! two drawn slices that show it with nothing else drawn, the structure is
//! taken to end half a slice beyond them and to bulge between as a round
//! one does (`pole_area`), where their areas are small enough to be its
//! polar caps (`polar_caps`); where more drawn slices show it, but none next to the
//! gap does, the plain blend is kept. In an end gap (no drawn slice beyond
//! one of its ends shows the structure) the parabola rests on one side
//! only and the area is kept between the gap's two drawn areas: on lung2 of
//! `interslice bench` traced on three slices (k = 6–8), whose area grows
//! slowly from its first slice and falls fast at its last, the parabola
//! through the three overshot the first gap by 1.6 times, and keeping it
//! between took the skipped slices from 0.805 / 0.771 / 0.644 to 0.831 /
//! 0.829 / 0.811 (the phantom, stardist and the T1 classes moved by at most
//! 0.003). Between drawn slices on both sides the area is kept between
//! half the smaller and twice the larger of the gap's two drawn areas:
//! three drawn areas that swing wildly (an outline that jumps) should not
//! empty or flood a slice. Gaps with a drawn slice
//! that does not show the structure are coned as `shape-based` cones them,
//! but where the structure narrows towards that slice the cone is cut to the
//! line through the two nearest drawn areas until it reaches 0
//! (`tip_area`): a small tip ends within a slice or two of its outline.
//!
//! Measured with `interslice bench` (`docs/interpolation.md`).
use crate::area_profile::profile_area;
use crate::shape_based::{blended, drawn_sdfs};
use crate::slices::{Plane, assemble};
use crate::{BoxReach, InterpError, Interpolator, SparseMask};
use interslice_core::Mask;

/// Signed-distance blending cut at the area of the drawn slices' profile.
#[derive(Debug, Clone, Copy)]
pub struct ShapeArea {
    /// Whether two drawn slices get the pole profile (`pole_area`). Not
    /// on a leave-one-out stack of drawn slices ([`Interpolator::for_stack`]):
    /// its slices lie a whole gap apart, so "ends within a slice beyond the
    /// outermost drawn slices" would reach a gap beyond them, and its
    /// outlines pass `polar_caps` where the real ones do not (a cone from
    /// radius 4 to 10 traced on its ends and middle, whose middle the
    /// profile then overshot twofold).
    pole: bool,
}

impl Default for ShapeArea {
    fn default() -> ShapeArea {
        ShapeArea { pole: true }
    }
}

impl Interpolator for ShapeArea {
    fn box_reach(&self) -> BoxReach {
        // The level that holds the profile's area can lie outside every
        // outline: the box grows as for objects that move.
        BoxReach::Drift
    }

    fn name(&self) -> &'static str {
        "shape-area"
    }

    fn description(&self) -> &'static str {
        "signed distance maps blended linearly, each skipped slice cut to the area of the parabolas through the drawn slices' areas, blended across the gap (between two drawn slices, a round structure's bulge)"
    }

    fn for_stack(
        &self,
        _axis: interslice_core::Axis,
        _real: &[usize],
    ) -> Result<Option<Box<dyn Interpolator>>, InterpError> {
        Ok(Some(Box::new(ShapeArea { pole: false })))
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        let plane = Plane::of(&input);
        let sdfs = drawn_sdfs(&input, &plane, 0)?;
        let drawn = input.drawn;
        let areas = drawn_areas(&input)?;
        let n = drawn.len();
        let pole = self.pole && pole_pair(drawn, &areas, &plane);
        assemble(&input, |s| {
            let (g, field) = blended(&sdfs, drawn, s)?;
            let (a, b) = (drawn[g], drawn[g + 1]);
            let (lo, hi) = (areas[g].min(areas[g + 1]), areas[g].max(areas[g + 1]));
            let Some(area) = profile_area(drawn, &areas, g, s) else {
                if pole && lo > 0.0 {
                    let target = pole_area(areas[g], areas[g + 1], b - a, s - a);
                    return Some(cut_to_area(&field, target.round() as usize));
                }
                let cone: Vec<bool> = field.iter().map(|&v| v < 0.0).collect();
                if let Some(target) = tip_area(drawn, &areas, g, s) {
                    let coned = cone.iter().filter(|&&x| x).count();
                    return Some(cut_to_area(&field, coned.min(target.round() as usize)));
                }
                return Some(cone);
            };
            // An end gap (no drawn slice beyond one of its ends shows the
            // structure) stays between its two drawn areas: the
            // parabola's turn there rests on one side only.
            let end_gap = g == 0 || areas[g - 1] == 0.0 || g + 2 >= n || areas[g + 2] == 0.0;
            let target = if end_gap {
                area.clamp(lo, hi)
            } else {
                area.clamp(lo / 2.0, 2.0 * hi)
            };
            Some(cut_to_area(&field, target.round() as usize))
        })
    }
}

/// The area at `t` slices into a gap of `l` slices between the only two
/// drawn slices that show a structure, of areas `a` and `b`: the line
/// between them times the bulge of a round structure whose ends lie half a
/// slice beyond them, `(t + ½)(l + ½ − t) / (½ (l + ½))` (1 on the drawn
/// slices, `(l + 1)² / (2l + 1)` in the middle).
///
/// Why: the outermost drawn slices are where the tracer saw the structure
/// begin and end (the end rule of `shape-auto`), so it ends within a slice
/// beyond each, and a round structure traced on its first and last slice
/// shows its small polar caps there, with the bulk between. A ball over
/// 11 slices has end areas a sixth of its middle's, which the line between
/// the ends misses. On the development data's lesions traced on two slices
/// (`interslice bench`: brain2, lung1, breast1 on three slices each, where
/// the middle slice holds 1.4–2.7 times the mean of the ends) it took
/// `shape-area` from 0.626 / 0.743 / 0.536 to 0.831 / 0.847 / 0.814 on the
/// skipped slices, past every shape anchor (`nearest`'s 0.782,
/// `shape-aligned`'s 0.771 and 0.536), and lung2 at k = 9 (two drawn
/// slices, 10 apart) from 0.427 to 0.716. It is not clamped as the
/// three-slice fit is: a ball traced on its polar caps holds ten times
/// their area in its middle (the upright ball of
/// `image::on_two_drawn_slices_...`: 0.969 unclamped, 0.495 held to twice
/// the larger end). lung2, longer than it is wide, would have kept more
/// with the clamp (0.802); `polar_caps` keeps the bulge off ends too
/// large to be caps.
fn pole_area(a: f64, b: f64, l: usize, t: usize) -> f64 {
    let (l, t) = (l as f64, t as f64);
    let line = a + (b - a) * t / l;
    line * (t + 0.5) * (l + 0.5 - t) / (0.5 * (l + 0.5))
}

/// The area at skipped slice `s` of gap `g` (between drawn slices `g` and
/// `g + 1`) where one of the two shows the structure and the other does
/// not, and the structure narrows towards the empty one: the line through
/// the areas of the showing slice and the drawn slice beyond it, carried on
/// until it reaches 0 (and 0 after). `None` where the structure does not
/// narrow there (or no drawn slice beyond shows it): the cone is kept.
///
/// Why: the cone (`crate::sdf::drawn_maps`) shrinks each outline towards
/// its deepest point on the empty slice, but on a grid a thin outline's
/// pixels all lie about as deep as its deepest one, so it keeps nearly
/// every pixel across most of the gap: a cylinder, not a cone. A nucleus
/// whose last drawn outline is its small tip (18 pixels, with 206 a gap
/// further in) ends within a slice of it, as its area profile says; the
/// cone carried the 18 pixels five slices on. A round structure's area
/// falls ever faster towards its pole, so the line through two drawn areas
/// reaches 0 at or past the true end: the cut is never too short for it.
fn tip_area(drawn: &[usize], areas: &[f64], g: usize, s: usize) -> Option<f64> {
    let (near, beyond, depth) = match (areas[g] > 0.0, areas[g + 1] > 0.0) {
        (true, false) => (g, g.checked_sub(1)?, s - drawn[g]),
        (false, true) => (g + 1, g + 2, drawn[g + 1] - s),
        _ => return None,
    };
    let far = *areas.get(beyond)?;
    let slope = (far - areas[near]) / drawn[near].abs_diff(drawn[beyond]) as f64;
    (slope > 0.0).then(|| (areas[near] - slope * depth as f64).max(0.0))
}

/// Whether `input` is filled with the pole profile: exactly two of its
/// drawn slices show the structure, with areas that can be its polar caps
/// (`polar_caps`).
pub fn pole_profile_applies(input: &SparseMask<'_>) -> Result<bool, InterpError> {
    Ok(pole_pair(
        input.drawn,
        &drawn_areas(input)?,
        &Plane::of(input),
    ))
}

/// Whether exactly two drawn slices show the structure and no other slice
/// is drawn, with areas that can be its polar caps (`polar_caps`): the gap
/// between them takes the pole profile.
///
/// A drawn slice without the structure beyond one of them (a label of a
/// label volume, whose other labels' drawn slices lack it) says the
/// structure ends somewhere before that slice, not that the two drawn
/// slices are its first and last, which the profile assumes. A flattened
/// ellipsoid's nucleus seen on slices 9 and 13 of its 8–15, with 5 and 17
/// drawn without it, took the profile's bulge (2.5 times its drawn area in
/// mid-gap) and a Dice of 0.74; the blend cut to the parabola through the
/// empty slice keeps 0.89. On stardist's nuclei as a label volume
/// (`shape-auto`, k = 1–9) only k = 5 and 7 moved, 0.7176 / 0.5578 →
/// 0.7171 / 0.5495; no other mask of the benchmark has a drawn slice
/// beyond its two.
fn pole_pair(drawn: &[usize], areas: &[f64], plane: &Plane) -> bool {
    drawn.len() == 2
        && areas.iter().all(|&a| a > 0.0)
        && polar_caps(areas[0].max(areas[1]), drawn[1] - drawn[0], plane)
}

/// The pixels inside the structure on each drawn slice of `input`.
fn drawn_areas(input: &SparseMask<'_>) -> Result<Vec<f64>, InterpError> {
    input
        .drawn
        .iter()
        .map(|&d| {
            let slice = input.mask.slice(input.axis, d)?;
            Ok(slice.iter().filter(|&&x| x).count() as f64)
        })
        .collect()
}

/// Whether drawn areas up to `larger` pixels can be the polar caps of a
/// round structure drawn on its first and last slice, `l` slices apart:
/// each at most [`CAP_SLACK`] times the cap of a ball that ends within a
/// slice beyond them (radius `r = (l / 2 + 1) dz`, a cap of height `dz`:
/// `π dz (2r − dz)`, physical units). Two large ends (a cone from radius 4
/// to 10 over 18 slices: 314 pixels against a cap of 60) are a structure
/// cut across its bulk, not its poles, and the bulge would flood it.
fn polar_caps(larger: f64, l: usize, plane: &Plane) -> bool {
    let dz = plane.slice_spacing;
    let r = (l as f64 / 2.0 + 1.0) * dz;
    let pixel = plane.spacing[0] * plane.spacing[1];
    larger * pixel <= CAP_SLACK * std::f64::consts::PI * dz * (2.0 * r - dz)
}

/// How much larger than a ball's polar cap (`polar_caps`) a drawn end
/// may be: pixels on a grid overcount a small disc (a ball of radius 12 cut
/// one slice from its pole shows 76 pixels for a cap of 72), and a
/// structure need not be a ball. The lesions of the development data
/// traced on two slices hold at most 0.6 of their cap (brain2 227 pixels
/// of 652, lung1 329 of 483, breast1 40 of 63, lung2 at k = 9 1070 of
/// 1998).
const CAP_SLACK: f64 = 1.5;

/// The `target` pixels of `field` with the lowest values (ties at the cut
/// level all kept): the sublevel set of the blended distance field that holds
/// the area.
pub fn cut_to_area(field: &[f32], target: usize) -> Vec<bool> {
    if target == 0 {
        return vec![false; field.len()];
    }
    if target >= field.len() {
        return vec![true; field.len()];
    }
    let level = nth_smallest(field, target - 1);
    field.iter().map(|&v| v <= level).collect()
}

/// The `n`-th smallest of `values` (0-based, `n < values.len()`) in
/// `f32::total_cmp`'s order.
///
/// Written here rather than `select_nth_unstable` on a copy of the slice:
/// `shape-area` cuts every skipped slice of a label's box, on every
/// leave-one-out run of the default too, and that copy and its partitions
/// were a seventh of the default's time on a round nucleus. One pass counts
/// the values by the top bits of their order-preserving key, and only the
/// bucket that holds the `n`-th is copied and selected from.
fn nth_smallest(values: &[f32], n: usize) -> f32 {
    const BITS: u32 = 12;
    // `total_cmp`'s order as an unsigned key: negatives flipped whole,
    // positives above them.
    let bucket = |v: f32| {
        let b = v.to_bits();
        let key = if b >> 31 == 1 { !b } else { b | 0x8000_0000 };
        (key >> (32 - BITS)) as usize
    };
    let mut counts = vec![0u32; 1 << BITS];
    for &v in values {
        counts[bucket(v)] += 1;
    }
    let mut before = 0usize;
    let mut holding = counts.len() - 1;
    for (b, &c) in counts.iter().enumerate() {
        if before + c as usize > n {
            holding = b;
            break;
        }
        before += c as usize;
    }
    let mut inside: Vec<f32> = values
        .iter()
        .copied()
        .filter(|&v| bucket(v) == holding)
        .collect();
    *inside.select_nth_unstable_by(n - before, f32::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape_based::ShapeBased;
    use interslice_core::{Axis, Geometry, LengthUnit, Volume};
    use proptest::prelude::*;

    proptest! {
        /// The bucketed selection gives what sorting gives, on fields of
        /// distances with ties, signed zeros, infinities and the far value.
        #[test]
        fn nth_smallest_is_the_sorted_value(
            values in prop::collection::vec(
                prop_oneof![
                    -50.0f32..50.0,
                    (-8i32..8).prop_map(|v| v as f32 * 0.5),
                    Just(-0.0f32),
                    Just(crate::sdf::FAR),
                    Just(f32::INFINITY),
                    Just(f32::NEG_INFINITY),
                ],
                1..400,
            ),
            pick in 0.0f64..1.0,
        ) {
            let n = ((values.len() as f64 * pick) as usize).min(values.len() - 1);
            let mut sorted = values.clone();
            sorted.sort_by(f32::total_cmp);
            prop_assert_eq!(nth_smallest(&values, n).to_bits(), sorted[n].to_bits());
        }
    }

    /// A ball of radius 12 voxels centred at z = 14, drawn every `step`
    /// slices from its first to its last.
    fn ball() -> Mask {
        let g = Geometry::new([40, 40, 29], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for z in 0..29usize {
            for y in 0..40usize {
                for x in 0..40usize {
                    let d = [x as f64 - 19.5, y as f64 - 19.5, z as f64 - 14.0];
                    if d.iter().map(|v| v * v).sum::<f64>() <= 144.0 {
                        m.set(x, y, z, true);
                    }
                }
            }
        }
        m
    }

    fn skipped_dice(truth: &Mask, out: &Mask, drawn: &[usize]) -> f64 {
        let skipped = crate::protocol::skipped(drawn);
        crate::protocol::dice_on(truth, out, Axis::Z, &skipped)
    }

    #[test]
    fn a_round_structure_keeps_its_area_where_the_blend_follows_a_line() {
        let m = ball();
        let drawn = [2usize, 8, 14, 20, 26];
        let input = SparseMask::new(&m, Axis::Z, &drawn);
        let area = ShapeArea::default().interpolate(input).unwrap();
        let blend = ShapeBased.interpolate(input).unwrap();
        let (a, b) = (
            skipped_dice(&m, &area, &drawn),
            skipped_dice(&m, &blend, &drawn),
        );
        assert!(a > b + 0.01, "shape-area {a:.4}, shape-based {b:.4}");
        // Drawn slices are copied, nothing past the outermost ones.
        for z in drawn {
            assert_eq!(
                area.slice(Axis::Z, z).unwrap(),
                m.slice(Axis::Z, z).unwrap()
            );
        }
        for z in [0usize, 1, 27, 28] {
            assert!(area.slice(Axis::Z, z).unwrap().iter().all(|&x| !x));
        }
    }

    /// A ball drawn on its first and last slice only: the blend draws a
    /// thin tube between its two small caps, the pole profile the ball.
    #[test]
    fn between_two_drawn_slices_it_bulges_as_a_round_structure() {
        let m = ball();
        let drawn = [3usize, 25];
        let input = SparseMask::new(&m, Axis::Z, &drawn);
        let (area, blend) = (
            ShapeArea::default().interpolate(input).unwrap(),
            ShapeBased.interpolate(input).unwrap(),
        );
        let (a, b) = (
            skipped_dice(&m, &area, &drawn),
            skipped_dice(&m, &blend, &drawn),
        );
        eprintln!("shape-area {a:.4}, shape-based {b:.4}");
        assert!(a > b + 0.2, "shape-area {a:.4}, shape-based {b:.4}");
        let count =
            |v: &Mask, z: usize| v.slice(Axis::Z, z).unwrap().iter().filter(|&&x| x).count();
        // The middle holds several times either drawn slice's 76 pixels:
        // 896 against the ball's 448 (its last slices lie a whole slice
        // from its poles, not the half the profile takes; the blend's 76
        // is further off).
        let (ends, mid) = (count(&m, 3).max(count(&m, 25)), count(&m, 14));
        let got = count(&area, 14);
        assert!(got > 4 * ends && got < 3 * mid, "{got} vs {mid}");
        // The profile itself: 1 on the drawn slices, (l + 1)² / (2l + 1)
        // in the middle.
        assert!((pole_area(10.0, 10.0, 4, 0) - 10.0).abs() < 1e-9);
        assert!((pole_area(10.0, 10.0, 4, 4) - 10.0).abs() < 1e-9);
        assert!((pole_area(10.0, 10.0, 4, 2) - 10.0 * 25.0 / 9.0).abs() < 1e-9);
    }

    /// The ball's top tip drawn next to an empty drawn slice: the cone
    /// would carry the tip's outline down the gap; the line through the
    /// tip's and the next drawn slice's areas ends it within two slices,
    /// where the ball ends (slice 2 holds no pixel of it). Where the ball
    /// widens towards the empty slice (its equator drawn next to it) the
    /// line says nothing and the cone is kept.
    #[test]
    fn a_narrowing_tip_ends_where_its_area_profile_does_not_where_the_cone_does() {
        let m = ball();
        let count =
            |v: &Mask, z: usize| v.slice(Axis::Z, z).unwrap().iter().filter(|&&x| x).count();
        let drawn = [0usize, 3, 9, 15, 21, 27];
        let input = SparseMask::new(&m, Axis::Z, &drawn);
        let (area, blend) = (
            ShapeArea::default().interpolate(input).unwrap(),
            ShapeBased.interpolate(input).unwrap(),
        );
        let (tip, next) = (count(&m, 3) as f64, count(&m, 9) as f64);
        let line = |depth: f64| (tip - (next - tip) / 6.0 * depth).max(0.0);
        assert_eq!(count(&area, 1), 0);
        assert!(count(&blend, 1) > 0, "the cone ends on slice 0");
        // The cut keeps the pixels tied at its level (`cut_to_area`):
        // 32 pixels for the line's 26, the cone's 52.
        let (got, cone) = (count(&area, 2), count(&blend, 2));
        assert!(
            (got as f64) < 1.5 * line(1.0) && got < cone,
            "{got} vs {cone}"
        );
        for z in [0, 1, 2] {
            assert_eq!(count(&m, z), 0);
        }
        let drawn = [0usize, 14, 20, 26];
        let input = SparseMask::new(&m, Axis::Z, &drawn);
        let (area, blend) = (
            ShapeArea::default().interpolate(input).unwrap(),
            ShapeBased.interpolate(input).unwrap(),
        );
        for z in 1..14 {
            assert_eq!(area.slice(Axis::Z, z), blend.slice(Axis::Z, z), "slice {z}");
        }
    }

    #[test]
    fn the_cut_keeps_the_lowest_values() {
        let f = [3.0, -1.0, 2.0, -2.0, 0.5];
        assert_eq!(cut_to_area(&f, 2), vec![false, true, false, true, false]);
        assert_eq!(cut_to_area(&f, 0), vec![false; 5]);
        assert_eq!(cut_to_area(&f, 9), vec![true; 5]);
    }
}
