//! Shapes and measures shared by the interpolation tests.
use interslice_core::{Axis, Geometry, LengthUnit, Mask, Volume};
use interslice_interp::{InterpError, Interpolator, SparseMask};

/// A mask from an implicit shape in physical coordinates of voxel centres.
pub fn shape(dims: [usize; 3], spacing: [f64; 3], inside: impl Fn([f64; 3]) -> bool) -> Mask {
    let g = Geometry::new(dims, spacing, LengthUnit::Micrometre).unwrap();
    let mut m: Mask = Volume::zeros(g);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = [
                    (i as f64 + 0.5) * spacing[0],
                    (j as f64 + 0.5) * spacing[1],
                    (k as f64 + 0.5) * spacing[2],
                ];
                m.set(i, j, k, inside(p));
            }
        }
    }
    m
}

/// Whether `p` is inside the axis-aligned ellipsoid of centre `c` and radii `r`.
pub fn in_ellipsoid(p: [f64; 3], c: [f64; 3], r: [f64; 3]) -> bool {
    (0..3).map(|d| ((p[d] - c[d]) / r[d]).powi(2)).sum::<f64>() <= 1.0
}

/// Keep only the drawn slices of `full` along `axis`.
pub fn sparse(full: &Mask, axis: Axis, drawn: &[usize]) -> Mask {
    let mut m: Mask = Volume::zeros(full.geometry().clone());
    for &d in drawn {
        m.set_slice(axis, d, &full.slice(axis, d).unwrap()).unwrap();
    }
    m
}

/// Every `step`-th slice from 0, plus the last one.
pub fn every(n: usize, step: usize) -> Vec<usize> {
    let mut d: Vec<usize> = (0..n).step_by(step).collect();
    if *d.last().unwrap() != n - 1 {
        d.push(n - 1);
    }
    d
}

/// Dice of two masks of the same grid.
pub fn dice(a: &Mask, b: &Mask) -> f64 {
    let (mut tp, mut na, mut nb) = (0usize, 0usize, 0usize);
    for (&x, &y) in a.data().iter().zip(b.data()) {
        tp += (x && y) as usize;
        na += x as usize;
        nb += y as usize;
    }
    2.0 * tp as f64 / (na + nb) as f64
}

/// A method as it is, but never run on its label's box
/// (`interslice_interp::crop`): what a boxed run is compared with.
pub struct Unboxed(pub Box<dyn Interpolator>);

impl Interpolator for Unboxed {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn description(&self) -> &'static str {
        self.0.description()
    }
    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        self.0.interpolate(input)
    }
    fn interpolate_with_confidence(
        &self,
        input: SparseMask<'_>,
    ) -> Result<(Mask, Volume<f32>), InterpError> {
        self.0.interpolate_with_confidence(input)
    }
}
