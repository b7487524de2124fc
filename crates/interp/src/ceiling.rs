//! The area ceiling: how far a level set of the blended distance maps can
//! go when it knows each skipped slice's true area. A bound for the
//! benchmark, not a method: it reads the truth.
//!
//! Why: `shape-area` cuts the blend `(1 − t) d_A + t d_B` of the two drawn
//! slices around a gap at the area its profile predicts. Cut at the true
//! area instead, the same blend shows how much of the distance to a target
//! is the area's prediction and how much the blend's shape, which no area
//! can mend. `interslice bench --methods area-ceiling` prints it beside the
//! methods (`docs/interpolation.md`, "What the tracing allows").
use crate::shape_area::cut_to_area;
use crate::shape_based::{blended, drawn_sdfs};
use crate::slices::{Plane, assemble};
use crate::{BoxReach, InterpError, Interpolator, SparseMask};
use interslice_core::Mask;

/// The blend of the drawn slices' distance maps cut at the true area of
/// each skipped slice of `truth` (same grid and axis as the sparse input).
#[derive(Debug, Clone)]
pub struct AreaCeiling {
    truth: Mask,
}

impl AreaCeiling {
    /// The ceiling of tracings of `truth`.
    pub fn new(truth: Mask) -> AreaCeiling {
        AreaCeiling { truth }
    }
}

impl Interpolator for AreaCeiling {
    fn box_reach(&self) -> BoxReach {
        BoxReach::Drift
    }

    fn name(&self) -> &'static str {
        "area-ceiling"
    }

    fn description(&self) -> &'static str {
        "a bound, not a method: the linear blend of the distance maps cut at each skipped slice's true area"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        if self.truth.geometry() != input.mask.geometry() {
            return Err(InterpError::Input(
                "area-ceiling: the truth's grid differs from the tracing's".into(),
            ));
        }
        let plane = Plane::of(&input);
        let sdfs = drawn_sdfs(&input, &plane, 0)?;
        assemble(&input, |s| {
            let (_, field) = blended(&sdfs, input.drawn, s)?;
            let truth = self.truth.slice(input.axis, s).ok()?;
            Some(cut_to_area(&field, truth.iter().filter(|&&x| x).count()))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{dice_on, drawn_for_skip, skipped, sparse_of};
    use crate::shape_area::ShapeArea;
    use interslice_core::{Axis, Geometry, LengthUnit, Volume};

    /// A cone along z whose radius grows by `rate` per slice.
    fn cone(rate: f64) -> Mask {
        let g = Geometry::new([48, 48, 30], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for z in 0..30usize {
            let r = 3.0 + rate * z as f64;
            for y in 0..48usize {
                for x in 0..48usize {
                    let (dx, dy) = (x as f64 - 23.5, y as f64 - 23.5);
                    if dx * dx + dy * dy <= r * r {
                        m.set(x, y, z, true);
                    }
                }
            }
        }
        m
    }

    #[test]
    fn the_ceiling_holds_the_true_area_and_is_no_worse_than_shape_area() {
        let truth = cone(0.6);
        let drawn = drawn_for_skip(&truth, Axis::Z, 5).unwrap();
        let sparse = sparse_of(&truth, Axis::Z, &drawn);
        let run = |m: &dyn Interpolator| {
            m.interpolate(SparseMask::new(&sparse, Axis::Z, &drawn))
                .unwrap()
        };
        let ceiling = run(&AreaCeiling::new(truth.clone()));
        for s in skipped(&drawn) {
            let count = |m: &Mask| m.slice(Axis::Z, s).unwrap().iter().filter(|&&x| x).count();
            // Ties at the cut level are kept: a few pixels over, never under.
            let (got, want) = (count(&ceiling), count(&truth));
            assert!(
                got >= want && got <= want + want / 10,
                "slice {s}: {got} vs {want}"
            );
        }
        let dice = |m: &Mask| dice_on(m, &truth, Axis::Z, &skipped(&drawn));
        let (c, a) = (dice(&ceiling), dice(&run(&ShapeArea::default())));
        assert!(c > 0.97 && c >= a - 0.002, "ceiling {c}, shape-area {a}");
    }

    #[test]
    fn a_truth_on_another_grid_is_refused() {
        let truth = cone(0.6);
        let drawn = drawn_for_skip(&truth, Axis::Z, 5).unwrap();
        let sparse = sparse_of(&truth, Axis::Z, &drawn);
        let g = Geometry::new([10, 10, 10], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let err = AreaCeiling::new(Volume::zeros(g))
            .interpolate(SparseMask::new(&sparse, Axis::Z, &drawn))
            .unwrap_err();
        assert!(err.to_string().contains("grid"), "{err}");
    }
}
