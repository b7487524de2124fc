//! Exact distances between the border voxels of two masks.
//!
//! For every border voxel of mask A we need the distance to the nearest border
//! voxel of mask B. That is the Euclidean distance transform of B's border set,
//! sampled at A's border voxels. Three facts keep this cheap:
//!
//! * Both border sets lie in the bounding box of both masks, so the transform is
//!   computed on that box only; the crop is exact, because every candidate
//!   nearest voxel is inside it.
//! * The border voxels of both masks are found once, in one parallel pass that
//!   stores two bits a voxel; both directions then read those bits.
//! * The transform is separable (Felzenszwalb–Huttenlocher, see [`crate::edt`]).
//!   The z pass runs first, in parallel over y rows, on integer slice counts
//!   (2 bytes a voxel). Then, slab by slab in parallel, the y pass builds the
//!   lower envelope of every column but evaluates it only on the rows that hold
//!   border voxels of A, and the x pass runs only on those rows and is evaluated
//!   only at those voxels. No full-size floating-point array is ever allocated.
use super::border::{BoundingBox, MaskView, mark_border_row};
use super::stats::percentile;
use crate::edt::LowerEnvelope;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Columns gathered together in the strided y pass.
const BLOCK: usize = 32;

/// Bit of a ground-truth border voxel in [`BorderFlags`].
const GT_BIT: u8 = 1;
/// Bit of a segmentation border voxel in [`BorderFlags`].
const SEG_BIT: u8 = 2;

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

/// The border voxels of two masks inside a box: per voxel (x-fastest, box
/// coordinates) bit [`GT_BIT`] for the first mask and [`SEG_BIT`] for the second.
struct BorderFlags {
    dims: [usize; 3],
    bits: Vec<u8>,
}

impl BorderFlags {
    /// One parallel pass over the slabs of the box.
    fn new<G: MaskView, S: MaskView>(g: &G, s: &S, bb: BoundingBox) -> BorderFlags {
        let [cx, cy, cz] = bb.dims();
        let mut bits = vec![0u8; cx * cy * cz];
        if !bits.is_empty() {
            bits.par_chunks_mut(cx * cy)
                .enumerate()
                .for_each(|(k, slab)| {
                    let z = bb.lo[2] + k;
                    for (j, row) in slab.chunks_mut(cx).enumerate() {
                        let y = bb.lo[1] + j;
                        mark_border_row(g, y, z, bb.lo[0], row, GT_BIT);
                        mark_border_row(s, y, z, bb.lo[0], row, SEG_BIT);
                    }
                });
        }
        BorderFlags {
            dims: [cx, cy, cz],
            bits,
        }
    }
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
    let flags = BorderFlags::new(a, b, bb);
    directed(&flags, GT_BIT, SEG_BIT, spacing)
}

/// Distances from the voxels flagged `from` to the nearest voxel flagged `to`.
fn directed(flags: &BorderFlags, from: u8, to: u8, spacing: [f64; 3]) -> Vec<f64> {
    if flags.dims[2] < u16::MAX as usize - 1 {
        directed_with::<u16>(flags, from, to, spacing)
    } else {
        directed_with::<u32>(flags, from, to, spacing)
    }
}

fn directed_with<Z: ZDist>(flags: &BorderFlags, from: u8, to: u8, spacing: [f64; 3]) -> Vec<f64> {
    let [cx, cy, cz] = flags.dims;
    let slab = cx * cy;
    if slab * cz == 0 {
        return Vec::new();
    }
    let zd = z_pass::<Z>(flags, to);
    let [sx, sy, sz] = spacing;
    let (sx2, sy2) = (sx * sx, sy * sy);
    let per_slab: Vec<Vec<f64>> = flags
        .bits
        .par_chunks(slab)
        .enumerate()
        .map_init(
            || SlabScratch::new(cx, cy),
            |sc, (k, fs)| {
                // Border voxels of A in this slab, row by row.
                sc.queries.clear();
                sc.rows.clear();
                for (j, row) in fs.chunks(cx).enumerate() {
                    let start = sc.queries.len();
                    sc.queries.extend(
                        row.iter()
                            .enumerate()
                            .filter(|(_, f)| **f & from != 0)
                            .map(|(i, _)| i),
                    );
                    if sc.queries.len() > start {
                        sc.rows.push((j, start, sc.queries.len()));
                    }
                }
                if sc.rows.is_empty() {
                    return Vec::new();
                }
                y_pass(&zd, k, [cx, cy, cz], sz, sy2, sc);
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
    env: LowerEnvelope,
}

impl SlabScratch {
    fn new(cx: usize, cy: usize) -> Self {
        SlabScratch {
            queries: Vec::new(),
            rows: Vec::new(),
            g: vec![0.0; cx * cy],
            buf: vec![0.0; BLOCK * cy],
            env: LowerEnvelope::with_capacity(cx.max(cy)),
        }
    }
}

/// Squared distances within slab `k`, on the rows listed in `sc.rows` only:
/// from the z distances `zd` (layout `[j][k][i]`) into `sc.g` (`[j][i]`), via
/// the lower envelope of every column along y.
fn y_pass<Z: ZDist>(
    zd: &[Z],
    k: usize,
    [cx, cy, cz]: [usize; 3],
    sz: f64,
    sy2: f64,
    sc: &mut SlabScratch,
) {
    let SlabScratch {
        g, buf, env, rows, ..
    } = sc;
    let row_stride = cz * cx;
    let mut i0 = 0;
    while i0 < cx {
        let w = BLOCK.min(cx - i0);
        for j in 0..cy {
            let at = row_stride * j + cx * k + i0;
            for (c, &z) in zd[at..at + w].iter().enumerate() {
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
            let col = i0 + c;
            env.evaluate_sorted(rows.iter().map(|r| r.0), |j, v| g[cx * j + col] = v);
        }
        i0 += w;
    }
}

/// For every voxel of the box, the number of slices to the nearest voxel
/// flagged `to` in the same (i, j) column (`Z::NONE` when the column has none).
/// Layout `[j][k][i]`, so that every y row is one contiguous block and the
/// rows run in parallel: a forward and a backward sweep along k per row.
fn z_pass<Z: ZDist>(flags: &BorderFlags, to: u8) -> Vec<Z> {
    let [cx, cy, cz] = flags.dims;
    let mut zd = vec![Z::NONE; cx * cy * cz];
    zd.par_chunks_mut(cx * cz)
        .enumerate()
        .for_each(|(j, block)| {
            for k in 0..cz {
                let f = &flags.bits[cx * (j + cy * k)..cx * (j + cy * k + 1)];
                let (before, rest) = block.split_at_mut(cx * k);
                let cur = &mut rest[..cx];
                if k == 0 {
                    for (z, &b) in cur.iter_mut().zip(f) {
                        *z = if b & to != 0 { Z::ZERO } else { Z::NONE };
                    }
                } else {
                    let prev = &before[cx * (k - 1)..];
                    for ((z, &b), &p) in cur.iter_mut().zip(f).zip(prev) {
                        *z = if b & to != 0 { Z::ZERO } else { p.succ() };
                    }
                }
            }
            for k in (0..cz.saturating_sub(1)).rev() {
                let (cur, next) = block[cx * k..cx * (k + 2)].split_at_mut(cx);
                for (x, y) in cur.iter_mut().zip(next.iter()) {
                    let s = y.succ();
                    if s < *x {
                        *x = s;
                    }
                }
            }
        });
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
    let flags = BorderFlags::new(gt, seg, bb);
    let mut gs = directed(&flags, GT_BIT, SEG_BIT, spacing);
    let mut sg = directed(&flags, SEG_BIT, GT_BIT, spacing);
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
