//! Confidence per voxel: how sure an interpolation is that a voxel is on the
//! side of the boundary it put it on, in `[0.5, 1]` (1 on drawn slices and
//! outside the drawn range, 0.5 on the boundary of a skipped slice).
//!
//! Shape methods: `σ(c · |φ| / τ(δ))`, with `φ` the signed distance to the
//! result's boundary on the slice and `τ(δ)` ([`crate::image::fuse::tau`])
//! the shape's uncertainty, which grows with the distance `δ` to the nearest
//! drawn slice; `c = 1` unless leave-one-out calibrated it
//! ([`crate::image::ImageGuided`] fits `c` on the held-out drawn slices). The
//! image-guided method writes `σ(c · |z|)` of its fused logit `z` instead.
//! On a skipped slice the result leaves empty next to a drawn outline (the
//! structure ended before it, how far past the outline no tracing says),
//! the pixels under that outline are a coin toss ([`shape_confidence`]).
use crate::SparseMask;
use crate::image::fuse::tau;
use crate::sdf::signed_distance;
use crate::slices::{Plane, bracket, to_nearest_drawn};
use interslice_core::{Mask, Volume};
use rayon::prelude::*;

/// The logistic function.
pub fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

/// Confidence of a shape result `mask` interpolated from `input` (see the module doc).
pub fn shape_confidence(mask: &Mask, input: &SparseMask<'_>, scale: f32) -> Volume<f32> {
    let plane = Plane::of(input);
    let n = mask.slice_count(input.axis);
    let drawn = input.drawn;
    let slices: Vec<Option<Vec<f32>>> = (0..n)
        .into_par_iter()
        .map(|s| {
            let delta = to_nearest_drawn(drawn, s)?;
            let m = mask.slice(input.axis, s).expect("slice in range");
            if !m.iter().any(|&x| x) {
                return ended_confidence(input, s, scale);
            }
            let t = tau(&plane, delta);
            let phi = signed_distance(&m, &plane);
            Some(phi.iter().map(|&d| sigmoid(scale * d.abs() / t)).collect())
        })
        .collect();
    let mut out = Volume::filled(mask.geometry().clone(), 1.0f32);
    for (s, v) in slices.into_iter().enumerate() {
        if let Some(v) = v {
            out.set_slice(input.axis, s, &v).expect("slice in range");
        }
    }
    out
}

/// Confidence on skipped slice `s` where the result is empty: `None` (as
/// sure as a drawn slice) where neither drawn slice beside it shows the
/// structure; else the structure ended before `s` although the nearer
/// drawn slice `D` that shows it lies `δ` slices away, and how far it
/// reaches past `D` is in no tracing. So a pixel inside `D`'s outline is
/// as unsure as a boundary (0.5), one outside it as sure as its distance
/// `φ_D` from that outline says, `max(½, σ(c · φ_D / τ(δ)))`.
fn ended_confidence(input: &SparseMask<'_>, s: usize, scale: f32) -> Option<Vec<f32>> {
    let plane = Plane::of(input);
    let g = bracket(input.drawn, s)?;
    let nearest = [input.drawn[g], input.drawn[g + 1]]
        .into_iter()
        .filter_map(|d| {
            let m = input.mask.slice(input.axis, d).ok()?;
            m.iter().any(|&x| x).then_some((d.abs_diff(s), m))
        })
        .min_by_key(|(delta, _)| *delta)?;
    let t = tau(&plane, nearest.0 as f64);
    let phi = signed_distance(&nearest.1, &plane);
    Some(
        phi.iter()
            .map(|&d| sigmoid(scale * d / t).max(0.5))
            .collect(),
    )
}

/// The scale `c` of `scales` with the least log-loss of `σ(c z)` against
/// the truth over the `(logit, truth)` slices (a one-parameter Platt
/// scaling); the first scale when no slice is given.
pub fn best_scale<'a>(
    scales: &[f32],
    slices: impl Iterator<Item = (&'a Vec<f32>, &'a Vec<bool>)> + Clone,
) -> f32 {
    let mut best = (f64::INFINITY, scales[0]);
    for &c in scales {
        let mut loss = 0.0f64;
        for (z, truth) in slices.clone() {
            for (&zi, &t) in z.iter().zip(truth.iter()) {
                let p = f64::from(sigmoid(c * zi)).clamp(1e-6, 1.0 - 1e-6);
                loss -= if t { p.ln() } else { (1.0 - p).ln() };
            }
        }
        if loss < best.0 {
            best = (loss, c);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{Axis, Geometry, LengthUnit};

    /// A disc of radius 6 on drawn slice 0, slice 6 drawn empty; the
    /// result keeps the disc on slice 1 and ends before slice 2.
    #[test]
    fn where_the_result_ends_before_a_drawn_outline_the_pixels_under_it_are_unsure() {
        let g = Geometry::new([24, 24, 12], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let disc = |i: usize, j: usize| (i as f64 - 12.0).hypot(j as f64 - 12.0) < 6.0;
        let mut sparse = Mask::zeros(g.clone());
        let mut result = Mask::zeros(g);
        for j in 0..24 {
            for i in 0..24 {
                sparse.set(i, j, 0, disc(i, j));
                for k in 0..2 {
                    result.set(i, j, k, disc(i, j));
                }
            }
        }
        let drawn = [0usize, 6, 11];
        let input = SparseMask::new(&sparse, Axis::Z, &drawn);
        let c = shape_confidence(&result, &input, 1.0);
        for k in 2..6 {
            // Under the disc: the structure may go on, a coin toss.
            assert_eq!(c.get(12, 12, k), 0.5, "slice {k}");
            // Just outside it, less sure the farther from slice 0; far out, sure.
            let near = c.get(19, 12, k);
            assert!(near > 0.5 && near < 0.99, "slice {k}: {near}");
            assert!(c.get(0, 0, k) > 0.9, "slice {k}: {}", c.get(0, 0, k));
        }
        assert!(c.get(19, 12, 2) > c.get(19, 12, 5));
        // The disc itself on slice 1: sure at its centre (6 pixels in).
        assert!(c.get(12, 12, 1) > 0.95, "{}", c.get(12, 12, 1));
        // Between two drawn-empty slices: as sure as they are.
        for k in 7..11 {
            assert!(c.slice(Axis::Z, k).unwrap().iter().all(|&x| x == 1.0));
        }
    }
}
