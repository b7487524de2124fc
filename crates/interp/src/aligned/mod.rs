//! `shape-aligned`: shape-based interpolation per matched object, aligned
//! before blending, with caps where objects end.
//!
//! For each pair of consecutive drawn slices A and B:
//! 1. The foreground of each slice is split into 8-connected components.
//! 2. Components of A and B are matched: by overlap, then (for those left
//!    without a partner) mutual nearest centroids closer than twice the sum of
//!    their equivalent radii. Matches are closed transitively into groups, so
//!    one component above and two below (a split or merge) form one group.
//! 3. A group present on both sides is interpolated in a frame that moves with
//!    its centroid: on a skipped slice at fraction `t`, with `Δ = c_B − c_A`,
//!    `f(x) = (1 − t) d_A(x − tΔ) + t d_B(x + (1 − t)Δ)`, where `d` are the
//!    group's signed distance maps (physical units, bilinear between pixels),
//!    and the slopes of a monotone cubic in that frame (from the whole
//!    neighbouring drawn slices, assuming the same drift per unit length)
//!    add curvature along the axis. An object that shifts or tilts keeps its
//!    shape instead of being smeared into the overlap of its two positions.
//! 4. A group present on one side only (a nucleolus that ends between drawn
//!    slices, an unmatched branch of a split) is capped by a sphere through
//!    its cross-section (equivalent radius `r`) with its centre `c` past the
//!    drawn slice: the cross-section shrinks (or first widens, for `c > 0`)
//!    by the ratio `ρ(z) / r`, `ρ(z)² = r² + 2cz − z²` (`Cap`), applied to
//!    the signed distance measured from the pixel edges, so that the cap
//!    vanishes where `ρ` does whatever the cross-section's shape. When the
//!    object shows on the previous drawn slice too, the sphere through both
//!    cross-sections (`cap_trend`) gives where the cap ends, and the
//!    cross-section shrinks to that end along a quarter ellipse; for an
//!    object seen on one drawn slice only, `c` comes from the sphere with
//!    the best expected Dice given that both neighbouring drawn slices lack
//!    it (`single_slice_centres`: a cross-section near the object's middle
//!    gives the sphere of radius `r`, one near its pole a longer cap). A cap
//!    never reaches the drawn slice that lacks the object: it ends half a
//!    slice short of it.
//! 5. Beyond the first and last drawn slices, objects on the outermost slice
//!    get the same cap (when [`ShapeAligned::end_caps`] is on), at most one
//!    neighbouring gap long: a slice outside the drawn range is not known to
//!    be empty, and an outermost slice near the pole of an object gives a
//!    short cap by the sphere rule.
//!
//! The crops of the two sides of a blend cover the same region (both groups'
//! boxes, grown by the shift), so a shrinking object is blended with true
//! distances, not with a far value. Drawn-empty slices enter the cubic slopes
//! as in [`crate::sdf::drawn_maps`].
//!
//! The matching, alignment and caps are written here: no crate offers
//! slice-to-slice object correspondence for contour interpolation.
use crate::sdf::{FAR, Map, drawn_maps, signed_distance};
use crate::shape_cubic::{HermiteAt, blend_inside, pchip_slope, slope_bound};
use crate::slices::{Plane, assemble};
use crate::{BoxReach, InterpError, Interpolator, SparseMask};
use interslice_core::Mask;
use interslice_core::morph::{ComponentRuns, Connectivity};
use interslice_core::regions::UnionFind;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

mod cap;
use cap::{Cap, make_cap};

/// Shape-based interpolation of matched, aligned objects with caps.
#[derive(Debug, Clone, Copy)]
pub struct ShapeAligned {
    /// Extrapolate a cap beyond the first and last drawn slices.
    pub end_caps: bool,
}

impl Default for ShapeAligned {
    fn default() -> Self {
        ShapeAligned { end_caps: true }
    }
}

/// One 8-connected component of a drawn slice.
#[derive(Debug, Clone)]
struct Component {
    /// Pixel count.
    area: usize,
    /// Centroid in pixel units (u, v).
    centroid: [f64; 2],
    /// Bounding box `[u0, v0, u1, v1)` in pixels.
    bbox: [usize; 4],
}

/// A drawn slice with its components and whole-slice signed distance.
struct Drawn {
    /// Component id + 1 per pixel (0 = background).
    ids: Vec<u32>,
    comps: Vec<Component>,
    sdf: Map,
}

/// A signed distance map on a rectangular crop of the slice.
struct Crop {
    u0: usize,
    v0: usize,
    w: usize,
    h: usize,
    d: Vec<f32>,
    /// The crop was cut by a side of the slice.
    clipped: bool,
}

impl Crop {
    /// Signed distance of the pixels of `comps` (a group of components),
    /// computed on their bounding box, united with `also` (the partner
    /// group's box, so that both crops of a blend cover the same region),
    /// grown by `margin` pixels.
    fn of_group(
        slice: &Drawn,
        comps: &[usize],
        also: Option<[usize; 4]>,
        margin: usize,
        plane: &Plane,
    ) -> Crop {
        let mut bb = group_bbox(slice, comps);
        if let Some(b) = also {
            bb = [
                bb[0].min(b[0]),
                bb[1].min(b[1]),
                bb[2].max(b[2]),
                bb[3].max(b[3]),
            ];
        }
        let u0 = bb[0].saturating_sub(margin);
        let v0 = bb[1].saturating_sub(margin);
        let u1 = (bb[2] + margin).min(plane.width);
        let v1 = (bb[3] + margin).min(plane.height);
        let (w, h) = (u1 - u0, v1 - v0);
        let clipped = bb[0] < margin
            || bb[1] < margin
            || bb[2] + margin > plane.width
            || bb[3] + margin > plane.height;
        if comps.len() == slice.comps.len() {
            // The group is the whole foreground, and the crop holds it with
            // its ring of background (or the slice's own edge): its distances
            // are the whole slice's, already computed.
            let mut d = Vec::with_capacity(w * h);
            for v in 0..h {
                let row = u0 + plane.width * (v0 + v);
                d.extend_from_slice(&slice.sdf[row..row + w]);
            }
            return Crop {
                u0,
                v0,
                w,
                h,
                d,
                clipped,
            };
        }
        let mut m = vec![false; w * h];
        for v in 0..h {
            for u in 0..w {
                let id = slice.ids[(u0 + u) + plane.width * (v0 + v)];
                m[u + w * v] = id > 0 && comps.contains(&(id as usize - 1));
            }
        }
        let sub = Plane {
            width: w,
            height: h,
            ..*plane
        };
        // The group's pixels are not empty; a crop without background (the
        // group fills the slice) gets the whole-slice rule.
        let d = signed_distance(&m, &sub);
        Crop {
            u0,
            v0,
            w,
            h,
            d,
            clipped,
        }
    }

    /// Row `v` of the full slice, moved by `shift` pixels across the rows,
    /// to sample bilinearly along it ([`CropRow::fill`]): the blend of a
    /// skipped slice reads each crop at one sub-pixel shift, so the vertical
    /// weights and rows are the same for a whole row of pixels. `None`
    /// (every sample far) when the row is outside the crop.
    #[inline]
    fn row(&self, v: usize, shift: f64) -> Option<CropRow<'_>> {
        let (whole, frac) = split_shift(shift);
        // The sample sits at crop row y + frac.
        let y = v as isize - self.v0 as isize + whole;
        let last = self.h as isize - 1;
        if y < 0 || y > last || (y == last && frac > 0.0) {
            return None;
        }
        let y0 = y as usize;
        let y1 = (y0 + 1).min(self.h - 1);
        Some(CropRow {
            r0: &self.d[self.w * y0..self.w * (y0 + 1)],
            r1: &self.d[self.w * y1..self.w * (y1 + 1)],
            fy: frac as f32,
            u0: self.u0,
        })
    }

    /// Deepest inside distance (positive).
    fn depth(&self) -> f32 {
        -self.d.iter().copied().fold(0.0f32, f32::min)
    }
}

/// Two rows of a crop's map and the vertical weight between them.
struct CropRow<'a> {
    r0: &'a [f32],
    r1: &'a [f32],
    fy: f32,
    /// The crop's first column in the full slice.
    u0: usize,
}

impl CropRow<'_> {
    /// Bilinear samples at the columns `u_lo..` of the full slice moved by
    /// `shift` pixels, one per element of `out`; far outside the crop.
    ///
    /// The shift is split into whole pixels and a fraction once, so every
    /// sample has the same weights (and the same ones whatever the slice's
    /// offset in the volume: a label's box computes what the whole volume
    /// does), and the loop over the crop's inner columns is plain
    /// arithmetic on two rows, which the compiler vectorises.
    #[inline]
    fn fill(&self, u_lo: usize, shift: f64, out: &mut [f32]) {
        let (whole, frac) = split_shift(shift);
        let fx = frac as f32;
        let n = out.len() as isize;
        let w = self.r0.len() as isize;
        // Output element i samples crop column j0 + i (+ fx).
        let j0 = u_lo as isize - self.u0 as isize + whole;
        let lo = (-j0).clamp(0, n);
        let hi = (w - 1 - j0).clamp(lo, n);
        let (lo, hi) = (lo as usize, hi as usize);
        out[..lo].fill(FAR);
        if hi > lo {
            let first = (lo as isize + j0) as usize;
            let len = hi - lo;
            let (a, b) = (&self.r0[first..=first + len], &self.r1[first..=first + len]);
            let fy = self.fy;
            for (i, o) in out[lo..hi].iter_mut().enumerate() {
                let top = a[i] * (1.0 - fx) + a[i + 1] * fx;
                let bot = b[i] * (1.0 - fx) + b[i + 1] * fx;
                *o = top * (1.0 - fy) + bot * fy;
            }
        }
        // Past the inner columns: the last column itself when the sample
        // falls on it exactly, far beyond.
        for (i, o) in out.iter_mut().enumerate().skip(hi) {
            let j = i as isize + j0;
            *o = if j == w - 1 && frac == 0.0 {
                let j = j as usize;
                self.r0[j] * (1.0 - self.fy) + self.r1[j] * self.fy
            } else {
                FAR
            };
        }
    }
}

/// A shift in pixels as whole pixels and a fraction in `[0, 1)`.
#[inline]
fn split_shift(shift: f64) -> (isize, f64) {
    let whole = shift.floor();
    (whole as isize, shift - whole)
}

/// Bounding box `[u0, v0, u1, v1)` of a group of components.
fn group_bbox(slice: &Drawn, comps: &[usize]) -> [usize; 4] {
    let mut bb = [usize::MAX, usize::MAX, 0, 0];
    for &c in comps {
        let b = slice.comps[c].bbox;
        bb = [
            bb[0].min(b[0]),
            bb[1].min(b[1]),
            bb[2].max(b[2]),
            bb[3].max(b[3]),
        ];
    }
    bb
}

/// Bilinear sample of a whole-slice map at pixel-index position (pu, pv),
/// clamped to the slice (noted on `fence` when that clamps).
#[inline]
fn sample_full(d: &[f32], plane: &Plane, fence: &Fence, pu: f64, pv: f64) -> f32 {
    fence.note(!on_plane(plane, pu, pv));
    let x = pu.clamp(0.0, (plane.width - 1) as f64);
    let y = pv.clamp(0.0, (plane.height - 1) as f64);
    // Clamped to >= 0: the cast truncates as floor would (no libm call).
    let (x0, y0) = (x as usize, y as usize);
    let (x1, y1) = (
        (x0 + 1).min(plane.width - 1),
        (y0 + 1).min(plane.height - 1),
    );
    let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
    let at = |a: usize, b: usize| d[a + plane.width * b];
    let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
    let bot = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
    top * (1.0 - fy) + bot * fy
}

/// Whether `(pu, pv)` (pixel-index position) lies on the slice.
#[inline]
fn on_plane(plane: &Plane, pu: f64, pv: f64) -> bool {
    pu >= 0.0 && pv >= 0.0 && pu <= (plane.width - 1) as f64 && pv <= (plane.height - 1) as f64
}

/// Records a run on a label's box ([`SparseMask::in_box`]) reading or
/// painting past the slice's sides, which the whole volume would not clamp.
struct Fence {
    /// The sides are a box's (else clamping is the method's rule).
    active: bool,
    crossed: AtomicBool,
}

impl Fence {
    fn new(active: bool) -> Fence {
        Fence {
            active,
            crossed: AtomicBool::new(false),
        }
    }

    /// Note a read or paint past a side when `past` is true.
    #[inline]
    fn note(&self, past: bool) {
        if self.active && past {
            self.crossed.store(true, Ordering::Relaxed);
        }
    }

    fn crossed(&self) -> bool {
        self.crossed.load(Ordering::Relaxed)
    }
}

/// 8-connected components of a row-major mask with their area, centroid
/// and bounding box, summed run by run (the sums are exact integers, so
/// their order does not matter).
fn components(mask: &[bool], w: usize, h: usize) -> (Vec<u32>, Vec<Component>) {
    let runs = ComponentRuns::of(mask, [w, h, 1], Connectivity::Full);
    let mut acc = vec![(0u64, 0u64, 0u64, [usize::MAX, usize::MAX, 0, 0]); runs.count()];
    for (c, v, u0, u1) in runs.runs() {
        let (n, su, sv, bb) = &mut acc[c as usize];
        let len = (u1 - u0) as u64;
        *n += len;
        // u0 + (u0 + 1) + ... + (u1 - 1).
        *su += len * (u0 + u1 - 1) as u64 / 2;
        *sv += len * v as u64;
        *bb = [bb[0].min(u0), bb[1].min(v), bb[2].max(u1), bb[3].max(v + 1)];
    }
    let comps = acc
        .into_iter()
        .map(|(n, su, sv, bbox)| Component {
            area: n as usize,
            centroid: [su as f64 / n as f64, sv as f64 / n as f64],
            bbox,
        })
        .collect();
    (runs.ids(), comps)
}

/// Groups of matched components of A (indices `0..na`) and B (`na..`):
/// `(a_components, b_components)` per group.
fn match_groups(a: &Drawn, b: &Drawn, plane: &Plane) -> Vec<(Vec<usize>, Vec<usize>)> {
    let (na, nb) = (a.comps.len(), b.comps.len());
    let mut uf: UnionFind<usize> = UnionFind::new(na + nb);
    let mut linked = vec![false; na + nb];
    // Overlap. Neighbouring pixels mostly repeat the pair before them; a
    // union is idempotent, so only a change of pair does any work.
    let mut last = (0u32, 0u32);
    for (&x, &y) in a.ids.iter().zip(&b.ids) {
        if x == 0 || y == 0 || (x, y) == last {
            continue;
        }
        last = (x, y);
        let (x, y) = (x as usize - 1, na + y as usize - 1);
        uf.union(x, y);
        linked[x] = true;
        linked[y] = true;
    }
    // Mutual nearest among the unlinked, in physical units.
    let radius = |c: &Component| plane.equivalent_radius(c.area as f64);
    let dist = |p: &Component, q: &Component| {
        ((p.centroid[0] - q.centroid[0]) * plane.spacing[0])
            .hypot((p.centroid[1] - q.centroid[1]) * plane.spacing[1])
    };
    let free_a: Vec<usize> = (0..na).filter(|&i| !linked[i]).collect();
    let free_b: Vec<usize> = (0..nb).filter(|&j| !linked[na + j]).collect();
    let nearest = |from: &Component, cands: &[usize], set: &[Component]| {
        cands
            .iter()
            .copied()
            .min_by(|&x, &y| dist(from, &set[x]).total_cmp(&dist(from, &set[y])))
    };
    for &i in &free_a {
        if let Some(j) = nearest(&a.comps[i], &free_b, &b.comps)
            && nearest(&b.comps[j], &free_a, &a.comps) == Some(i)
            && dist(&a.comps[i], &b.comps[j]) < 2.0 * (radius(&a.comps[i]) + radius(&b.comps[j]))
        {
            uf.union(i, na + j);
        }
    }
    let mut groups: Vec<(usize, Vec<usize>, Vec<usize>)> = Vec::new();
    for x in 0..na + nb {
        let r = uf.find_mut(x);
        let g = match groups.iter().position(|g| g.0 == r) {
            Some(g) => g,
            None => {
                groups.push((r, Vec::new(), Vec::new()));
                groups.len() - 1
            }
        };
        if x < na {
            groups[g].1.push(x);
        } else {
            groups[g].2.push(x - na);
        }
    }
    groups.into_iter().map(|(_, a, b)| (a, b)).collect()
}

/// Area-weighted centroid of a set of components.
fn centroid(slice: &Drawn, comps: &[usize]) -> [f64; 2] {
    let mut s = [0.0, 0.0];
    let mut n = 0.0;
    for &c in comps {
        let k = &slice.comps[c];
        s[0] += k.centroid[0] * k.area as f64;
        s[1] += k.centroid[1] * k.area as f64;
        n += k.area as f64;
    }
    [s[0] / n, s[1] / n]
}

/// How one group fills the slices of one gap.
enum GroupPlan {
    /// Present on both sides: blend aligned distance maps.
    Blend { a: Crop, b: Crop, delta: [f64; 2] },
    /// Present on one side only: a cap on that side (`from_a`).
    Cap {
        d: Crop,
        from_a: bool,
        cap: Cap,
        depth: f32,
    },
}

impl ShapeAligned {
    /// The plans of gap `(A, B)`; `before` is the drawn slice before A and
    /// `after` the one after B, with their physical distances, for the trend
    /// of objects that end inside the gap.
    fn plan_gap(
        &self,
        a: &Drawn,
        b: &Drawn,
        gap: f64,
        before: Option<(&Drawn, f64)>,
        after: Option<(&Drawn, f64)>,
        plane: &Plane,
    ) -> Vec<GroupPlan> {
        let mut plans = Vec::new();
        for (ca, cb) in match_groups(a, b, plane) {
            match (ca.is_empty(), cb.is_empty()) {
                (false, false) => {
                    let (pa, pb) = (centroid(a, &ca), centroid(b, &cb));
                    let delta = [pb[0] - pa[0], pb[1] - pa[1]];
                    let margin = delta[0].abs().max(delta[1].abs()).ceil() as usize + 3;
                    plans.push(GroupPlan::Blend {
                        a: Crop::of_group(a, &ca, Some(group_bbox(b, &cb)), margin, plane),
                        b: Crop::of_group(b, &cb, Some(group_bbox(a, &ca)), margin, plane),
                        delta,
                    });
                }
                (false, true) | (true, false) => {
                    let from_a = !ca.is_empty();
                    let max_len = gap - 0.5 * plane.slice_spacing;
                    let (d, cap, depth) = if from_a {
                        make_cap(a, &ca, gap, max_len, before, plane)
                    } else {
                        make_cap(b, &cb, gap, max_len, after, plane)
                    };
                    plans.push(GroupPlan::Cap {
                        d,
                        from_a,
                        cap,
                        depth,
                    });
                }
                (true, true) => {}
            }
        }
        plans
    }
}

/// Slope of the whole-slice maps through a knot for the aligned cubic.
struct Neighbour<'a> {
    sdf: &'a [f32],
    /// Physical distance to the knot.
    h: f64,
}

impl Interpolator for ShapeAligned {
    fn box_reach(&self) -> BoxReach {
        BoxReach::Drift
    }

    fn name(&self) -> &'static str {
        "shape-aligned"
    }

    fn description(&self) -> &'static str {
        "shape-based per matched object, aligned on centroids, monotone cubic, caps where objects end"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        let plane = Plane::of(&input);
        let drawn = input.drawn;
        let nd = drawn.len();
        // Whole-slice maps (drawn-empty slices coned, see `drawn_maps`) give
        // the cubic slopes; the components give the groups.
        let maps = drawn_maps(&input, &plane, &vec![true; nd])?;
        let slices: Vec<Drawn> = drawn
            .par_iter()
            .zip(maps)
            .map(|(&d, sdf)| {
                let mask = input
                    .mask
                    .slice(input.axis, d)
                    .expect("validated drawn index");
                let (ids, comps) = components(&mask, plane.width, plane.height);
                Drawn {
                    ids,
                    comps,
                    sdf: sdf.expect("every map computed"),
                }
            })
            .collect();
        let ss = plane.slice_spacing;
        let plans: Vec<Vec<GroupPlan>> = (0..nd - 1)
            .into_par_iter()
            .map(|g| {
                if drawn[g + 1] - drawn[g] <= 1 {
                    return Vec::new();
                }
                let gap = (drawn[g + 1] - drawn[g]) as f64 * ss;
                let before =
                    (g > 0).then(|| (&slices[g - 1], (drawn[g] - drawn[g - 1]) as f64 * ss));
                let after = (g + 2 < nd)
                    .then(|| (&slices[g + 2], (drawn[g + 2] - drawn[g + 1]) as f64 * ss));
                self.plan_gap(&slices[g], &slices[g + 1], gap, before, after, &plane)
            })
            .collect();
        // End caps: the outermost drawn slices' objects, over half the gap next to them.
        let end_cap = |which: usize, other: usize| -> Option<(Crop, Cap, f32)> {
            if !self.end_caps || slices[which].comps.is_empty() {
                return None;
            }
            let all: Vec<usize> = (0..slices[which].comps.len()).collect();
            let gap = drawn[which].abs_diff(drawn[other]) as f64 * ss;
            Some(make_cap(
                &slices[which],
                &all,
                gap,
                gap,
                Some((&slices[other], gap)),
                &plane,
            ))
        };
        input.check_cancelled()?;
        let first_cap = end_cap(0, 1);
        let last_cap = end_cap(nd - 1, nd - 2);
        let fence = Fence::new(input.in_box);
        let crops = plans.iter().flatten().flat_map(|p| match p {
            GroupPlan::Blend { a, b, .. } => vec![a, b],
            GroupPlan::Cap { d, .. } => vec![d],
        });
        let caps = [&first_cap, &last_cap].into_iter().flatten().map(|c| &c.0);
        fence.note(crops.chain(caps).any(|c| c.clipped));
        if fence.crossed() {
            return Err(InterpError::OutsideBox);
        }
        let out = assemble(&input, |s| {
            let mut out = vec![false; plane.len()];
            let mut any = false;
            let p = drawn.partition_point(|&d| d < s);
            if p == 0 || p == nd {
                // Outside the drawn range.
                let (cap, z) = if p == 0 {
                    (first_cap.as_ref()?, (drawn[0] - s) as f64 * ss)
                } else {
                    (last_cap.as_ref()?, (s - drawn[nd - 1]) as f64 * ss)
                };
                let (d, cap, depth) = cap;
                let off = cap.offset(z, *depth, half_pixel(&plane))?;
                paint_cap(&mut out, d, off, &plane);
                return Some(out);
            }
            let g = p - 1;
            let (a, b) = (drawn[g], drawn[g + 1]);
            let h = (b - a) as f64 * ss;
            let t = (s - a) as f64 / (b - a) as f64;
            let prev = (g > 0).then(|| Neighbour {
                sdf: &slices[g - 1].sdf,
                h: (a - drawn[g - 1]) as f64 * ss,
            });
            let next = (g + 2 < nd).then(|| Neighbour {
                sdf: &slices[g + 2].sdf,
                h: (drawn[g + 2] - b) as f64 * ss,
            });
            for plan in &plans[g] {
                match plan {
                    GroupPlan::Blend {
                        a: ca,
                        b: cb,
                        delta,
                    } => {
                        any = true;
                        blend(
                            &mut out,
                            BlendArgs {
                                ca,
                                cb,
                                delta: *delta,
                                t,
                                h,
                                prev: prev.as_ref(),
                                next: next.as_ref(),
                                full_a: &slices[g].sdf,
                                full_b: &slices[g + 1].sdf,
                                fence: &fence,
                            },
                            &plane,
                        );
                    }
                    GroupPlan::Cap {
                        d,
                        from_a,
                        cap,
                        depth,
                    } => {
                        let z = if *from_a { t * h } else { (1.0 - t) * h };
                        if let Some(off) = cap.offset(z, *depth, half_pixel(&plane)) {
                            any = true;
                            paint_cap(&mut out, d, off, &plane);
                        }
                    }
                }
            }
            any.then_some(out)
        })?;
        if fence.crossed() {
            return Err(InterpError::OutsideBox);
        }
        Ok(out)
    }
}

/// Half a pixel: the signed distances run between pixel centres, so the
/// boundary of the drawn shape lies about this far past the outermost inside
/// (and before the innermost outside) pixel centre.
fn half_pixel(plane: &Plane) -> f32 {
    (0.25 * (plane.spacing[0] + plane.spacing[1])) as f32
}

/// Paint `e + off < 0` of a cap's crop, `e` the signed distance measured from
/// the pixel edges (`d ± half`): an offset below a pixel then moves the
/// boundary by that much, instead of nothing until it reaches a whole pixel.
fn paint_cap(out: &mut [bool], d: &Crop, off: f32, plane: &Plane) {
    let half = half_pixel(plane);
    for v in 0..d.h {
        for u in 0..d.w {
            let x = d.d[u + d.w * v];
            let e = if x < 0.0 { x + half } else { x - half };
            if e + off < 0.0 {
                out[(d.u0 + u) + plane.width * (d.v0 + v)] = true;
            }
        }
    }
}

struct BlendArgs<'a> {
    ca: &'a Crop,
    cb: &'a Crop,
    delta: [f64; 2],
    t: f64,
    h: f64,
    prev: Option<&'a Neighbour<'a>>,
    next: Option<&'a Neighbour<'a>>,
    full_a: &'a [f32],
    full_b: &'a [f32],
    fence: &'a Fence,
}

/// Paint the aligned blend of one group on one skipped slice.
// Also compiled for AVX2 and chosen at run time: its row loops vectorise
// twice as wide (the results are the same: no fused multiply-add).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn blend<'a>(out: &mut [bool], x: BlendArgs<'a>, plane: &Plane) {
    let BlendArgs {
        ca,
        cb,
        delta,
        t,
        h,
        prev,
        next,
        full_a,
        full_b,
        fence,
    } = x;
    // The moving frame: a point x on the skipped slice sits at x - tΔ on A
    // and x + (1 - t)Δ on B; the drift per unit length is Δ / h.
    let (sa, sb) = (
        [-t * delta[0], -t * delta[1]],
        [(1.0 - t) * delta[0], (1.0 - t) * delta[1]],
    );
    // Region that can be inside: both crops moved onto this slice.
    let lo = [0, 1].map(|i| {
        let c = |k: &Crop| if i == 0 { k.u0 } else { k.v0 };
        (c(ca) as f64 - sa[i]).min(c(cb) as f64 - sb[i]).floor()
    });
    let hi = [0, 1].map(|i| {
        let c = |k: &Crop| if i == 0 { k.u0 + k.w } else { k.v0 + k.h };
        (c(ca) as f64 - sa[i]).max(c(cb) as f64 - sb[i]).ceil()
    });
    fence.note(
        lo[0] < 0.0 || lo[1] < 0.0 || hi[0] > plane.width as f64 || hi[1] > plane.height as f64,
    );
    let (u0, v0) = (lo[0].max(0.0) as usize, lo[1].max(0.0) as usize);
    let u1 = hi[0].min(plane.width as f64) as usize;
    let v1 = hi[1].min(plane.height as f64) as usize;
    let hf = h as f32;
    let basis = HermiteAt::new(
        t as f32,
        [
            slope_bound(hf, prev.map(|n| n.h as f32)),
            slope_bound(hf, next.map(|n| n.h as f32)),
        ],
    );
    let n = u1.saturating_sub(u0);
    let (mut ya_row, mut yb_row) = (vec![FAR; n], vec![FAR; n]);
    let mut open_row = vec![false; n];
    for v in v0..v1 {
        let pv = v as f64;
        let (ra, rb) = (ca.row(v, sa[1]), cb.row(v, sb[1]));
        if ra.is_none() && rb.is_none() {
            // Both far: outside on either side.
            continue;
        }
        for (row, y, shift) in [(&ra, &mut ya_row, sa[0]), (&rb, &mut yb_row, sb[0])] {
            match row {
                Some(r) => r.fill(u0, shift, y),
                None => y.fill(FAR),
            }
        }
        // Where the values decide, the neighbouring slices need not be read:
        // one pass over the row writes those pixels (vector lanes, no
        // branch), a second one visits the rest, if any.
        let row = &mut out[u0 + plane.width * v..u0 + n + plane.width * v];
        let mut any_open = false;
        for (((o, open), &ya), &yb) in row.iter_mut().zip(&mut open_row).zip(&ya_row).zip(&yb_row) {
            let (inside, outside) = basis.sides(ya, yb);
            *o |= inside;
            *open = !(inside | outside);
            any_open |= *open;
        }
        if !any_open {
            continue;
        }
        for (i, (&ya, &yb)) in ya_row.iter().zip(&yb_row).enumerate() {
            if !open_row[i] {
                continue;
            }
            let u = u0 + i;
            let pu = u as f64;
            let sec = (yb - ya) / hf;
            // Slopes from the whole neighbouring slices, sampled where the
            // moving frame would be on them, minus this pair's whole-slice
            // values: the group maps and the whole maps agree near the group.
            let m0 = match prev {
                Some(n) => {
                    let k = n.h / h;
                    let wa = sample_full(full_a, plane, fence, pu + sa[0], pv + sa[1]);
                    let wp = sample_full(
                        n.sdf,
                        plane,
                        fence,
                        pu + sa[0] - k * delta[0],
                        pv + sa[1] - k * delta[1],
                    );
                    pchip_slope((wa - wp) / n.h as f32, sec, n.h as f32, hf)
                }
                None => sec,
            };
            let m1 = match next {
                Some(n) => {
                    let k = n.h / h;
                    let wb = sample_full(full_b, plane, fence, pu + sb[0], pv + sb[1]);
                    let wn = sample_full(
                        n.sdf,
                        plane,
                        fence,
                        pu + sb[0] + k * delta[0],
                        pv + sb[1] + k * delta[1],
                    );
                    pchip_slope(sec, (wn - wb) / n.h as f32, hf, n.h as f32)
                }
                None => sec,
            };
            if blend_inside(basis.value(ya, yb, m0, m1, hf)) {
                out[u + plane.width * v] = true;
            }
        }
    }
}
