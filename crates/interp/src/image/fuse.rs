//! One skipped slice: the shape prior's signed distance fused with an
//! intensity likelihood learned from the drawn slices, regularised by an
//! edge-weighted diffusion, restricted to a band around the prior.
//!
//! The logit of "inside" at pixel `x` is
//! `z0(x) = −φ(x) / τ + w · L(I(x))`, where `φ` is the prior's signed distance
//! (physical units, negative inside), `τ` is the prior's uncertainty, which
//! grows with the distance `δ` to the nearest drawn slice (fitted by
//! leave-one-out, [`crate::image::Plan`]), and `L` is the log-likelihood ratio of the intensity
//! ([`IntensityModel`]). With `λ > 0`, `z` then minimises
//! `Σ (z − z0)² + λ Σ_{x~y} ω_xy (z_x − z_y)²` (Jacobi iterations), with
//! `ω_xy = exp(−(I_x − I_y)² / 2σ²)`: the random walker's edge weights
//! (Grady 2006) on a logit instead of a probability, so the decision follows
//! image edges where the image has them. Pixels farther than the band from
//! the prior's boundary keep the prior.
//!
//! Separation: pixels the image adds outside the prior belong to the prior
//! object they are reached from first (a breadth-first growth inside the
//! band); an added pixel touching (8-neighbourhood) an inside pixel of
//! another object is dropped, so objects separate in the prior stay separate.
use crate::image::model::IntensityModel;
use crate::slices::Plane;
use interslice_core::morph::Connectivity;
use interslice_core::regions::{flood_2d, neighbours_2d};
use std::collections::VecDeque;

/// Fusion parameters chosen by leave-one-out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// Weight of the intensity log-likelihood (0 = shape only).
    pub w: f32,
    /// Strength of the edge-weighted smoothing (0 = none).
    pub lambda: f32,
}

impl Params {
    /// No image: the shape prior alone.
    pub const SHAPE_ONLY: Params = Params {
        w: 0.0,
        lambda: 0.0,
    };
}

/// Jacobi iterations of the smoothing.
const ITERATIONS: usize = 12;

/// The band half-width in physical units around the prior's boundary.
pub fn band(plane: &Plane, delta: f64) -> f32 {
    let p = plane.spacing[0].min(plane.spacing[1]);
    (4.0 * p)
        .max(0.5 * delta * plane.slice_spacing)
        .min(40.0 * p) as f32
}

/// The prior's default scale `τ` at `delta` slices from the nearest drawn
/// slice (used for the shape methods' confidence; the image method fits its
/// own, [`crate::image::Plan`]).
pub fn tau(plane: &Plane, delta: f64) -> f32 {
    let p = plane.spacing[0].min(plane.spacing[1]);
    (p * (1.0 + 0.5 * delta * plane.slice_spacing / p)) as f32
}

/// The fused logit of "inside" of one slice (`> 0` inside) and the mask.
///
/// `t` is the prior's scale `τ` (physical units) and `delta` the distance to
/// the nearest drawn slice, in slices (it sets the band).
pub fn fuse(
    phi: &[f32],
    image: &[f32],
    model: &IntensityModel,
    plane: &Plane,
    (t, delta): (f32, f64),
    p: Params,
) -> (Vec<bool>, Vec<f32>) {
    let b = band(plane, delta);
    let mut z: Vec<f32> = phi
        .iter()
        .zip(image)
        .map(|(&d, &i)| {
            if d.abs() <= b {
                -d / t + p.w * model.llr(i)
            } else {
                -d / t
            }
        })
        .collect();
    if p.w == 0.0 {
        let mask = z.iter().map(|&x| x > 0.0).collect();
        return (mask, z);
    }
    if p.lambda > 0.0 {
        smooth(&mut z, phi, image, plane, b, p.lambda);
    }
    let mask = separate(phi, &z, plane, b);
    (mask, z)
}

/// Edge-weighted Jacobi smoothing of `z` on the band pixels (4-neighbours).
fn smooth(z: &mut [f32], phi: &[f32], image: &[f32], plane: &Plane, b: f32, lambda: f32) {
    let (w, h) = (plane.width, plane.height);
    let in_band: Vec<usize> = (0..w * h).filter(|&i| phi[i].abs() <= b).collect();
    if in_band.is_empty() {
        return;
    }
    // σ² of the intensity differences between band neighbours.
    let mut acc = 0.0f64;
    let mut cnt = 0u64;
    for &i in &in_band {
        let u = i % w;
        if u + 1 < w {
            acc += f64::from((image[i] - image[i + 1]).powi(2));
            cnt += 1;
        }
        if i + w < w * h {
            acc += f64::from((image[i] - image[i + w]).powi(2));
            cnt += 1;
        }
    }
    let s2 = ((acc / cnt.max(1) as f64) as f32).max(1e-12);
    let weight = |a: f32, c: f32| (-(a - c).powi(2) / (2.0 * s2)).exp();
    // Each band pixel's neighbours (left, right, above, below) with their
    // weights, worked out once rather than on every iteration (the
    // exponentials were a sixth of the method's time); the sums below add
    // them in the same order, so the result is the same to the bit.
    let links: Vec<([(usize, f32); 4], usize)> = in_band
        .iter()
        .map(|&i| {
            let (u, v) = (i % w, i / w);
            let near = [
                (u > 0).then(|| i - 1),
                (u + 1 < w).then(|| i + 1),
                (v > 0).then(|| i - w),
                (v + 1 < h).then(|| i + w),
            ];
            let mut l = ([(0usize, 0.0f32); 4], 0);
            for j in near.into_iter().flatten() {
                l.0[l.1] = (j, lambda * weight(image[i], image[j]));
                l.1 += 1;
            }
            l
        })
        .collect();
    let z0 = z.to_vec();
    let mut next = z.to_vec();
    for _ in 0..ITERATIONS {
        for (&i, (l, m)) in in_band.iter().zip(&links) {
            let mut num = z0[i];
            let mut den = 1.0f32;
            for &(j, o) in &l[..*m] {
                num += o * z[j];
                den += o;
            }
            next[i] = num / den;
        }
        for &i in &in_band {
            z[i] = next[i];
        }
    }
}

/// The mask `z > 0`, keeping the prior's objects apart (see the module doc).
pub(crate) fn separate(phi: &[f32], z: &[f32], plane: &Plane, b: f32) -> Vec<bool> {
    let (w, h) = (plane.width, plane.height);
    // Objects of the prior (8-connected) grown breadth-first through the band.
    let prior: Vec<bool> = phi.iter().map(|&p| p < 0.0).collect();
    let mut queue = VecDeque::new();
    let mut region = flood_2d(&prior, w, h, Connectivity::Full, |_, i| queue.push_back(i));
    while let Some(i) = queue.pop_front() {
        for j in neighbours_2d(i, w, h, Connectivity::Full) {
            if region[j] == 0 && phi[j] <= b {
                region[j] = region[i];
                queue.push_back(j);
            }
        }
    }
    let inside: Vec<bool> = (0..w * h).map(|i| z[i] > 0.0 && region[i] != 0).collect();
    (0..w * h)
        .map(|i| {
            if !inside[i] {
                return false;
            }
            if phi[i] < 0.0 {
                return true;
            }
            !neighbours_2d(i, w, h, Connectivity::Full).any(|j| inside[j] && region[j] != region[i])
        })
        .collect()
}
