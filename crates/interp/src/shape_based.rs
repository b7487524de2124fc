//! `shape-based`: signed distance maps of the drawn slices, blended linearly
//! along the axis (Raya & Udupa 1990; Herman, Zheng & Bucholtz 1992).
//!
//! Each drawn slice becomes a signed distance map in physical units (spacing
//! respected); a skipped slice at fraction `t` between drawn slices A and B is
//! `(1 - t) d_A + t d_B < 0`. Nothing is produced outside the drawn range.
//!
//! A drawn slice without the object is given the map described in
//! [`crate::sdf::drawn_maps`]: the object erodes to a point on the empty slice
//! (a cone) instead of being cut off right after the last slice showing it.
//! Objects are not matched: a shifted object is blended into the overlap of
//! its two positions, and an object on one side only is coned, not capped.
use crate::sdf::{Map, drawn_maps};
use crate::slices::{Plane, assemble, bracket};
use crate::{BoxReach, InterpError, Interpolator, SparseMask};
use interslice_core::Mask;

/// Linear blending of signed distance maps.
#[derive(Debug, Default, Clone, Copy)]
pub struct ShapeBased;

/// Signed distance maps of the drawn slices that border a gap (`None` for
/// drawn slices whose neighbours are all drawn: they are never needed).
/// `extra` widens "border" to `extra` drawn slices on each side of a gap,
/// for schemes that look further (cubic).
pub fn drawn_sdfs(
    input: &SparseMask<'_>,
    plane: &Plane,
    extra: usize,
) -> Result<Vec<Option<Map>>, InterpError> {
    let d = input.drawn;
    let n = d.len();
    let mut needed = vec![false; n];
    for g in 0..n - 1 {
        if d[g + 1] - d[g] > 1 {
            needed[g.saturating_sub(extra)..=(g + 1 + extra).min(n - 1)].fill(true);
        }
    }
    drawn_maps(input, plane, &needed)
}

impl Interpolator for ShapeBased {
    fn box_reach(&self) -> BoxReach {
        BoxReach::Outline
    }

    fn name(&self) -> &'static str {
        "shape-based"
    }

    fn description(&self) -> &'static str {
        "signed distance maps of the drawn slices blended linearly (Raya & Udupa 1990)"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        let plane = Plane::of(&input);
        let sdfs = drawn_sdfs(&input, &plane, 0)?;
        assemble(&input, |s| {
            let (_, field) = blended(&sdfs, input.drawn, s)?;
            Some(field.iter().map(|&v| v < 0.0).collect())
        })
    }
}

/// The blended distance field `(1 − t) d_A + t d_B` on skipped slice `s`
/// at fraction `t` of the gap between drawn slices A and B, with the gap's
/// index (`None` outside the drawn range): inside where it is below zero.
/// `sdfs` from [`drawn_sdfs`].
pub fn blended(sdfs: &[Option<Map>], drawn: &[usize], s: usize) -> Option<(usize, Vec<f32>)> {
    let g = bracket(drawn, s)?;
    let (a, b) = (drawn[g], drawn[g + 1]);
    let t = ((s - a) as f64 / (b - a) as f64) as f32;
    let da = sdfs[g].as_ref().expect("gap border");
    let db = sdfs[g + 1].as_ref().expect("gap border");
    let field = da
        .iter()
        .zip(db.iter())
        .map(|(&x, &y)| (1.0 - t) * x + t * y)
        .collect();
    Some((g, field))
}
