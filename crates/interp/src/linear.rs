//! `linear`: the original contour-correspondence interpolator.
//!
//! For each pair of consecutive drawn slices A and B: the contours of A
//! (traced along pixel cracks, [`interslice_core::trace::mask_polygons`]) are
//! resampled to about one point per pixel; every point `p` is paired with the
//! nearest point `q` of the (equally resampled) contours of B; on a skipped
//! slice `s = a + step` the contour passes through `p + t (q - p)` with
//! `t = step / (gap + 1)`, and the moved contours are filled by the even-odd
//! rule over all of them (so holes stay holes).
//!
//! Faithful to the 2014 program, including its limits:
//! - nothing is produced before the first or after the last drawn slice;
//! - an object drawn on A but not on B (or on B but not on A) has no
//!   correspondence and vanishes from every slice between them;
//! - the correspondence is one-way (A to B): when one contour on A faces two on
//!   B (a split), all its points run to the nearer one or jump between them, so
//!   the skipped slices may show a single, distorted shape or self-crossings;
//! - nearest-point pairing slides along strongly shifted or rotated contours.
use crate::slices::{Plane, assemble, bracket, drawn_slices};
// Not run on a label's box: its moved contours are rounded at absolute pixel
// positions and ties in the nearest-point pairing follow the tracing order,
// so a shifted box can move a voxel on a pixel boundary.
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::Mask;
use interslice_core::raster::rasterize_polygons;
use interslice_core::trace::mask_polygons;
use rayon::prelude::*;

/// The original contour-correspondence linear interpolator.
#[derive(Debug, Default, Clone, Copy)]
pub struct Linear;

impl Interpolator for Linear {
    fn name(&self) -> &'static str {
        "linear"
    }

    fn description(&self) -> &'static str {
        "original 2014 method: nearest-point contour correspondence, straight lines between drawn slices"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        let plane = Plane::of(&input);
        let slices = drawn_slices(&input);
        // Resampled contours of every drawn slice, computed once.
        let contours: Vec<Vec<Vec<[f64; 2]>>> = slices
            .par_iter()
            .map(|m| {
                mask_polygons(m, plane.width, plane.height)
                    .iter()
                    .map(|p| resample(p, 1.0))
                    .collect()
            })
            .collect();
        // Per gap, the nearest-point partner of every point of A on B.
        let partners: Vec<Vec<Vec<[f64; 2]>>> = (0..input.drawn.len() - 1)
            .into_par_iter()
            .map(|g| match_nearest(&contours[g], &contours[g + 1]))
            .collect();
        let drawn = input.drawn;
        assemble(&input, |s| {
            let g = bracket(drawn, s)?;
            let (a, b) = (drawn[g], drawn[g + 1]);
            if contours[g].is_empty() || contours[g + 1].is_empty() {
                return None;
            }
            let t = (s - a) as f64 / (b - a) as f64;
            let moved: Vec<Vec<[f64; 2]>> = contours[g]
                .iter()
                .zip(&partners[g])
                .map(|(ps, qs)| {
                    ps.iter()
                        .zip(qs)
                        .map(|(p, q)| [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])])
                        .collect()
                })
                .collect();
            Some(fill_even_odd(&moved, plane.width, plane.height))
        })
    }
}

/// Points along a closed polygon, about `step` apart (every vertex kept).
pub fn resample(poly: &[[f64; 2]], step: f64) -> Vec<[f64; 2]> {
    let n = poly.len();
    let mut out = Vec::with_capacity(n * 2);
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let pieces = (len / step).ceil().max(1.0) as usize;
        for p in 0..pieces {
            let t = p as f64 / pieces as f64;
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

/// For every point of `from`, the nearest point of `to` (all contours of `to`
/// together). Brute force over a coarse grid of buckets would be faster; the
/// contours of one slice have a few thousand points, so a plain scan in
/// parallel is fast enough and obviously right.
fn match_nearest(from: &[Vec<[f64; 2]>], to: &[Vec<[f64; 2]>]) -> Vec<Vec<[f64; 2]>> {
    let targets: Vec<[f64; 2]> = to.iter().flatten().copied().collect();
    if targets.is_empty() {
        return Vec::new();
    }
    from.iter()
        .map(|poly| {
            poly.par_iter()
                .map(|p| {
                    let mut best = targets[0];
                    let mut bd = f64::INFINITY;
                    for q in &targets {
                        let d = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
                        if d < bd {
                            bd = d;
                            best = *q;
                        }
                    }
                    best
                })
                .collect()
        })
        .collect()
}

/// Even-odd fill over all polygons together (a hole contour inside an outer
/// contour removes its pixels), by XOR of each polygon's own fill.
pub fn fill_even_odd(polys: &[Vec<[f64; 2]>], width: usize, height: usize) -> Vec<bool> {
    let mut buf = vec![false; width * height];
    for p in polys {
        let one = rasterize_polygons(&[p.as_slice()], width, height);
        for (b, o) in buf.iter_mut().zip(one) {
            *b ^= o;
        }
    }
    buf
}
