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
use crate::SparseMask;
use crate::image::fuse::tau;
use crate::sdf::signed_distance;
use crate::slices::{Plane, to_nearest_drawn};
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
                // Nothing on the slice between two drawn slices: as sure as
                // the nearest drawn slice is empty.
                return None;
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
