//! Caps: how an object's cross-section shrinks past the last drawn slice
//! that shows it (a sphere through that cross-section, or through it and
//! the one behind), for the end of an object inside a gap and at the
//! outermost drawn slices.
use super::{Crop, Drawn, group_bbox};
use crate::slices::Plane;
use std::cell::RefCell;
use std::collections::HashMap;

/// How the cross-section of an object that ends changes past the last drawn
/// slice showing it: the sphere through that cross-section (equivalent
/// radius `r`) whose centre sits `c` past the slice (negative: behind it),
/// `ρ(z)² = r² + 2cz − z²`, vanishing at `c + sqrt(c² + r²)`. When that end
/// lies beyond `len` (the slice known to lack the object is closer), the
/// profile is compressed along the axis to end at `len`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Cap {
    r: f64,
    c: f64,
    /// Where the cap vanishes (physical distance from its drawn slice).
    len: f64,
    /// Axis compression: the profile is evaluated at `z * scale`.
    scale: f64,
    /// Shrink along a quarter ellipse `sqrt(1 − (z / len)²)` to the same end
    /// instead of along the sphere.
    quarter_ellipse: bool,
}

impl Cap {
    /// The sphere cap through radius `r` with centre offset `c`, at most `max_len` long.
    fn new(r: f64, c: f64, max_len: f64) -> Cap {
        let natural = (c + (c * c + r * r).sqrt()).max(0.0);
        let len = natural.min(max_len.max(0.0));
        let scale = if len > 0.0 && natural > len {
            natural / len
        } else {
            1.0
        };
        Cap {
            r,
            c,
            len,
            scale,
            quarter_ellipse: false,
        }
    }

    /// Cross-section radius relative to the drawn one at distance `z`;
    /// `None` once the cap has vanished.
    #[inline]
    fn ratio(&self, z: f64) -> Option<f64> {
        if z >= self.len || self.r <= 0.0 {
            return None;
        }
        if self.quarter_ellipse {
            let q = z / self.len;
            return Some((1.0 - q * q).sqrt());
        }
        let z = z * self.scale;
        let rho2 = self.r * self.r + 2.0 * self.c * z - z * z;
        (rho2 > 0.0).then(|| rho2.sqrt() / self.r)
    }

    /// Largest cross-section radius relative to the drawn one (> 1 when the
    /// sphere's centre lies past the drawn slice).
    fn max_ratio(&self) -> f64 {
        if self.c > 0.0 && self.r > 0.0 && !self.quarter_ellipse {
            (1.0 + (self.c / self.r).powi(2)).sqrt()
        } else {
            1.0
        }
    }

    /// Offset added at distance `z` to the drawn slice's signed distance,
    /// measured from the pixel edges ([`paint_cap`]): the cross-section
    /// scaled by [`Cap::ratio`], as an erosion (or, past 1, a dilation) by
    /// `(depth − half) (1 − ratio)`, `depth − half` the inscribed radius, so
    /// the cap vanishes where the ratio reaches 0 whatever the shape of the
    /// cross-section.
    #[inline]
    pub(super) fn offset(&self, z: f64, depth: f32, half: f32) -> Option<f32> {
        self.ratio(z).map(|q| (depth - half) * (1.0 - q) as f32)
    }
}

/// Sphere centre offsets `(toward, away)` for the cap of an object seen on a
/// single drawn slice, with equivalent radius `r` there and the nearest drawn
/// slices lacking it at distances `toward` (the side being capped) and
/// `away` (the other side).
///
/// The object is modelled as a sphere through the drawn cross-section whose
/// centre lies at an unknown offset `c` from the drawn slice (radius
/// `sqrt(r² + c²)`). The sphere must miss both empty drawn slices:
/// `−cb < c < ca` with `ca = (toward² − r²) / 2 toward` and likewise `cb`;
/// nothing else tells where the slice cut the object, so `c` is taken as
/// uniform over that range. A point at distance `z` on the capped side is
/// then inside with probability `P(c > (ρ² + z² − r²) / 2z)`: the points
/// inside with probability at least `τ` form the sphere through the drawn
/// cross-section centred at the `(1 − τ)`-quantile of `c` (on the other side,
/// at minus the `τ`-quantile). Of these shapes the one with the highest
/// expected Dice against the possible spheres is taken (`τ` below 1/2: Dice
/// rewards covering a likely part more than it punishes a spill). A
/// cross-section through the middle of an object (`r` close to the gap)
/// gives about the sphere of radius `r`; one near a pole reaches farther,
/// towards both empty slices.
pub(super) fn single_slice_centres(r: f64, toward: f64, away: f64) -> (f64, f64) {
    // The search below takes about a million operations, and a fragmented
    // slice (tissue classes, foam) has hundreds of objects seen on one drawn
    // slice, most of a few pixels: equal areas in equal gaps ask the same
    // question. Each thread keeps the answers it gave (exactly these
    // arguments, so the same result), up to `MEMO` of them.
    const MEMO: usize = 4096;
    thread_local! {
        static ANSWERS: RefCell<HashMap<[u64; 3], (f64, f64)>> = RefCell::new(HashMap::new());
    }
    let key = [r.to_bits(), toward.to_bits(), away.to_bits()];
    if let Some(a) = ANSWERS.with(|m| m.borrow().get(&key).copied()) {
        return a;
    }
    let answer = search_centres(r, toward, away);
    ANSWERS.with(|m| {
        let mut m = m.borrow_mut();
        if m.len() >= MEMO {
            m.clear();
        }
        m.insert(key, answer);
    });
    answer
}

/// [`single_slice_centres`], computed.
fn search_centres(r: f64, toward: f64, away: f64) -> (f64, f64) {
    const N: usize = 48;
    const M: usize = 160;
    let bound = |g: f64| ((g * g - r * r) / (2.0 * g)).max(0.0);
    let (ca, cb) = (bound(toward), bound(away));
    if r <= 0.0 || ca + cb <= 1e-9 * (toward + away) {
        return (0.0, 0.0);
    }
    let quantile = |p: f64| -cb + p * (ca + cb);
    let cs: Vec<f64> = (0..N)
        .map(|i| quantile((i as f64 + 0.5) / N as f64))
        .collect();
    let dz = (toward + away) / M as f64;
    let zs: Vec<f64> = (0..M).map(|j| -away + (j as f64 + 0.5) * dz).collect();
    let truth: Vec<Vec<f64>> = cs
        .iter()
        .map(|&c| {
            let r2 = r * r + c * c;
            zs.iter()
                .map(|&z| (r2 - (z - c) * (z - c)).max(0.0))
                .collect()
        })
        .collect();
    let vt: Vec<f64> = truth.iter().map(|t| t.iter().sum()).collect();
    let mut best = (f64::NEG_INFINITY, 0.0, 0.0);
    for s in 1..=25 {
        let tau = s as f64 * 0.02;
        let (at, aa) = (quantile(1.0 - tau), -quantile(tau));
        let est: Vec<f64> = zs
            .iter()
            .map(|&z| {
                let (a, y) = if z > 0.0 { (at, z) } else { (aa, -z) };
                (r * r + 2.0 * a * y - y * y).max(0.0)
            })
            .collect();
        let ve: f64 = est.iter().sum();
        let dice: f64 = truth
            .iter()
            .zip(&vt)
            .map(|(t, &v)| {
                let inter: f64 = t.iter().zip(&est).map(|(a, b)| a.min(*b)).sum();
                2.0 * inter / (v + ve)
            })
            .sum::<f64>()
            / N as f64;
        if dice > best.0 {
            best = (dice, at, aa);
        }
    }
    (best.1, best.2)
}

/// Equivalent radius `sqrt(area / π)` of a set of components, physical units.
pub(super) fn equivalent_radius(slice: &Drawn, comps: &[usize], plane: &Plane) -> f64 {
    let area: usize = comps.iter().map(|&c| slice.comps[c].area).sum();
    plane.equivalent_radius(area as f64)
}

/// The cap of the object `comps` of drawn slice `this`, which the drawn slice
/// `toward` away on the capped side lacks (for an end cap: the distance
/// assumed), the cap at most `max_len` long; `behind` is the drawn slice on
/// the other side with its distance. From the sphere through this cross-section
/// and the one behind ([`cap_trend`]) when the object shows there, else the
/// single-slice model ([`single_slice_centres`]). Returns the cap and the
/// crop of the object's signed distance, grown for a cap that widens.
pub(super) fn make_cap(
    this: &Drawn,
    comps: &[usize],
    toward: f64,
    max_len: f64,
    behind: Option<(&Drawn, f64)>,
    plane: &Plane,
) -> (Crop, Cap, f32) {
    let r = equivalent_radius(this, comps, plane);
    // A sphere that reaches the empty slice contradicts it: its centre is
    // kept where the sphere ends at `toward` at the latest.
    let reach = ((toward * toward - r * r) / (2.0 * toward)).max(0.0);
    let cap = match cap_trend(this, comps, behind, plane) {
        // Two cross-sections fix where the sphere through them ends, not the
        // object's elongation: the cross-section shrinks along a quarter
        // ellipse to that end.
        Some(c) => Cap {
            quarter_ellipse: true,
            ..Cap::new(r, c.min(reach), max_len)
        },
        None => {
            let away = behind.map_or(toward, |(_, h)| h);
            Cap::new(
                r,
                single_slice_centres(r, toward, away).0.min(reach),
                max_len,
            )
        }
    };
    let probe = Crop::of_group(this, comps, None, 2, plane);
    let depth = probe.depth();
    let grow = depth as f64 * (cap.max_ratio() - 1.0) / plane.spacing[0].min(plane.spacing[1]);
    let d = if grow > 0.5 {
        Crop::of_group(this, comps, None, 2 + grow.ceil() as usize, plane)
    } else {
        probe
    };
    (d, cap, depth)
}

/// Where the sphere through an object's cross-sections has its centre,
/// relative to drawn slice `this` (positive: past it, away from `other`):
/// with equivalent radii `r1` on `this` and `r0` on the `other` drawn slice
/// (the components there that overlap it), `h` apart, the sphere
/// `r(z)² = R² − (z − c)²` through both (z = 0 on `this`, `−h` on `other`)
/// has `c = −h/2 − (r0² − r1²) / 2h` — exact for a sphere, a round end
/// otherwise. `None` when the object has no cross-section on `other`.
fn cap_trend(
    this: &Drawn,
    comps: &[usize],
    other: Option<(&Drawn, f64)>,
    plane: &Plane,
) -> Option<f64> {
    let (o, h) = other?;
    let a1: usize = comps.iter().map(|&c| this.comps[c].area).sum();
    let mut hit = vec![false; o.comps.len()];
    // Only the group's box can hold its pixels: a fragmented slice has
    // hundreds of small objects, each capped, and each read the whole slice.
    let [u0, v0, u1, v1] = group_bbox(this, comps);
    for v in v0..v1 {
        let row = plane.width * v;
        for (&x, &y) in this.ids[row + u0..row + u1]
            .iter()
            .zip(&o.ids[row + u0..row + u1])
        {
            if x > 0 && y > 0 && comps.contains(&(x as usize - 1)) {
                hit[y as usize - 1] = true;
            }
        }
    }
    let a0: usize = o
        .comps
        .iter()
        .zip(&hit)
        .filter(|(_, h)| **h)
        .map(|(c, _)| c.area)
        .sum();
    if a0 == 0 || h <= 0.0 {
        return None;
    }
    let px = plane.spacing[0] * plane.spacing[1] / std::f64::consts::PI;
    let (r0, r1) = (a0 as f64 * px, a1 as f64 * px);
    Some(-h / 2.0 - (r0 - r1) / (2.0 * h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cross_section_through_the_middle_gives_about_the_sphere_of_its_radius() {
        // r just short of the gap: the sphere can hardly be off-centre.
        let (t, a) = single_slice_centres(6.0, 7.0, 7.0);
        assert!(t.abs() < 0.3 && a.abs() < 0.3, "{t} {a}");
        let cap = Cap::new(6.0, t, 6.5);
        assert!((cap.len - (t + (t * t + 36.0).sqrt())).abs() < 1e-9);
        assert_eq!(cap.ratio(0.0), Some(1.0));
        assert!(cap.ratio(cap.len).is_none());
    }

    #[test]
    fn a_cross_section_near_a_pole_gives_a_longer_cap_that_misses_the_empty_slices() {
        let (r, g) = (1.0, 7.0);
        let (t, a) = single_slice_centres(r, g, g);
        // Symmetric gaps give a symmetric shape, wider than the slice.
        assert!((t - a).abs() < 1e-9 && t > 0.0, "{t} {a}");
        let cap = Cap::new(r, t, g - 0.5);
        assert!(cap.len > 2.0 * r && cap.len < g, "{}", cap.len);
        assert!(cap.max_ratio() > 1.0);
        // A nearer empty slice on one side pulls the shape to the other.
        let (t2, a2) = single_slice_centres(r, 3.0, g);
        assert!(t2 < a2, "{t2} {a2}");
    }

    #[test]
    fn remembered_answers_are_the_computed_ones() {
        for (r, t, a) in [(1.0, 7.0, 7.0), (0.6, 3.0, 9.0), (1.0, 7.0, 7.0)] {
            let first = single_slice_centres(r, t, a);
            assert_eq!(first, search_centres(r, t, a));
            assert_eq!(single_slice_centres(r, t, a), first);
        }
        // Another gap is another question.
        assert_ne!(
            single_slice_centres(1.0, 7.0, 7.0),
            single_slice_centres(1.0, 3.0, 9.0)
        );
    }

    #[test]
    fn a_sphere_fitted_past_the_empty_slice_is_compressed_to_end_before_it() {
        let cap = Cap::new(3.0, 4.0, 5.0);
        assert!((cap.len - 5.0).abs() < 1e-12);
        assert!(cap.ratio(4.99).is_some() && cap.ratio(5.0).is_none());
    }
}
