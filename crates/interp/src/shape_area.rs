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
//! holds the area of the parabola through the areas of the gap's two drawn
//! slices and the drawn slice beyond the nearer end
//! ([`crate::area_profile`]): the blend says where, the profile how much (the
//! way `image-guided` raises a diluted walk to its prior's area). Where no
//! third drawn slice shows the structure (two drawn slices, or an end gap
//! with nothing beyond) the profile is not known, and the plain blend is
//! kept. The area is kept between half the smaller and twice the larger of
//! the gap's two drawn areas: three drawn areas that swing wildly (an outline
//! that jumps) should not empty or flood a slice. Gaps with a drawn slice
//! that does not show the structure are coned as `shape-based` cones them.
//!
//! Measured with `interslice bench` (`docs/interpolation.md`).
use crate::area_profile::{fit_slices, parabola};
use crate::shape_based::{blended, drawn_sdfs};
use crate::slices::{Plane, assemble};
use crate::{BoxReach, InterpError, Interpolator, SparseMask};
use interslice_core::Mask;

/// Signed-distance blending cut at the area of the drawn slices' profile.
#[derive(Debug, Default, Clone, Copy)]
pub struct ShapeArea;

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
        "signed distance maps blended linearly, each skipped slice cut to the area of the parabola through three drawn slices' areas"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        let plane = Plane::of(&input);
        let sdfs = drawn_sdfs(&input, &plane, 0)?;
        let drawn = input.drawn;
        let mut areas = Vec::with_capacity(drawn.len());
        for &d in drawn {
            let slice = input.mask.slice(input.axis, d)?;
            areas.push(slice.iter().filter(|&&x| x).count() as f64);
        }
        let n = drawn.len();
        assemble(&input, |s| {
            let (g, field) = blended(&sdfs, drawn, s)?;
            let (a, b) = (drawn[g], drawn[g + 1]);
            let fit = fit_slices(g, n, s - a <= b - s, |i| areas[i] > 0.0);
            let Some(fit) = fit else {
                return Some(field.iter().map(|&v| v < 0.0).collect());
            };
            let (area, ..) = parabola(
                fit.map(|i| drawn[i] as f64),
                fit.map(|i| areas[i]),
                s as f64,
            );
            let (lo, hi) = (areas[g].min(areas[g + 1]), areas[g].max(areas[g + 1]));
            let target = area.clamp(lo / 2.0, 2.0 * hi).round() as usize;
            Some(cut_to_area(&field, target))
        })
    }
}

/// The `target` pixels of `field` with the lowest values (ties at the cut
/// level all kept): the sublevel set of the blended distance field that holds
/// the area.
fn cut_to_area(field: &[f32], target: usize) -> Vec<bool> {
    if target == 0 {
        return vec![false; field.len()];
    }
    if target >= field.len() {
        return vec![true; field.len()];
    }
    let mut sorted = field.to_vec();
    let (_, level, _) = sorted.select_nth_unstable_by(target - 1, f32::total_cmp);
    let level = *level;
    field.iter().map(|&v| v <= level).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape_based::ShapeBased;
    use interslice_core::{Axis, Geometry, LengthUnit, Volume};

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
        let area = ShapeArea.interpolate(input).unwrap();
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

    #[test]
    fn with_two_drawn_slices_it_is_the_plain_blend() {
        let m = ball();
        let drawn = [4usize, 20];
        let input = SparseMask::new(&m, Axis::Z, &drawn);
        assert_eq!(
            ShapeArea.interpolate(input).unwrap(),
            ShapeBased.interpolate(input).unwrap()
        );
    }

    #[test]
    fn the_cut_keeps_the_lowest_values() {
        let f = [3.0, -1.0, 2.0, -2.0, 0.5];
        assert_eq!(cut_to_area(&f, 2), vec![false, true, false, true, false]);
        assert_eq!(cut_to_area(&f, 0), vec![false; 5]);
        assert_eq!(cut_to_area(&f, 9), vec![true; 5]);
    }
}
