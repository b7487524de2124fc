//! Exact distances between the border voxels of two masks.
//!
//! For every border voxel of mask A we need the distance to the nearest border
//! voxel of mask B. That is the Euclidean distance transform of B's border set,
//! sampled at A's border voxels. Two facts keep this cheap:
//!
//! * Both border sets lie in the bounding box of both masks, so the transform is
//!   computed on that box only; the crop is exact, because every candidate
//!   nearest voxel is inside it.
//! * The transform is separable (Felzenszwalb–Huttenlocher, see [`crate::edt`]).
//!   We run the z pass first on whole slabs (integer distances, 2 bytes a voxel),
//!   then, slab by slab in parallel, the y pass into a slab buffer and the final x
//!   pass only on rows that hold border voxels of A, evaluated only at those
//!   voxels. No full-size floating-point array is ever allocated.
use super::border::{BoundingBox, MaskView, is_border};
use super::stats::percentile;
use crate::edt::LowerEnvelope;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Columns gathered together in the strided y pass.
const BLOCK: usize = 32;

/// Distance statistics between the border voxels of a ground truth and a
/// segmentation, in physical units. `None` when either border set is empty.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct SurfaceDistances {
    /// Border voxels of the ground truth.
    pub border_gt: u64,
    /// Border voxels of the segmentation.
    pub border_seg: u64,
    /// Hausdorff distance: the largest distance in either direction.
    pub hd: Option<f64>,
    /// The larger of the two directed 95th percentiles.
    pub hd95: Option<f64>,
    /// The 95th percentile of both directions' distances pooled.
    pub hd95_pooled: Option<f64>,
    /// Average symmetric surface distance: the mean of both directions pooled.
    pub assd: Option<f64>,
    /// Mean of the two directed means.
    pub masd: Option<f64>,
    /// Normalised surface distance (surface Dice): share of border voxels of both
    /// masks within the tolerance of the other border.
    pub nsd: Option<f64>,
    /// Largest distance from a ground-truth border voxel to the segmentation's border.
    pub hd_gt_to_seg: Option<f64>,
    /// Largest distance from a segmentation border voxel to the ground truth's border.
    pub hd_seg_to_gt: Option<f64>,
    /// 95th percentile of the ground truth → segmentation distances.
    pub hd95_gt_to_seg: Option<f64>,
    /// 95th percentile of the segmentation → ground truth distances.
    pub hd95_seg_to_gt: Option<f64>,
    /// Mean ground truth → segmentation distance.
    pub mean_gt_to_seg: Option<f64>,
    /// Mean segmentation → ground truth distance.
    pub mean_seg_to_gt: Option<f64>,
}

/// Integer z distances of the first pass: `u16` for up to 65 534 slices (2 bytes
/// a voxel), `u32` beyond.
trait ZDist: Copy + Send + Sync + Ord {
    const NONE: Self;
    const ZERO: Self;
    fn succ(self) -> Self;
    fn to_f64(self) -> f64;
}

macro_rules! zdist {
    ($t:ty) => {
        impl ZDist for $t {
            const NONE: Self = <$t>::MAX;
            const ZERO: Self = 0;
            #[inline]
            fn succ(self) -> Self {
                if self == Self::NONE { self } else { self + 1 }
            }
            #[inline]
            fn to_f64(self) -> f64 {
                f64::from(self)
            }
        }
    };
}
zdist!(u16);
zdist!(u32);

/// Distances (physical units) from every border voxel of `a` to the nearest
/// border voxel of `b`, in no particular order. `bb` must hold the border voxels
/// of both masks. Every value is `+∞` when `b` has no border voxel.
pub fn directed_distances<A: MaskView, B: MaskView>(
    a: &A,
    b: &B,
    bb: BoundingBox,
    spacing: [f64; 3],
) -> Vec<f64> {
    if bb.dims()[2] < u16::MAX as usize - 1 {
        directed_with::<u16, _, _>(a, b, bb, spacing)
    } else {
        directed_with::<u32, _, _>(a, b, bb, spacing)
    }
}

fn directed_with<Z: ZDist, A: MaskView, B: MaskView>(
    a: &A,
    b: &B,
    bb: BoundingBox,
    spacing: [f64; 3],
) -> Vec<f64> {
    let [cx, cy, cz] = bb.dims();
    let slab = cx * cy;
    if slab * cz == 0 {
        return Vec::new();
    }
    let zd = z_pass::<Z, B>(b, bb);
    let [sx, sy, sz] = spacing;
    let (sx2, sy2) = (sx * sx, sy * sy);
    let per_slab: Vec<Vec<f64>> = zd
        .par_chunks(slab)
        .enumerate()
        .map_init(
            || SlabScratch::new(cx, cy),
            |sc, (k, zs)| {
                // Border voxels of A in this slab, row by row (crop coordinates).
                sc.queries.clear();
                sc.rows.clear();
                for j in 0..cy {
                    let start = sc.queries.len();
                    for i in 0..cx {
                        if is_border(a, bb.lo[0] + i, bb.lo[1] + j, bb.lo[2] + k) {
                            sc.queries.push(i);
                        }
                    }
                    if sc.queries.len() > start {
                        sc.rows.push((j, start, sc.queries.len()));
                    }
                }
                if sc.rows.is_empty() {
                    return Vec::new();
                }
                y_pass(zs, cx, cy, sz, sy2, sc);
                let mut out = Vec::with_capacity(sc.queries.len());
                for &(j, s, e) in &sc.rows {
                    sc.env.build(&sc.g[cx * j..cx * (j + 1)], sx2);
                    sc.env
                        .evaluate_sorted(sc.queries[s..e].iter().copied(), |_, d2| {
                            out.push(d2.sqrt())
                        });
                }
                out
            },
        )
        .collect();
    per_slab.concat()
}

/// Per-thread buffers of the slab passes.
struct SlabScratch {
    queries: Vec<usize>,
    rows: Vec<(usize, usize, usize)>,
    g: Vec<f64>,
    buf: Vec<f64>,
    line: Vec<f64>,
    env: LowerEnvelope,
}

impl SlabScratch {
    fn new(cx: usize, cy: usize) -> Self {
        SlabScratch {
            queries: Vec::new(),
            rows: Vec::new(),
            g: vec![0.0; cx * cy],
            buf: vec![0.0; BLOCK * cy],
            line: vec![0.0; cy],
            env: LowerEnvelope::with_capacity(cx.max(cy)),
        }
    }
}

/// Squared distances within the slab: from the z distances `zs` (`cx * cy`,
/// x-fastest) to `sc.g`, via the lower envelope along y.
fn y_pass<Z: ZDist>(zs: &[Z], cx: usize, cy: usize, sz: f64, sy2: f64, sc: &mut SlabScratch) {
    let SlabScratch {
        g, buf, line, env, ..
    } = sc;
    let mut i0 = 0;
    while i0 < cx {
        let w = BLOCK.min(cx - i0);
        for j in 0..cy {
            let row = &zs[cx * j + i0..cx * j + i0 + w];
            for (c, &z) in row.iter().enumerate() {
                buf[c * cy + j] = if z == Z::NONE {
                    f64::INFINITY
                } else {
                    let d = z.to_f64() * sz;
                    d * d
                };
            }
        }
        for c in 0..w {
            env.build(&buf[c * cy..(c + 1) * cy], sy2);
            env.evaluate_into(line);
            buf[c * cy..(c + 1) * cy].copy_from_slice(line);
        }
        for j in 0..cy {
            let row = &mut g[cx * j + i0..cx * j + i0 + w];
            for (c, v) in row.iter_mut().enumerate() {
                *v = buf[c * cy + j];
            }
        }
        i0 += w;
    }
}

/// For every voxel of the box, the number of slices to the nearest border voxel
/// of `b` in the same (i, j) column (`Z::NONE` when the column has none): a
/// forward and a backward sweep over whole slabs, parallel within each slab.
fn z_pass<Z: ZDist, B: MaskView>(b: &B, bb: BoundingBox) -> Vec<Z> {
    let [cx, cy, cz] = bb.dims();
    let slab = cx * cy;
    let mut zd = vec![Z::NONE; slab * cz];
    for k in 0..cz {
        let (before, rest) = zd.split_at_mut(k * slab);
        let prev = (k > 0).then(|| &before[(k - 1) * slab..]);
        rest[..slab]
            .par_chunks_mut(cx)
            .enumerate()
            .for_each(|(j, row)| {
                for (i, z) in row.iter_mut().enumerate() {
                    *z = if is_border(b, bb.lo[0] + i, bb.lo[1] + j, bb.lo[2] + k) {
                        Z::ZERO
                    } else {
                        prev.map_or(Z::NONE, |p| p[i + cx * j].succ())
                    };
                }
            });
    }
    for k in (0..cz.saturating_sub(1)).rev() {
        let (cur, next) = zd[k * slab..(k + 2) * slab].split_at_mut(slab);
        cur.par_chunks_mut(4096)
            .zip(next.par_chunks(4096))
            .for_each(|(c, n)| {
                for (x, y) in c.iter_mut().zip(n) {
                    let s = y.succ();
                    if s < *x {
                        *x = s;
                    }
                }
            });
    }
    zd
}

/// Summary of one direction's distances.
struct Directed {
    n: usize,
    max: Option<f64>,
    mean: Option<f64>,
    p95: Option<f64>,
    sum: f64,
    within: usize,
}

fn summarise(d: &mut [f64], tol: f64) -> Directed {
    let n = d.len();
    let sum: f64 = d.par_iter().sum();
    let max = d.par_iter().copied().reduce_with(f64::max);
    // Distances equal to the tolerance up to rounding count as within it.
    let limit = tol * (1.0 + 1e-12);
    let within = d.par_iter().filter(|&&x| x <= limit).count();
    Directed {
        n,
        max,
        mean: (n > 0).then(|| sum / n as f64),
        p95: percentile(d, 95.0),
        sum,
        within,
    }
}

/// All border-distance statistics of `seg` against `gt`.
///
/// `bb` is the bounding box of both masks' foreground, or `None` when both are
/// empty. `tolerance` is the NSD tolerance in physical units.
pub fn surface_distances<G: MaskView, S: MaskView>(
    gt: &G,
    seg: &S,
    bb: Option<BoundingBox>,
    spacing: [f64; 3],
    tolerance: f64,
) -> SurfaceDistances {
    let Some(bb) = bb else {
        return SurfaceDistances::default();
    };
    let mut gs = directed_distances(gt, seg, bb, spacing);
    let mut sg = directed_distances(seg, gt, bb, spacing);
    let mut out = SurfaceDistances {
        border_gt: gs.len() as u64,
        border_seg: sg.len() as u64,
        ..SurfaceDistances::default()
    };
    if gs.is_empty() || sg.is_empty() {
        // One border set is empty: every distance is undefined.
        return out;
    }
    let a = summarise(&mut gs, tolerance);
    let b = summarise(&mut sg, tolerance);
    let n = (a.n + b.n) as f64;
    out.hd_gt_to_seg = a.max;
    out.hd_seg_to_gt = b.max;
    out.hd = a.max.zip(b.max).map(|(x, y)| x.max(y));
    out.hd95_gt_to_seg = a.p95;
    out.hd95_seg_to_gt = b.p95;
    out.hd95 = a.p95.zip(b.p95).map(|(x, y)| x.max(y));
    out.mean_gt_to_seg = a.mean;
    out.mean_seg_to_gt = b.mean;
    out.masd = a.mean.zip(b.mean).map(|(x, y)| (x + y) / 2.0);
    out.assd = Some((a.sum + b.sum) / n);
    out.nsd = Some((a.within + b.within) as f64 / n);
    gs.append(&mut sg);
    out.hd95_pooled = percentile(&mut gs, 95.0);
    out
}
