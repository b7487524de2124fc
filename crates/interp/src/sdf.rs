//! Signed distance maps of drawn slices, the common ground of the shape-based
//! methods (Raya & Udupa 1990; Herman et al. 1992).
use crate::slices::Plane;
use crate::{InterpError, SparseMask};
use interslice_core::edt::signed_edt_2d_f32;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

/// Signed distance of every pixel of a row-major slice, in physical units:
/// negative inside (minus the distance to the nearest background pixel
/// centre), positive outside (the distance to the nearest foreground pixel
/// centre). `sdf < 0` is exactly the mask, so drawn slices are reproduced.
///
/// A slice without foreground gets `empty_value()` everywhere (a finite
/// "far outside", so that blending stays arithmetic), and a slice without
/// background gets its negative.
pub fn signed_distance(mask: &[bool], plane: &Plane) -> Vec<f32> {
    let far = empty_value(plane);
    if !mask.iter().any(|&m| m) {
        return vec![far; mask.len()];
    }
    if mask.iter().all(|&m| m) {
        return vec![-far; mask.len()];
    }
    signed_edt_2d_f32(mask, plane.width, plane.height, plane.spacing)
}

/// The signed distance maps of a label's drawn slices, computed once and
/// read by every run over those slices.
///
/// `shape-auto` runs each candidate twice on the compact stack of the drawn
/// slices (leave-one-out, [`crate::loo`]) and once more on the label: every
/// run sees the same drawn slices (a compact slice *is* a drawn slice), and
/// their two distance transforms are most of a shape method's work. The
/// maps are keyed by the slice's content and plane, so that a run on any
/// stack of those slices finds them; a slice not in the cache (a group's
/// crop, a predicted slice) is computed as before. A map is shared, not
/// copied, by every run that reads it.
#[derive(Default)]
pub struct SdfCache {
    maps: HashMap<SliceKey, Map>,
}

impl std::fmt::Debug for SdfCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "SdfCache({} maps)", self.maps.len())
    }
}

/// A signed distance map of a slice, shared by the runs that read it.
pub type Map = Arc<[f32]>;

/// A slice's pixels (one bit each) and its plane.
#[derive(PartialEq, Eq, Hash)]
struct SliceKey {
    width: usize,
    height: usize,
    spacing: [u64; 2],
    bits: Vec<u64>,
}

impl SliceKey {
    fn of(mask: &[bool], plane: &Plane) -> SliceKey {
        SliceKey {
            width: plane.width,
            height: plane.height,
            spacing: plane.spacing.map(f64::to_bits),
            bits: mask
                .chunks(64)
                .map(|c| c.iter().rev().fold(0u64, |w, &b| (w << 1) | u64::from(b)))
                .collect(),
        }
    }
}

impl SdfCache {
    /// The maps of every drawn slice of `input`, computed in parallel.
    pub fn of_drawn(input: &SparseMask<'_>) -> Result<SdfCache, InterpError> {
        let plane = Plane::of(input);
        let maps = input
            .drawn
            .par_iter()
            .map(|&d| {
                let m = input.mask.slice(input.axis, d)?;
                let map = Map::from(signed_distance(&m, &plane));
                Ok((SliceKey::of(&m, &plane), map))
            })
            .collect::<Result<HashMap<_, _>, InterpError>>()?;
        Ok(SdfCache { maps })
    }

    /// `run` on `input` with its drawn slices' maps, computed here once
    /// unless the caller passed them: for a method whose stages (leave-one-out
    /// runs, then the final one) read the same drawn slices.
    pub fn sharing<T>(
        input: SparseMask<'_>,
        run: impl FnOnce(SparseMask<'_>) -> Result<T, InterpError>,
    ) -> Result<T, InterpError> {
        if input.maps.is_some() {
            return run(input);
        }
        let cache = SdfCache::of_drawn(&input)?;
        run(input.with_maps(&cache))
    }

    /// The map of `mask`, from the cache when it holds it.
    pub fn signed_distance(cache: Option<&SdfCache>, mask: &[bool], plane: &Plane) -> Map {
        cache
            .and_then(|c| c.maps.get(&SliceKey::of(mask, plane)))
            .map_or_else(|| Map::from(signed_distance(mask, plane)), Arc::clone)
    }
}

/// "No object near": the value of the drawn-empty slices that have no
/// non-empty drawn neighbour in the blends and slopes of the shape methods,
/// and of a group's map past its crop. Finite, so the arithmetic stays
/// defined (no `∞ − ∞`, no `0 · ∞`), and independent of the slice's size, so
/// that a label's box ([`crate::crop`]) computes what the whole volume does;
/// this far out, PCHIP's slope next to such a slice has reached its limit.
pub const FAR: f32 = 1.0e20;

/// The distance used for "no object on this slice": the slice's diagonal,
/// farther than any pixel can be from an object on the slice.
pub fn empty_value(plane: &Plane) -> f32 {
    let a = plane.width as f64 * plane.spacing[0];
    let b = plane.height as f64 * plane.spacing[1];
    (a.hypot(b) + plane.spacing[0] + plane.spacing[1]) as f32
}

/// Signed distance maps of the drawn slices of `input`, computed where
/// `needed[i]` is true (`None` elsewhere), with drawn-empty slices handled.
///
/// A drawn slice without foreground is not "infinitely far" from the objects
/// of its neighbours: blending with a constant far value would cut every
/// object off right after the last slice that shows it. Instead an empty
/// drawn slice gets, per pixel, the smallest of `d_N + depth_N` over its
/// non-empty drawn neighbours `N` (the previous and next drawn slices), where
/// `depth_N` is the deepest inside distance of `N`. That map is `>= 0`
/// everywhere (the empty slice stays empty, `< 0` is never true on it) and
/// touches 0 at the deepest point of the neighbour, so a linear blend erodes
/// the object to a point on the empty slice: a cone, not a cut. An empty
/// slice without non-empty neighbours gets [`FAR`].
pub fn drawn_maps(
    input: &SparseMask<'_>,
    plane: &Plane,
    needed: &[bool],
) -> Result<Vec<Option<Map>>, InterpError> {
    let d = input.drawn;
    let n = d.len();
    let masks: Vec<Option<Vec<bool>>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let wanted = needed[i] || (i > 0 && needed[i - 1]) || (i + 1 < n && needed[i + 1]);
            wanted.then(|| {
                input
                    .mask
                    .slice(input.axis, d[i])
                    .expect("validated drawn index")
            })
        })
        .collect();
    let empty: Vec<bool> = masks
        .iter()
        .map(|m| m.as_ref().is_some_and(|m| !m.iter().any(|&x| x)))
        .collect();
    // Non-empty slices whose map is needed themselves or by an empty neighbour.
    let compute: Vec<bool> = (0..n)
        .map(|i| {
            masks[i].is_some()
                && !empty[i]
                && (needed[i]
                    || (i > 0 && needed[i - 1] && empty[i - 1])
                    || (i + 1 < n && needed[i + 1] && empty[i + 1]))
        })
        .collect();
    let sdfs: Vec<Option<Map>> = (0..n)
        .into_par_iter()
        .map(|i| {
            // A cancelled run skips the rest of its transforms.
            (compute[i] && !input.is_cancelled()).then(|| {
                SdfCache::signed_distance(input.maps, masks[i].as_ref().expect("read"), plane)
            })
        })
        .collect();
    input.check_cancelled()?;
    let depth = |m: &[f32]| -m.iter().copied().fold(0.0f32, f32::min);
    Ok((0..n)
        .into_par_iter()
        .map(|i| {
            if !needed[i] {
                return None;
            }
            if !empty[i] {
                return sdfs[i].clone();
            }
            let neighbours: Vec<&Map> = [i.checked_sub(1), (i + 1 < n).then_some(i + 1)]
                .into_iter()
                .flatten()
                .filter_map(|j| sdfs[j].as_ref().filter(|_| !empty[j]))
                .collect();
            if neighbours.is_empty() {
                return Some(Map::from(vec![FAR; plane.len()]));
            }
            let mut out = vec![FAR; plane.len()];
            for m in neighbours {
                let r = depth(m);
                for (o, &x) in out.iter_mut().zip(m.iter()) {
                    *o = o.min(x + r);
                }
            }
            Some(Map::from(out))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Against the definition: minus the distance to the nearest
        /// background pixel inside, the distance to the nearest foreground
        /// pixel outside (pixel centres, physical units), so the inside
        /// transform on the foreground's box is the whole slice's.
        #[test]
        fn signed_distance_is_the_distance_to_the_other_side(
            w in 1usize..12,
            h in 1usize..12,
            bits in any::<u128>(),
            sparse in any::<bool>(),
            su in 0.3f64..2.0,
            sv in 0.3f64..2.0,
        ) {
            let mask: Vec<bool> = (0..w * h)
                .map(|i| {
                    let b = bits >> (i % 128) & 1 == 1;
                    if sparse { b && bits >> ((i * 7 + 3) % 128) & 1 == 1 } else { b }
                })
                .collect();
            let plane = Plane { width: w, height: h, spacing: [su, sv], slice_spacing: 1.0 };
            let got = signed_distance(&mask, &plane);
            let far = empty_value(&plane);
            for p in 0..w * h {
                let (u, v) = ((p % w) as f64, (p / w) as f64);
                let nearest = (0..w * h)
                    .filter(|&q| mask[q] != mask[p])
                    .map(|q| {
                        let (x, y) = ((q % w) as f64, (q / w) as f64);
                        ((x - u) * su).hypot((y - v) * sv)
                    })
                    .fold(f64::INFINITY, f64::min);
                let want = match (nearest.is_finite(), mask[p]) {
                    (true, true) => -nearest,
                    (true, false) => nearest,
                    (false, true) => -f64::from(far),
                    (false, false) => f64::from(far),
                };
                prop_assert!((f64::from(got[p]) - want).abs() <= 1e-4 * want.abs().max(1.0),
                    "pixel {p}: {} vs {want}", got[p]);
            }
        }
    }
}
