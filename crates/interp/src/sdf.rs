//! Signed distance maps of drawn slices, the common ground of the shape-based
//! methods (Raya & Udupa 1990; Herman et al. 1992).
use crate::slices::Plane;
use interslice_core::edt::squared_edt_2d_f32;

/// Signed distance of every pixel of a row-major slice, in physical units:
/// negative inside (minus the distance to the nearest background pixel
/// centre), positive outside (the distance to the nearest foreground pixel
/// centre). `sdf < 0` is exactly the mask, so drawn slices are reproduced.
///
/// A slice without foreground gets `empty_value()` everywhere (a finite
/// "far outside", so that blending stays arithmetic), and a slice without
/// background gets its negative.
pub fn signed_distance(mask: &[bool], plane: &Plane) -> Vec<f32> {
    let any_fg = mask.iter().any(|&m| m);
    let any_bg = mask.iter().any(|&m| !m);
    let far = empty_value(plane);
    if !any_fg {
        return vec![far; mask.len()];
    }
    if !any_bg {
        return vec![-far; mask.len()];
    }
    let (w, h) = (plane.width, plane.height);
    let (outside, inside) = rayon::join(
        || squared_edt_2d_f32(mask, w, h, plane.spacing),
        || {
            let bg: Vec<bool> = mask.iter().map(|&m| !m).collect();
            squared_edt_2d_f32(&bg, w, h, plane.spacing)
        },
    );
    mask.iter()
        .zip(outside.iter().zip(&inside))
        .map(|(&m, (&o, &i))| if m { -i.sqrt() } else { o.sqrt() })
        .collect()
}

/// The distance used for "no object on this slice": the slice's diagonal,
/// farther than any pixel can be from an object on the slice.
pub fn empty_value(plane: &Plane) -> f32 {
    let a = plane.width as f64 * plane.spacing[0];
    let b = plane.height as f64 * plane.spacing[1];
    (a.hypot(b) + plane.spacing[0] + plane.spacing[1]) as f32
}
