//! Exact distances between the border voxels of two masks.
//!
//! For every border voxel of mask A we need the distance to the nearest border
//! voxel of mask B. That is the Euclidean distance transform of B's border set,
//! sampled at A's border voxels only. Four facts keep this cheap:
//!
//! * Both border sets lie in the bounding box of both masks, so all work is done
//!   on that box; the crop is exact, because every candidate nearest voxel is
//!   inside it.
//! * The border voxels of both masks are found once, in one parallel pass that
//!   stores two bits a voxel; both directions then read those bits.
//! * The transform is separable: a z pass counts, in every column, the slices to
//!   the nearest voxel of B (integers, 2 bytes a voxel, vectorised sweeps; one
//!   array reused by both directions). The squared distance from a voxel to B
//!   is then the least `sx²·Δi² + (sy²·Δj² + (sz·count)²)` over its slab.
//! * Borders being compared are usually close, so that least value is searched
//!   for directly around each border voxel of A: the cells of the slab are
//!   visited from a table sorted by `sx²·Δi² + sy²·Δj²` (`disc.rs`), four
//!   at a time, until that lower bound reaches the best value so far; a few
//!   dozen cells a voxel on dense, close borders. Past the table the search
//!   goes on row by row outward, skipping every cell that cannot beat the best
//!   so far. A slab whose searches grow too long (far-apart borders) runs the
//!   last two passes of the separable transform instead
//!   (Felzenszwalb–Huttenlocher, [`crate::edt`]): envelopes along y evaluated
//!   only on the rows that hold border voxels of A, then along those rows
//!   evaluated only at those voxels. Every way computes the same sums in the
//!   same order (the two searches take the least of the very same values),
//!   and no full-size floating-point array is ever allocated: each slab writes
//!   its distances into its part of one output array.
use super::Metrics;
use super::border::{BoundingBox, MaskView, mark_border_row};
use super::disc::{Disc, GROUP, MAX_CELLS};
use super::stats::{percentile, summarise};
use crate::edt::LowerEnvelope;
use rayon::prelude::*;

/// Positions of a slab that one task of the z pass owns.
const Z_RUN: usize = 512;

/// Columns gathered together (transposed) in the y pass.
const BLOCK: usize = 16;

/// The direct search of a slab gives up after visiting this many times the
/// slab's voxels (far-apart borders); the envelope passes then take over. A
/// visited cell costs about a tenth of a voxel of the envelope passes.
const SEARCH_BUDGET: usize = 8;

/// What a row costs the direct search beyond its cells, in cells.
const ROW_COST: usize = 8;

/// Bit of a ground-truth border voxel in [`BorderFlags`].
const GT_BIT: u8 = 1;
/// Bit of a segmentation border voxel in [`BorderFlags`].
const SEG_BIT: u8 = 2;

/// The border voxels of two masks inside a box: per voxel (x-fastest, box
/// coordinates) bit [`GT_BIT`] for the first mask and [`SEG_BIT`] for the second.
#[derive(Debug, Clone)]
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

/// Integer z distances of the first pass: `i16` for up to 32 765 slices (2
/// bytes a voxel; signed, because x86-64's baseline vector instructions have
/// a signed 16-bit minimum and no unsigned one), `u32` beyond. `u16` serves
/// the tests.
trait ZDist: Copy + Send + Sync + Ord {
    const NONE: Self;
    const ZERO: Self;
    /// One slice further; `NONE` stays `NONE`.
    fn succ(self) -> Self;
    fn index(self) -> usize;
}

macro_rules! zdist {
    ($t:ty) => {
        impl ZDist for $t {
            const NONE: Self = <$t>::MAX;
            const ZERO: Self = 0;
            #[inline]
            fn succ(self) -> Self {
                // NONE is MAX, and real counts stay below MAX - 1.
                self.saturating_add(1)
            }
            #[inline]
            fn index(self) -> usize {
                // Counts are never negative.
                self as usize
            }
        }
    };
}
zdist!(i16);
zdist!(u16);
zdist!(u32);

/// The slice counts of [`z_pass`], kept from one direction to the next (at
/// 512³ a fresh array would cost a quarter of a GiB of page faults).
#[derive(Default)]
struct ZScratch {
    small: Vec<i16>,
    wide: Vec<u32>,
}

/// Distances from the voxels flagged `from` to the nearest voxel flagged `to`,
/// slab by slab, row by row, ascending x. Every value is `+∞` when no voxel is
/// flagged `to`. `zs` keeps the slice counts' memory for the next call.
fn directed_reusing(
    flags: &BorderFlags,
    from: u8,
    to: u8,
    spacing: [f64; 3],
    zs: &mut ZScratch,
) -> Vec<f64> {
    if flags.dims[2] < i16::MAX as usize - 1 {
        directed_in(
            flags,
            [from, to],
            spacing,
            SEARCH_BUDGET,
            MAX_CELLS,
            &mut zs.small,
        )
    } else {
        directed_in(
            flags,
            [from, to],
            spacing,
            SEARCH_BUDGET,
            MAX_CELLS,
            &mut zs.wide,
        )
    }
}

/// [`directed_reusing`] with fresh slice counts.
#[cfg(test)]
fn directed(flags: &BorderFlags, from: u8, to: u8, spacing: [f64; 3]) -> Vec<f64> {
    directed_reusing(flags, from, to, spacing, &mut ZScratch::default())
}

/// [`directed_in`] with fresh slice counts.
#[cfg(test)]
fn directed_with<Z: ZDist>(
    flags: &BorderFlags,
    from: u8,
    to: u8,
    spacing: [f64; 3],
    budget: usize,
) -> Vec<f64> {
    directed_in::<Z>(
        flags,
        [from, to],
        spacing,
        budget,
        MAX_CELLS,
        &mut Vec::new(),
    )
}

/// [`directed_reusing`] from the voxels flagged `from` to those flagged `to`, with
/// slice counts of type `Z` in `zd`, a [`Disc`] of about `disc_cells` cells;
/// the direct search of a slab gives up after `budget` cells per voxel of the
/// slab. Each slab writes its distances into its own part of the output,
/// sized by a first count.
fn directed_in<Z: ZDist>(
    flags: &BorderFlags,
    [from, to]: [u8; 2],
    spacing: [f64; 3],
    budget: usize,
    disc_cells: f64,
    zd: &mut Vec<Z>,
) -> Vec<f64> {
    let [cx, cy, cz] = flags.dims;
    let plane = cx * cy;
    if plane * cz == 0 {
        return Vec::new();
    }
    let counts: Vec<usize> = flags
        .bits
        .par_chunks(plane)
        .map(|s| count_flagged(s, from))
        .collect();
    // Zeroed (not filled) memory: every slab writes its whole part.
    let mut out = vec![0.0; counts.iter().sum()];
    let mut parts = Vec::with_capacity(cz);
    let mut rest = out.as_mut_slice();
    for &n in &counts {
        let (head, tail) = rest.split_at_mut(n);
        parts.push(head);
        rest = tail;
    }
    z_pass::<Z>(flags, to, zd);
    let [sx, sy, sz] = spacing;
    // (sz · slices)² for every count a column can hold, then +∞ for `NONE`.
    let heights: Vec<f64> = (0..cz)
        .map(|z| {
            let d = z as f64 * sz;
            d * d
        })
        .chain([f64::INFINITY])
        .collect();
    let disc = Disc::new(cx, cy, sx * sx, sy * sy, disc_cells);
    parts
        .into_par_iter()
        .zip(flags.bits.par_chunks(plane))
        .zip(zd.par_chunks(plane))
        .filter(|((part, _), _)| !part.is_empty())
        .for_each_init(
            || SlabScratch::new(cx, cy),
            |sc, ((part, fs), zs)| {
                sc.find_queries(fs, cx, from);
                let slab = Slab {
                    zs,
                    cx,
                    cy,
                    heights: &heights,
                    sx2: sx * sx,
                    sy2: sy * sy,
                    inv_sx2: 1.0 / (sx * sx),
                    disc: &disc,
                };
                if !sc.search(&slab, budget.saturating_mul(plane), part) {
                    sc.envelopes(&slab, part);
                }
            },
        );
    out
}

/// Voxels of `bits` with `bit` (one bit) set: `u8` lane counters, flushed
/// before they could overflow, so the loop runs on whole vector registers.
fn count_flagged(bits: &[u8], bit: u8) -> usize {
    const LANES: usize = 32;
    let shift = bit.trailing_zeros();
    let mut n = 0;
    for block in bits.chunks(LANES * 255) {
        let mut lanes = [0u8; LANES];
        let runs = block.chunks_exact(LANES);
        n += runs.remainder().iter().filter(|&&f| f & bit != 0).count();
        for run in runs {
            for (l, &f) in lanes.iter_mut().zip(run) {
                *l += (f >> shift) & 1;
            }
        }
        n += lanes.iter().map(|&l| usize::from(l)).sum::<usize>();
    }
    n
}

/// One slab of the z pass's slice counts and what turns them into squared
/// distances: a flagged voxel at `(i, j)` of count `c` is at
/// `sx²·Δi² + (sy²·Δj² + heights[c])` from a voxel of the slab, the order of
/// the sums of the separable transform (so both ways give the same values).
struct Slab<'a, Z> {
    /// Counts `[j][i]`, x fastest.
    zs: &'a [Z],
    cx: usize,
    cy: usize,
    /// `(sz · count)²` by count, and a last entry `+∞` that stands for `NONE`.
    heights: &'a [f64],
    sx2: f64,
    sy2: f64,
    /// `1 / sx2`, for the search's window widths (which have a step to spare).
    inv_sx2: f64,
    /// The cell offsets the search visits first.
    disc: &'a Disc,
}

impl<Z: ZDist> Slab<'_, Z> {
    /// [`Slab::nearest`] by the cells of the disc, nearest first, a group of
    /// [`GROUP`] at a time (independent of each other, so they overlap in the
    /// processor) while the group's first can beat the best value so far;
    /// past the disc (a value beyond its limit), by [`Slab::nearest`].
    #[inline]
    fn nearest_disc(&self, px: usize, py: usize, budget: &mut usize) -> Option<f64> {
        let at = py * self.cx + px;
        if self.zs[at] == Z::ZERO {
            // The voxel itself is flagged: `heights[0]` is 0, the least of all.
            return Some(self.heights[0]);
        }
        let mut best = f64::INFINITY;
        let last = self.heights.len() - 1;
        let mut visited = 0;
        for group in self.disc.groups() {
            if group[0].lb >= best {
                break;
            }
            visited += GROUP;
            let m = group
                .iter()
                .map(|c| {
                    let i = px.wrapping_add_signed(c.d[0] as isize);
                    let j = py.wrapping_add_signed(c.d[1] as isize);
                    let inside = i < self.cx && j < self.cy;
                    // Outside the slab reads the count of the voxel itself
                    // and maps it to the infinite height.
                    let z = self.zs[if inside {
                        at.wrapping_add_signed(c.lin)
                    } else {
                        at
                    }];
                    let z = if inside { z.index().min(last) } else { last };
                    c.x + (c.fy + self.heights[z])
                })
                .fold(f64::INFINITY, |m, v| if v < m { v } else { m });
            if m < best {
                best = m;
            }
        }
        *budget = budget.checked_sub(visited)?;
        if best > self.disc.limit {
            return self.nearest(px, py, budget);
        }
        Some(best)
    }

    /// The squared distance from voxel `(px, py)` to the nearest flagged voxel:
    /// rows are visited outward from `py` and each row outward from `px`,
    /// skipping every cell whose `sx²·Δi² + sy²·Δj²` alone reaches the best
    /// value so far (rounding is monotone, so a skipped cell cannot be lower).
    /// `None` once more than `budget` cells were visited.
    fn nearest(&self, px: usize, py: usize, budget: &mut usize) -> Option<f64> {
        let mut best = f64::INFINITY;
        // A first bound from the voxel's own column, which the rows narrow.
        for dj in 0..self.cy {
            let fy = self.sy2 * dj as f64 * dj as f64;
            if fy >= best || (dj > py && py + dj >= self.cy) {
                break;
            }
            *budget = budget.checked_sub(1)?;
            for j in [py.checked_sub(dj), Some(py + dj).filter(|&j| j < self.cy)]
                .into_iter()
                .flatten()
            {
                let z = self.zs[j * self.cx + px];
                if z != Z::NONE {
                    let v = fy + self.heights[z.index()];
                    if v < best {
                        best = v;
                    }
                }
            }
        }
        for dj in 0..self.cy {
            let fy = self.sy2 * dj as f64 * dj as f64;
            if fy >= best || (dj > py && py + dj >= self.cy) {
                break;
            }
            let below = py.checked_sub(dj);
            let above = Some(py + dj).filter(|&j| j < self.cy && dj > 0);
            for j in [below, above].into_iter().flatten() {
                let visited = self.scan_row(j, px, fy, &mut best);
                *budget = budget.checked_sub(visited)?;
            }
        }
        Some(best)
    }

    /// The least `sx²·Δi² + (fy + heights[count])` of row `j` into `best`,
    /// over the cells whose `sx²·Δi² + fy` can be below `best` (one more on
    /// each side than the square root says, against rounding). Returns the
    /// number of cells visited.
    #[inline]
    fn scan_row(&self, j: usize, px: usize, fy: f64, best: &mut f64) -> usize {
        // At most `cx` steps; `as` saturates an infinite bound.
        let w = (((*best - fy) * self.inv_sx2).sqrt() as usize).min(self.cx) + 1;
        let lo = px.saturating_sub(w);
        let hi = (px + w + 1).min(self.cx);
        let row = &self.zs[j * self.cx + lo..j * self.cx + hi];
        let last = self.heights.len() - 1;
        let pf = px as f64;
        // Branch-free, so the compiler vectorises it: `NONE` maps to the
        // infinite last entry of `heights`.
        let m = row
            .iter()
            .zip(lo..)
            .map(|(&z, i)| {
                let d = i as f64 - pf;
                self.sx2 * d * d + (fy + self.heights[z.index().min(last)])
            })
            .fold(f64::INFINITY, |m, v| if v < m { v } else { m });
        if m < *best {
            *best = m;
        }
        hi - lo + ROW_COST
    }
}

/// Per-thread buffers of the slab passes.
struct SlabScratch {
    /// x of every query voxel of the slab, row after row.
    queries: Vec<usize>,
    /// Rows holding queries: `(j, start, end)` into `queries`.
    rows: Vec<(usize, usize, usize)>,
    /// Squared y-z distances on the rows of `rows`: `g[r * cx + i]`.
    g: Vec<f64>,
    /// [`BLOCK`] columns of slice counts, each contiguous (as `u32`).
    cols: Vec<u32>,
    env: LowerEnvelope,
}

impl SlabScratch {
    fn new(cx: usize, cy: usize) -> Self {
        SlabScratch {
            queries: Vec::new(),
            rows: Vec::new(),
            g: vec![0.0; cx * cy],
            cols: vec![0; BLOCK * cy],
            env: LowerEnvelope::with_capacity(cx.max(cy)),
        }
    }

    /// The voxels flagged `from` (one bit) in slab `fs` (`[j][i]`), row by
    /// row: eight flags at a time as one word, then its set bits.
    fn find_queries(&mut self, fs: &[u8], cx: usize, from: u8) {
        debug_assert_eq!(from.count_ones(), 1);
        self.queries.clear();
        self.rows.clear();
        let rep = u64::from(from) * 0x0101_0101_0101_0101;
        for (j, row) in fs.chunks_exact(cx).enumerate() {
            let start = self.queries.len();
            for (c, run) in row.chunks(8).enumerate() {
                let mut w = [0u8; 8];
                w[..run.len()].copy_from_slice(run);
                // At most one bit a byte: each step clears one voxel.
                let mut x = u64::from_le_bytes(w) & rep;
                while x != 0 {
                    self.queries.push(c * 8 + x.trailing_zeros() as usize / 8);
                    x &= x - 1;
                }
            }
            if self.queries.len() > start {
                self.rows.push((j, start, self.queries.len()));
            }
        }
    }

    /// Distances at the query voxels into `out` by a direct search around
    /// each of them; false when the searches would visit more than `budget`
    /// cells (far-apart borders): then the envelopes cost less.
    fn search<Z: ZDist>(&self, slab: &Slab<'_, Z>, mut budget: usize, out: &mut [f64]) -> bool {
        let mut o = out.iter_mut();
        for &(j, s, e) in &self.rows {
            for (&p, d) in self.queries[s..e].iter().zip(&mut o) {
                match slab.nearest_disc(p, j, &mut budget) {
                    Some(v) => *d = v.sqrt(),
                    None => return false,
                }
            }
        }
        true
    }

    /// Distances at the query voxels by the last two passes of the separable
    /// transform. The y pass builds the lower envelope of every column and
    /// evaluates it on the query rows only, into `g`; columns are transposed
    /// [`BLOCK`] at a time into `cols`, so that both the reads and the
    /// envelope's input are contiguous. The x pass builds the envelope of every
    /// query row and evaluates it at the query voxels.
    fn envelopes<Z: ZDist>(&mut self, slab: &Slab<'_, Z>, out: &mut [f64]) {
        let SlabScratch {
            queries,
            rows,
            g,
            cols,
            env,
        } = self;
        let Slab {
            zs,
            cx,
            cy,
            heights,
            sx2,
            sy2,
            ..
        } = *slab;
        let none = Z::NONE.index() as u32;
        let mut i0 = 0;
        while i0 < cx {
            let w = BLOCK.min(cx - i0);
            for (j, row) in zs.chunks_exact(cx).enumerate() {
                for (c, &z) in row[i0..i0 + w].iter().enumerate() {
                    cols[c * cy + j] = z.index() as u32;
                }
            }
            for (c, col) in cols.chunks_exact(cy).take(w).enumerate() {
                env.build_from(
                    cy,
                    sy2,
                    col.iter()
                        .enumerate()
                        .filter(|(_, z)| **z != none)
                        .map(|(j, &z)| (j, heights[z as usize])),
                );
                let mut at = i0 + c;
                env.evaluate_sorted(rows.iter().map(|r| r.0), |_, v| {
                    g[at] = v;
                    at += cx;
                });
            }
            i0 += w;
        }
        for (r, &(_, s, e)) in rows.iter().enumerate() {
            env.build(&g[r * cx..(r + 1) * cx], sx2);
            let mut o = out[s..e].iter_mut();
            env.evaluate_sorted(queries[s..e].iter().copied(), |_, d2| {
                if let Some(d) = o.next() {
                    *d = d2.sqrt();
                }
            });
        }
    }
}

/// For every voxel of the box, the number of slices to the nearest voxel
/// flagged `to` in the same (i, j) column (`Z::NONE` when the column has none),
/// in the flags' layout (x fastest). Tasks own the same run of [`Z_RUN`]
/// positions in every slab and sweep it forward then backward along k: whole
/// contiguous runs at a time, which the compiler vectorises.
fn z_pass<Z: ZDist>(flags: &BorderFlags, to: u8, zd: &mut Vec<Z>) {
    let [cx, cy, cz] = flags.dims;
    let plane = cx * cy;
    if zd.len() != plane * cz {
        // Zeroed (not filled) memory: the forward sweep writes every voxel.
        *zd = vec![Z::ZERO; plane * cz];
    }
    let nruns = plane.div_ceil(Z_RUN);
    let mut runs: Vec<Vec<&mut [Z]>> = (0..nruns).map(|_| Vec::with_capacity(cz)).collect();
    for slab in zd.chunks_mut(plane) {
        for (run, part) in runs.iter_mut().zip(slab.chunks_mut(Z_RUN)) {
            run.push(part);
        }
    }
    runs.into_par_iter().enumerate().for_each(|(r, mut parts)| {
        let at = r * Z_RUN;
        for k in 0..cz {
            let (before, rest) = parts.split_at_mut(k);
            let cur = &mut rest[0];
            let fs = &flags.bits[plane * k + at..][..cur.len()];
            match before.last() {
                None => {
                    for (z, &f) in cur.iter_mut().zip(fs) {
                        *z = if f & to != 0 { Z::ZERO } else { Z::NONE };
                    }
                }
                Some(prev) => {
                    for ((z, &f), &p) in cur.iter_mut().zip(fs).zip(prev.iter()) {
                        *z = if f & to != 0 { Z::ZERO } else { p.succ() };
                    }
                }
            }
        }
        for k in (0..cz.saturating_sub(1)).rev() {
            let (cur, next) = parts[k..k + 2].split_at_mut(1);
            for (x, y) in cur[0].iter_mut().zip(next[0].iter()) {
                *x = (*x).min(y.succ());
            }
        }
    });
}

/// The border counts and every border-distance statistic of `gt` and `seg`
/// into `m`, whose other fields (`tolerance` for the NSD) are set.
///
/// `bb` is the bounding box of both masks' foreground, or `None` when both are
/// empty.
pub(super) fn add_distances<G: MaskView, S: MaskView>(
    m: &mut Metrics,
    gt: &G,
    seg: &S,
    bb: Option<BoundingBox>,
    spacing: [f64; 3],
) {
    let Some(bb) = bb else {
        return;
    };
    let flags = BorderFlags::new(gt, seg, bb);
    let mut zs = ZScratch::default();
    let mut gs = directed_reusing(&flags, GT_BIT, SEG_BIT, spacing, &mut zs);
    let mut sg = directed_reusing(&flags, SEG_BIT, GT_BIT, spacing, &mut zs);
    drop(zs);
    m.border_gt = gs.len() as u64;
    m.border_seg = sg.len() as u64;
    if gs.is_empty() || sg.is_empty() {
        // One border set is empty: every distance is undefined.
        return;
    }
    let tol = m.tolerance;
    let (a, b) = rayon::join(|| summarise(&mut gs, tol), || summarise(&mut sg, tol));
    let n = (a.n + b.n) as f64;
    m.hd_gt_to_seg = a.max;
    m.hd_seg_to_gt = b.max;
    m.hd = a.max.zip(b.max).map(|(x, y)| x.max(y));
    m.hd95_gt_to_seg = a.p95;
    m.hd95_seg_to_gt = b.p95;
    m.hd95 = a.p95.zip(b.p95).map(|(x, y)| x.max(y));
    m.mean_gt_to_seg = a.mean;
    m.mean_seg_to_gt = b.mean;
    m.masd = a.mean.zip(b.mean).map(|(x, y)| (x + y) / 2.0);
    m.assd = Some((a.sum + b.sum) / n);
    m.nsd = Some((a.within + b.within) as f64 / n);
    gs.append(&mut sg);
    m.hd95_pooled = percentile(&mut gs, 95.0);
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Distances from every voxel flagged `from` (slab, row, x order) to the
    /// nearest flagged `to`, by trying every pair.
    fn brute(flags: &BorderFlags, from: u8, to: u8, s: [f64; 3]) -> Vec<f64> {
        let [cx, cy, _] = flags.dims;
        let at = |n: usize| [n % cx, (n / cx) % cy, n / (cx * cy)];
        let targets: Vec<[usize; 3]> = (0..flags.bits.len())
            .filter(|&n| flags.bits[n] & to != 0)
            .map(at)
            .collect();
        (0..flags.bits.len())
            .filter(|&n| flags.bits[n] & from != 0)
            .map(|n| {
                let p = at(n);
                targets
                    .iter()
                    .map(|q| {
                        (0..3)
                            .map(|a| ((p[a] as f64 - q[a] as f64) * s[a]).powi(2))
                            .sum::<f64>()
                    })
                    .fold(f64::INFINITY, f64::min)
                    .sqrt()
            })
            .collect()
    }

    /// Random border flags in boxes up to `nx` × `ny` × `nz`, a voxel
    /// flagged with a probability drawn from `density`, and random spacing.
    fn random_flags(
        nx: usize,
        ny: usize,
        nz: usize,
        density: impl Strategy<Value = f64>,
    ) -> impl Strategy<Value = (BorderFlags, [f64; 3])> {
        (
            1usize..nx,
            1usize..ny,
            1usize..nz,
            0.2f64..3.0,
            0.2f64..3.0,
            0.2f64..3.0,
            density,
        )
            .prop_flat_map(|(x, y, z, a, b, c, p)| {
                (
                    Just([x, y, z]),
                    proptest::collection::vec(0u8..4, x * y * z),
                    proptest::collection::vec(proptest::bool::weighted(p), x * y * z),
                    Just([a, b, c]),
                )
            })
            .prop_map(|(dims, bits, keep, s)| {
                let bits = bits
                    .iter()
                    .zip(&keep)
                    .map(|(&b, &k)| if k { b } else { 0 })
                    .collect();
                (BorderFlags { dims, bits }, s)
            })
    }

    /// Small boxes of sparse flags: most voxels carry neither bit.
    fn flags() -> impl Strategy<Value = (BorderFlags, [f64; 3])> {
        random_flags(12, 12, 9, Just(0.15))
    }

    fn same(got: &[f64], want: &[f64]) -> bool {
        got.len() == want.len()
            && got
                .iter()
                .zip(want)
                .all(|(g, w)| g == w || (g - w).abs() <= 1e-12 * w.abs().max(1e-12))
    }

    proptest! {
        /// The direct search, the envelope passes and both count types give
        /// the brute-force distances.
        #[test]
        fn every_way_matches_brute_force((f, s) in flags()) {
            for (from, to) in [(GT_BIT, SEG_BIT), (SEG_BIT, GT_BIT)] {
                let want = brute(&f, from, to, s);
                let search = directed_with::<u16>(&f, from, to, s, usize::MAX);
                let envelopes = directed_with::<u16>(&f, from, to, s, 0);
                let wide = directed_with::<u32>(&f, from, to, s, SEARCH_BUDGET);
                prop_assert!(same(&search, &want), "search {search:?} vs {want:?}");
                prop_assert!(same(&envelopes, &want), "envelopes {envelopes:?} vs {want:?}");
                prop_assert!(same(&wide, &want));
                prop_assert_eq!(&directed(&f, from, to, s), &wide);
            }
        }

        /// Every disc size (down to one cell, when the row search takes over
        /// past the disc) and every count type give the same values, equal
        /// to brute force, on boxes wider than a run of eight flags.
        #[test]
        fn disc_sizes_and_count_types_agree((f, s) in wide_flags(), cells in 0.5f64..60.0) {
            for (from, to) in [(GT_BIT, SEG_BIT), (SEG_BIT, GT_BIT)] {
                let want = brute(&f, from, to, s);
                let full = directed_in::<i16>(&f, [from, to], s, usize::MAX, MAX_CELLS, &mut Vec::new());
                prop_assert!(same(&full, &want), "{full:?} vs {want:?}");
                for z in [directed_in::<i16>(&f, [from, to], s, usize::MAX, cells, &mut Vec::new()),
                          directed_in::<u32>(&f, [from, to], s, usize::MAX, cells, &mut Vec::new()),
                          directed_in::<u16>(&f, [from, to], s, usize::MAX, 1.0, &mut Vec::new())] {
                    prop_assert_eq!(&z, &full);
                }
                // Both directions through one scratch, as `add_distances` runs them.
                let mut zs = ZScratch::default();
                let a = directed_reusing(&f, from, to, s, &mut zs);
                let b = directed_reusing(&f, to, from, s, &mut zs);
                prop_assert_eq!(&a, &full);
                prop_assert_eq!(b, directed_with::<u32>(&f, to, from, s, usize::MAX));
            }
        }
    }

    /// Boxes up to 40 wide and tall, a few slabs, flags of varying density.
    fn wide_flags() -> impl Strategy<Value = (BorderFlags, [f64; 3])> {
        random_flags(40, 40, 5, 0.02..0.5)
    }

    #[test]
    fn flag_counts_cross_their_flush() {
        let bits: Vec<u8> = (0..20_000usize)
            .map(|n| ((n * 7919) % 4) as u8 | u8::from(n < 9000))
            .collect();
        for bit in [GT_BIT, SEG_BIT] {
            let want = bits.iter().filter(|&&b| b & bit != 0).count();
            assert_eq!(count_flagged(&bits, bit), want);
            assert_eq!(
                count_flagged(&bits[..31], bit),
                bits[..31].iter().filter(|&&b| b & bit != 0).count()
            );
        }
    }
}
