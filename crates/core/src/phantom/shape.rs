//! Smooth star-shaped solids: a radius that varies with direction.
//!
//! The radius of a [`StarShape`] in direction `d` (a unit vector from its
//! centre) is `radius * (1 + Σ a_t P_{l_t}(d · n_t)) * Π (1 - depth_s * bump_s(d))`:
//! a sphere perturbed by rotated zonal spherical harmonics (Legendre
//! polynomials of degree 2..4 of the angle to a random axis, which span the
//! low-order spherical harmonics), times smooth dents (`bump = exp(-(1 - d·m)
//! / width)`), which make a surface non-convex the way an indented nucleus is.
//! Written here because it is a few lines of geometry specific to this model.

/// Legendre polynomial `P_l(x)` for l in 0..=4 (|P_l| <= 1 on [-1, 1]).
#[inline]
pub fn legendre(l: u8, x: f64) -> f64 {
    match l {
        0 => 1.0,
        1 => x,
        2 => 0.5 * (3.0 * x * x - 1.0),
        3 => 0.5 * (5.0 * x * x - 3.0) * x,
        _ => {
            let x2 = x * x;
            (35.0 * x2 * x2 - 30.0 * x2 + 3.0) / 8.0
        }
    }
}

/// One spherical-harmonic-like term of a radius function.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Harmonic {
    /// Unit axis of the zonal harmonic.
    pub axis: [f64; 3],
    /// Degree 2..=4.
    pub degree: u8,
    /// Relative amplitude (signed).
    pub amplitude: f64,
}

/// A smooth inward dent of a radius function.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dent {
    /// Unit direction of the dent's centre.
    pub axis: [f64; 3],
    /// Relative depth in 0..1 (radius times `1 - depth` at the centre).
    pub depth: f64,
    /// Angular width parameter (larger is wider), about `angle² / 2`.
    pub width: f64,
}

/// A star-shaped solid around `centre` (continuous voxel coordinates, in
/// which voxel (i, j, k) has its centre at (i + 0.5, j + 0.5, k + 0.5)).
#[derive(Debug, Clone, PartialEq)]
pub struct StarShape {
    /// Centre (the star point).
    pub centre: [f64; 3],
    /// Mean radius in voxels.
    pub radius: f64,
    /// Spherical-harmonic-like perturbations of the radius.
    pub harmonics: Vec<Harmonic>,
    /// Dents.
    pub dents: Vec<Dent>,
}

#[inline]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl StarShape {
    /// Radius in unit direction `d`.
    #[inline]
    pub fn radius_at(&self, d: [f64; 3]) -> f64 {
        let mut f = 1.0;
        for h in &self.harmonics {
            f += h.amplitude * legendre(h.degree, dot(d, h.axis));
        }
        for dent in &self.dents {
            f *= 1.0 - dent.depth * (-(1.0 - dot(d, dent.axis)) / dent.width).exp();
        }
        self.radius * f
    }

    /// An upper bound of the radius in every direction.
    pub fn max_radius(&self) -> f64 {
        self.radius
            * (1.0
                + self
                    .harmonics
                    .iter()
                    .map(|h| h.amplitude.abs())
                    .sum::<f64>())
    }

    /// Signed radial depth of `p` below the surface, in voxels: positive inside,
    /// `radius_at(d) - |p - centre|` (the centre has the full radius).
    #[inline]
    pub fn depth(&self, p: [f64; 3]) -> f64 {
        let v = [
            p[0] - self.centre[0],
            p[1] - self.centre[1],
            p[2] - self.centre[2],
        ];
        let r2 = dot(v, v);
        if r2 == 0.0 {
            return self.radius_at([0.0, 0.0, 1.0]);
        }
        let r = r2.sqrt();
        self.radius_at([v[0] / r, v[1] / r, v[2] / r]) - r
    }

    /// True when `p` is inside (on the surface counts as inside).
    #[inline]
    pub fn contains(&self, p: [f64; 3]) -> bool {
        let v = [
            p[0] - self.centre[0],
            p[1] - self.centre[1],
            p[2] - self.centre[2],
        ];
        let r2 = dot(v, v);
        let m = self.max_radius();
        if r2 > m * m {
            return false;
        }
        self.depth(p) >= 0.0
    }

    /// The surface point in unit direction `d`.
    pub fn surface_point(&self, d: [f64; 3]) -> [f64; 3] {
        let r = self.radius_at(d);
        [
            self.centre[0] + r * d[0],
            self.centre[1] + r * d[1],
            self.centre[2] + r * d[2],
        ]
    }

    /// Voxel index bounds `[lo, hi)` per axis of the shape's bounding box, clipped to `dims`.
    pub fn voxel_bounds(&self, dims: [usize; 3]) -> [(usize, usize); 3] {
        let m = self.max_radius();
        std::array::from_fn(|a| {
            let lo = (self.centre[a] - m - 0.5).floor().max(0.0) as usize;
            let hi = ((self.centre[a] + m + 0.5).ceil().max(0.0) as usize).min(dims[a]);
            (lo.min(hi), hi)
        })
    }
}

/// `n` nearly uniform unit directions (a Fibonacci sphere), for containment checks.
pub fn sphere_directions(n: usize) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legendre_values_and_bounds() {
        assert_eq!(legendre(2, 1.0), 1.0);
        assert_eq!(legendre(3, -1.0), -1.0);
        assert_eq!(legendre(4, 0.0), 3.0 / 8.0);
        for l in 0..=4 {
            for i in 0..=100 {
                let x = -1.0 + i as f64 / 50.0;
                assert!(legendre(l, x).abs() <= 1.0 + 1e-12);
            }
        }
    }

    #[test]
    fn sphere_and_dent() {
        let mut s = StarShape {
            centre: [5.0; 3],
            radius: 3.0,
            harmonics: vec![],
            dents: vec![],
        };
        assert!(s.contains([7.9, 5.0, 5.0]));
        assert!(!s.contains([8.1, 5.0, 5.0]));
        assert!(s.contains([5.0; 3]));
        s.dents.push(Dent {
            axis: [1.0, 0.0, 0.0],
            depth: 0.5,
            width: 0.1,
        });
        assert!((s.radius_at([1.0, 0.0, 0.0]) - 1.5).abs() < 1e-12);
        assert!(!s.contains([7.0, 5.0, 5.0]));
        assert!(s.contains([3.0, 5.0, 5.0]));
        assert_eq!(s.voxel_bounds([6, 100, 100])[0], (1, 6));
        for d in sphere_directions(50) {
            assert!((dot(d, d) - 1.0).abs() < 1e-12);
        }
    }
}
