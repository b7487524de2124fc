//! Exact squared Euclidean distance transform (EDT) on anisotropic grids.
//!
//! The transform is separable: one pass finds, along every line of one axis,
//! the distance to the nearest feature pixel of that line; each further pass
//! takes the lower envelope of parabolas `s²·(p − q)² + f(q)` along the lines
//! of the next axis, which is the algorithm of Felzenszwalb & Huttenlocher,
//! "Distance Transforms of Sampled Functions" (Theory of Computing, 2012). The
//! result is exact: every value is `Σ (s_a · Δ_a)²` for the nearest feature
//! pixel, not an approximation such as a chamfer distance.
//!
//! Written here rather than taken from a crate because no maintained Rust crate
//! offers an exact, anisotropic, parallel 3D transform; the algorithm is short and
//! is checked against brute force by property tests.
//!
//! In 3D (first along x, then y, then z) every pass runs in parallel over lines
//! with rayon; lines that are strided in memory (y and z) are processed in
//! blocks of adjacent columns so that reads and writes touch contiguous runs of
//! memory. A 2D transform runs on the calling thread ([`squared_edt_2d_as`]).
//!
//! Values are in physical units² (spacing²). A pixel with no feature anywhere gets
//! `f64::INFINITY`. The `_f32` variants store the result as `f32` (half the memory
//! at 512³; relative error below 1e-6, since every line is computed in `f64` and
//! only stored in `f32` between passes).
use rayon::prelude::*;

/// Number of adjacent columns handled together in a strided pass.
const BLOCK: usize = 32;

/// Storage type of a transform: `f64` (exact) or `f32` (half the memory).
pub trait EdtValue: Copy + Send + Sync + 'static {
    /// Convert from the `f64` computed along a line.
    fn from_f64(x: f64) -> Self;
    /// Convert to `f64` for the next pass.
    fn to_f64(self) -> f64;
}

impl EdtValue for f64 {
    #[inline]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
}

impl EdtValue for f32 {
    #[inline]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

/// Squared Euclidean distance (physical units²) from every pixel to the nearest
/// `true` pixel; `f64::INFINITY` when there is none.
///
/// `features` is row-major, `features[u + width * v]`; `spacing` is `[su, sv]`.
///
/// # Panics
/// If `features.len() != width * height` (a programming error).
pub fn squared_edt_2d(
    features: &[bool],
    width: usize,
    height: usize,
    spacing: [f64; 2],
) -> Vec<f64> {
    squared_edt_2d_as::<f64>(features, width, height, spacing)
}

/// [`squared_edt_2d`] stored as `f32`.
pub fn squared_edt_2d_f32(
    features: &[bool],
    width: usize,
    height: usize,
    spacing: [f64; 2],
) -> Vec<f32> {
    squared_edt_2d_as::<f32>(features, width, height, spacing)
}

/// Squared Euclidean distance (physical units²) from every voxel to the nearest
/// `true` voxel; `f64::INFINITY` when there is none.
///
/// `features` is x-fastest, `features[i + nx * (j + ny * k)]`; `spacing` is
/// `[sx, sy, sz]`.
///
/// # Panics
/// If `features.len()` is not `nx * ny * nz` (a programming error).
pub fn squared_edt_3d(features: &[bool], dims: [usize; 3], spacing: [f64; 3]) -> Vec<f64> {
    squared_edt_3d_as::<f64>(features, dims, spacing)
}

/// [`squared_edt_3d`] stored as `f32`: half the memory (512 MiB instead of 1 GiB
/// at 512³).
pub fn squared_edt_3d_f32(features: &[bool], dims: [usize; 3], spacing: [f64; 3]) -> Vec<f32> {
    squared_edt_3d_as::<f32>(features, dims, spacing)
}

/// A column distance (in pixels) of the 2D transforms where the column holds
/// nothing to measure to.
const NONE: u32 = u32::MAX;

/// Generic 2D transform, on the calling thread.
///
/// Slices are transformed many at a time by callers that already run in
/// parallel over slices (the shape interpolators), and one slice of a few
/// hundred pixels a side is too little work to split between threads. So
/// the order of the passes is chosen for one thread: first, per column, the
/// pixel distance to the nearest feature of the column (two sweeps over the
/// rows that run along whole rows at once), then the lower envelope along
/// each row, which is contiguous in memory: no gathering of strided columns.
// Also compiled for AVX2 and chosen at run time: its row loops vectorise
// twice as wide (the results are the same: no fused multiply-add).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn squared_edt_2d_as<S: EdtValue>(
    features: &[bool],
    width: usize,
    height: usize,
    spacing: [f64; 2],
) -> Vec<S> {
    assert_eq!(
        features.len(),
        width * height,
        "features length must be width * height"
    );
    let mut out = vec![S::from_f64(f64::INFINITY); features.len()];
    if width == 0 || height == 0 {
        return out;
    }
    // Pixels to the nearest feature of the column; NONE when there is none.
    let mut g = vec![NONE; features.len()];
    for v in 0..height {
        let row = v * width;
        let (done, rest) = g.split_at_mut(row);
        let cur = &mut rest[..width];
        let f = &features[row..row + width];
        if v == 0 {
            for (c, &x) in cur.iter_mut().zip(f) {
                *c = if x { 0 } else { NONE };
            }
        } else {
            let prev = &done[row - width..];
            for ((c, &x), &p) in cur.iter_mut().zip(f).zip(prev) {
                *c = if x { 0 } else { p.saturating_add(1) };
            }
        }
    }
    for v in (0..height.saturating_sub(1)).rev() {
        let row = v * width;
        let (cur, below) = g[row..].split_at_mut(width);
        for (c, &b) in cur.iter_mut().zip(&below[..width]) {
            *c = (*c).min(b.saturating_add(1));
        }
    }
    let (su2, sv2) = (spacing[0] * spacing[0], spacing[1] * spacing[1]);
    let mut env = LowerEnvelope::with_capacity(width);
    for (grow, orow) in g.chunks(width).zip(out.chunks_mut(width)) {
        env.build_from(
            width,
            su2,
            grow.iter()
                .enumerate()
                .filter(|(_, d)| **d != NONE)
                .map(|(q, &d)| {
                    let d = f64::from(d);
                    (q, d * d * sv2)
                }),
        );
        // A feature pixel is at distance 0: only the others read the envelope.
        for (o, &d) in orow.iter_mut().zip(grow) {
            if d == 0 {
                *o = S::from_f64(0.0);
            }
        }
        env.evaluate_sorted((0..width).filter(|&p| grow[p] != 0), |p, x| {
            orow[p] = S::from_f64(x)
        });
    }
    out
}

/// Signed Euclidean distance (physical units) of a binary slice: on a `true`
/// pixel minus the distance to the nearest `false` pixel, on a `false` pixel
/// the distance to the nearest `true` one, so that `d < 0` is exactly the
/// mask. Infinite where the other class is absent from the slice (callers
/// that need finite values treat empty and full slices themselves).
///
/// Each value equals the square root of [`squared_edt_2d_f32`]'s on the
/// mask (for `false` pixels) or on its complement (for `true` pixels), but
/// the two transforms share their work:
/// - one pass along the columns finds, for every pixel, the distance to the
///   nearest pixel *of the other class* in its column, which is the column
///   distance each transform reads at the pixels it does not take as
///   features;
/// - along each row, the envelope of the distance to one class holds that
///   class's runs by their two ends only (from a run of feature pixels, the
///   nearest to any pixel outside it is one of its ends) and is evaluated
///   on the other class's runs only.
///
/// So every pixel is read once by one envelope instead of by two.
///
/// # Panics
/// If `mask.len() != width * height` (a programming error).
// Also compiled for AVX2 and chosen at run time (the results are the same:
// no fused multiply-add).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub fn signed_edt_2d_f32(
    mask: &[bool],
    width: usize,
    height: usize,
    spacing: [f64; 2],
) -> Vec<f32> {
    assert_eq!(
        mask.len(),
        width * height,
        "mask length must be width * height"
    );
    let mut out = vec![f32::INFINITY; mask.len()];
    if width == 0 || height == 0 {
        return out;
    }
    // Pixels to the nearest pixel of the other class in the column; NONE
    // when there is none. Down the rows (the other class above), then up.
    let mut g = vec![NONE; mask.len()];
    for v in 1..height {
        let row = v * width;
        let (done, rest) = g.split_at_mut(row);
        let above = &done[row - width..];
        let (m_above, m_cur) = (&mask[row - width..row], &mask[row..row + width]);
        for (((c, &p), &a), &b) in rest[..width].iter_mut().zip(above).zip(m_above).zip(m_cur) {
            *c = if a != b { 1 } else { p.saturating_add(1) };
        }
    }
    for v in (0..height - 1).rev() {
        let row = v * width;
        let (cur, below) = g[row..].split_at_mut(width);
        let (m_cur, m_below) = (&mask[row..row + width], &mask[row + width..row + 2 * width]);
        for (((c, &b), &x), &y) in cur.iter_mut().zip(&below[..width]).zip(m_cur).zip(m_below) {
            let down = if x != y { 1 } else { b.saturating_add(1) };
            *c = (*c).min(down);
        }
    }
    let (su2, sv2) = (spacing[0] * spacing[0], spacing[1] * spacing[1]);
    let mut to_true = LowerEnvelope::with_capacity(width);
    let mut to_false = LowerEnvelope::with_capacity(width);
    // Runs of one class along the row: `[a, b)` and the class.
    let mut runs: Vec<(usize, usize, bool)> = Vec::new();
    // The samples of the envelopes of the distance to `true` and to `false`.
    let mut of_true: Vec<(usize, f64)> = Vec::with_capacity(width);
    let mut of_false: Vec<(usize, f64)> = Vec::with_capacity(width);
    for ((mrow, grow), orow) in mask
        .chunks(width)
        .zip(g.chunks(width))
        .zip(out.chunks_mut(width))
    {
        runs.clear();
        of_true.clear();
        of_false.clear();
        let mut a = 0;
        while a < width {
            let c = mrow[a];
            let b = mrow[a..]
                .iter()
                .position(|&x| x != c)
                .map_or(width, |n| a + n);
            runs.push((a, b, c));
            // The run's ends are features of its class's envelope; its
            // pixels, at their column distance, samples of the other one.
            let (ends, body) = if c {
                (&mut of_true, &mut of_false)
            } else {
                (&mut of_false, &mut of_true)
            };
            ends.push((a, 0.0));
            if b - a > 1 {
                ends.push((b - 1, 0.0));
            }
            for (q, &d) in grow.iter().enumerate().take(b).skip(a) {
                if d != NONE {
                    let d = f64::from(d);
                    body.push((q, d * d * sv2));
                }
            }
            a = b;
        }
        to_true.build_from(width, su2, of_true.iter().copied());
        to_false.build_from(width, su2, of_false.iter().copied());
        let (mut near_true, mut near_false) = (to_true.cursor(), to_false.cursor());
        for &(a, b, c) in &runs {
            // Two loops, not one with a sign and a chosen cursor: a cursor
            // picked through a reference is read and written through memory
            // at every pixel (6 % more instructions for the default).
            if c {
                for (p, o) in orow.iter_mut().enumerate().take(b).skip(a) {
                    *o = -(near_false.value(p) as f32).sqrt();
                }
            } else {
                for (p, o) in orow.iter_mut().enumerate().take(b).skip(a) {
                    *o = (near_true.value(p) as f32).sqrt();
                }
            }
        }
    }
    out
}

/// Generic 3D transform.
pub fn squared_edt_3d_as<S: EdtValue>(
    features: &[bool],
    dims: [usize; 3],
    spacing: [f64; 3],
) -> Vec<S> {
    let mut out = squared_edt_xy_as::<S>(features, dims, spacing);
    let [nx, ny, nz] = dims;
    if nx * ny * nz > 0 && nz > 1 {
        strided_pass(&mut out, nx * ny, nz, spacing[2]);
    }
    out
}

/// The transform restricted to each z-slab: passes along x and y only. Feeding
/// this to a pass along z (e.g. [`LowerEnvelope`] on selected columns) completes
/// the 3D transform; callers that need distances at a few voxels only can skip
/// the columns they do not need.
pub fn squared_edt_xy_as<S: EdtValue>(
    features: &[bool],
    dims: [usize; 3],
    spacing: [f64; 3],
) -> Vec<S> {
    let [nx, ny, nz] = dims;
    let n = nx
        .checked_mul(ny)
        .and_then(|a| a.checked_mul(nz))
        .expect("dims overflow");
    assert_eq!(features.len(), n, "features length must be nx * ny * nz");
    let mut out = vec![S::from_f64(f64::INFINITY); n];
    if n == 0 {
        return out;
    }
    // Slab by slab in parallel: both passes of a slab run while it is in cache.
    let slab = nx * ny;
    let (sx2, sy2) = (spacing[0] * spacing[0], spacing[1] * spacing[1]);
    out.par_chunks_mut(slab)
        .zip(features.par_chunks(slab))
        .for_each_init(
            || ColumnScratch::new(ny),
            |sc, (o, f)| {
                for (orow, frow) in o.chunks_mut(nx).zip(f.chunks(nx)) {
                    row_1d(frow, orow, sx2);
                }
                if ny > 1 {
                    columns_pass(o, nx, ny, sy2, sc);
                }
            },
        );
    out
}

/// Distance along one row by a forward and a backward sweep (exact in 1D).
fn row_1d<S: EdtValue>(f: &[bool], out: &mut [S], s2: f64) {
    let n = f.len();
    // Forward: distance to the nearest feature at or left of p (as an index gap).
    let mut last: Option<usize> = None;
    for p in 0..n {
        if f[p] {
            last = Some(p);
        }
        out[p] = S::from_f64(match last {
            Some(q) => {
                let d = (p - q) as f64;
                d * d * s2
            }
            None => f64::INFINITY,
        });
    }
    if last.is_none() {
        return;
    }
    // Backward: nearest feature at or right of p, if closer.
    let mut next: Option<usize> = None;
    for p in (0..n).rev() {
        if f[p] {
            next = Some(p);
        }
        if let Some(q) = next {
            let d = (q - p) as f64;
            let v = d * d * s2;
            if v < out[p].to_f64() {
                out[p] = S::from_f64(v);
            }
        }
    }
}

/// Per-thread buffers of a pass along strided columns.
struct ColumnScratch {
    /// `BLOCK` columns, each contiguous.
    buf: Vec<f64>,
    env: LowerEnvelope,
}

impl ColumnScratch {
    fn new(len: usize) -> Self {
        ColumnScratch {
            buf: vec![0.0; BLOCK * len],
            env: LowerEnvelope::with_capacity(len),
        }
    }

    /// Transform the first `w` gathered columns (each `len` long) in place.
    fn transform(&mut self, w: usize, len: usize, s2: f64) {
        for col in self.buf.chunks_mut(len).take(w) {
            self.env.build(col, s2);
            // The envelope holds its own copy of the heights: overwrite in place.
            self.env.evaluate_into(col);
        }
    }
}

/// The pass along the columns of one contiguous `[len][inner]` block (a slab):
/// columns are gathered `BLOCK` at a time so reads and writes stay contiguous.
fn columns_pass<S: EdtValue>(
    data: &mut [S],
    inner: usize,
    len: usize,
    s2: f64,
    sc: &mut ColumnScratch,
) {
    let mut i0 = 0;
    while i0 < inner {
        let w = BLOCK.min(inner - i0);
        for (p, row) in data.chunks(inner).enumerate() {
            for (c, v) in row[i0..i0 + w].iter().enumerate() {
                sc.buf[c * len + p] = v.to_f64();
            }
        }
        sc.transform(w, len, s2);
        for (p, row) in data.chunks_mut(inner).enumerate() {
            for (c, v) in row[i0..i0 + w].iter_mut().enumerate() {
                *v = S::from_f64(sc.buf[c * len + p]);
            }
        }
        i0 += w;
    }
}

/// A pass along the middle axis of a `[outer][len][inner]` layout with
/// `outer = 1`: lines run over `len` with stride `inner`. Columns are split into
/// blocks of [`BLOCK`] adjacent columns; each block owns disjoint sub-slices of
/// every row, so blocks run in parallel without unsafe code.
fn strided_pass<S: EdtValue>(data: &mut [S], inner: usize, len: usize, s: f64) {
    if len <= 1 || inner == 0 {
        return;
    }
    let s2 = s * s;
    let nblocks = inner.div_ceil(BLOCK);
    let mut blocks: Vec<Vec<&mut [S]>> = (0..nblocks).map(|_| Vec::with_capacity(len)).collect();
    for row in data.chunks_mut(inner) {
        let mut rest = row;
        for b in blocks.iter_mut() {
            let w = rest.len().min(BLOCK);
            let (head, tail) = rest.split_at_mut(w);
            b.push(head);
            rest = tail;
        }
    }
    blocks.into_par_iter().for_each_init(
        || ColumnScratch::new(len),
        |sc, mut rows| {
            let w = rows[0].len();
            // Gather: buf[c * len + p] = rows[p][c].
            for (p, r) in rows.iter().enumerate() {
                for (c, v) in r.iter().enumerate() {
                    sc.buf[c * len + p] = v.to_f64();
                }
            }
            sc.transform(w, len, s2);
            // Scatter back.
            for (p, r) in rows.iter_mut().enumerate() {
                for (c, v) in r.iter_mut().enumerate() {
                    *v = S::from_f64(sc.buf[c * len + p]);
                }
            }
        },
    );
}

/// The lower envelope of the parabolas `y = s²·(p − q)² + f(q)` of one line, for
/// the finite values `f(q)`: evaluating it at `p` gives the squared distance
/// `min_q s²·(p − q)² + f(q)`.
///
/// The breakpoints between neighbouring parabolas are kept as fractions
/// `num / den` (`den > 0`) and compared by cross-multiplication, so building
/// and evaluating need no division.
#[derive(Debug, Clone, Default)]
pub struct LowerEnvelope {
    /// Parabolas on the envelope, left to right; only `..len` is in use.
    parabolas: Vec<Parabola>,
    len: usize,
    s2: f64,
    line_len: usize,
}

/// One parabola of an envelope and where it starts to be the lowest.
#[derive(Debug, Clone, Copy, Default)]
struct Parabola {
    /// Its position `q`.
    q: f64,
    /// Its height `f(q)`.
    h: f64,
    /// `f(q) + s²·q²`, the part of the breakpoint formula that depends on `q` only.
    a: f64,
    /// Breakpoint with the previous parabola: `num / den` (`den > 0`; unused
    /// for the first parabola, whose breakpoint is −∞).
    num: f64,
    den: f64,
}

impl LowerEnvelope {
    /// An empty envelope with room for lines of `len` samples.
    pub fn with_capacity(len: usize) -> Self {
        LowerEnvelope {
            parabolas: vec![Parabola::default(); len],
            len: 0,
            s2: 1.0,
            line_len: 0,
        }
    }

    /// Build the envelope of line `f` (squared distances so far; infinite values
    /// are ignored) for sample spacing² `s2`.
    pub fn build(&mut self, f: &[f64], s2: f64) {
        self.build_from(
            f.len(),
            s2,
            f.iter()
                .enumerate()
                .filter(|(_, h)| h.is_finite())
                .map(|(q, &h)| (q, h)),
        );
    }

    /// Build the envelope of a line of `line_len` samples from its finite
    /// samples only, given as `(position, height)` with strictly ascending
    /// positions below `line_len`: callers whose lines are mostly empty, or
    /// stored in another type, feed them without a floating-point copy.
    pub fn build_from(
        &mut self,
        line_len: usize,
        s2: f64,
        samples: impl IntoIterator<Item = (usize, f64)>,
    ) {
        if self.parabolas.len() < line_len {
            self.parabolas.resize(line_len, Parabola::default());
        }
        self.s2 = s2;
        self.line_len = line_len;
        let two_s2 = 2.0 * s2;
        let env = &mut self.parabolas[..line_len];
        let mut len = 0usize;
        // The last parabola on the envelope, kept in registers (`env[len - 1]`).
        let mut top = Parabola::default();
        for (q, h) in samples {
            debug_assert!(h.is_finite());
            let q = position(q);
            let a = h + s2 * q * q;
            // Pop the parabolas that q hides: the breakpoint of q with the last
            // one, (a - a_p) / (2 s² (q - p)), is at or before the last one's own
            // breakpoint. The first parabola's breakpoint is −∞: never popped.
            let (num, den) = loop {
                if len == 0 {
                    break (-1.0, 0.0);
                }
                let num = a - top.a;
                let den = two_s2 * (q - top.q);
                if len > 1 && num * top.den <= top.num * den {
                    len -= 1;
                    top = env[len - 1];
                } else {
                    break (num, den);
                }
            };
            top = Parabola { q, h, a, num, den };
            env[len] = top;
            len += 1;
        }
        self.len = len;
    }

    /// True when the line had no finite value (every evaluation is infinite).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Evaluate at every sample `0..len` into `out` (length `len`).
    pub fn evaluate_into(&self, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.line_len);
        self.evaluate_sorted(0..out.len(), |p, v| out[p] = v);
    }

    /// Evaluate at sample positions `ps`, which must be ascending, calling
    /// `f(p, value)` for each.
    #[inline]
    pub fn evaluate_sorted(
        &self,
        ps: impl IntoIterator<Item = usize>,
        mut f: impl FnMut(usize, f64),
    ) {
        let mut at = self.cursor();
        for p in ps {
            f(p, at.value(p));
        }
    }

    /// A reader of the envelope at ascending positions.
    #[inline]
    pub fn cursor(&self) -> EnvelopeCursor<'_> {
        let env = &self.parabolas[..self.len];
        EnvelopeCursor {
            env,
            k: 0,
            cur: env.first().copied(),
            s2: self.s2,
        }
    }
}

/// A position along a line as a float. Lines are far shorter than 2³²
/// samples, and a 32-bit integer converts in one instruction where a
/// 64-bit unsigned one takes several (this is in the innermost loops).
#[inline]
fn position(p: usize) -> f64 {
    debug_assert!(p <= u32::MAX as usize);
    f64::from(p as u32)
}

/// Reads a [`LowerEnvelope`] at ascending positions: each read moves on
/// from the parabola of the previous one, so reading a whole line costs one
/// pass over the envelope.
pub struct EnvelopeCursor<'a> {
    env: &'a [Parabola],
    /// The parabola lowest at the last position read, and its index.
    k: usize,
    cur: Option<Parabola>,
    s2: f64,
}

impl EnvelopeCursor<'_> {
    /// The envelope at `p`, at or after every earlier position read
    /// (infinite for an envelope without parabolas).
    #[inline]
    pub fn value(&mut self, p: usize) -> f64 {
        let Some(cur) = self.cur.as_mut() else {
            return f64::INFINITY;
        };
        let pf = position(p);
        // Advance while the next parabola starts before p.
        while let Some(next) = self.env.get(self.k + 1) {
            if next.num < pf * next.den {
                self.k += 1;
                *cur = *next;
            } else {
                break;
            }
        }
        let d = pf - cur.q;
        self.s2 * d * d + cur.h
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute_2d(f: &[bool], w: usize, h: usize, s: [f64; 2]) -> Vec<f64> {
        let mut out = vec![f64::INFINITY; w * h];
        for v in 0..h {
            for u in 0..w {
                let mut best = f64::INFINITY;
                for b in 0..h {
                    for a in 0..w {
                        if f[a + w * b] {
                            let du = (u as f64 - a as f64) * s[0];
                            let dv = (v as f64 - b as f64) * s[1];
                            best = best.min(du * du + dv * dv);
                        }
                    }
                }
                out[u + w * v] = best;
            }
        }
        out
    }

    fn brute_3d(f: &[bool], d: [usize; 3], s: [f64; 3]) -> Vec<f64> {
        let [nx, ny, nz] = d;
        let pts: Vec<[usize; 3]> = (0..nx * ny * nz)
            .filter(|&n| f[n])
            .map(|n| [n % nx, (n / nx) % ny, n / (nx * ny)])
            .collect();
        (0..nx * ny * nz)
            .map(|n| {
                let q = [n % nx, (n / nx) % ny, n / (nx * ny)];
                pts.iter()
                    .map(|p| {
                        (0..3)
                            .map(|a| {
                                let x = (p[a] as f64 - q[a] as f64) * s[a];
                                x * x
                            })
                            .sum::<f64>()
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .collect()
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        if a.is_infinite() || b.is_infinite() {
            return a == b;
        }
        (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-12)
    }

    fn grid_2d() -> impl Strategy<Value = (usize, usize, Vec<bool>, [f64; 2], u8)> {
        (1usize..14, 1usize..14, 0.2f64..3.0, 0.2f64..3.0, 0u8..4).prop_flat_map(
            |(w, h, a, b, mode)| {
                (
                    Just(w),
                    Just(h),
                    proptest::collection::vec(proptest::bool::weighted(0.15), w * h),
                    Just([a, b]),
                    Just(mode),
                )
            },
        )
    }

    fn grid_3d() -> impl Strategy<Value = ([usize; 3], Vec<bool>, [f64; 3], u8)> {
        (
            1usize..9,
            1usize..9,
            1usize..9,
            0.2f64..3.0,
            0.2f64..3.0,
            0.2f64..3.0,
            0u8..4,
        )
            .prop_flat_map(|(x, y, z, a, b, c, mode)| {
                (
                    Just([x, y, z]),
                    proptest::collection::vec(proptest::bool::weighted(0.1), x * y * z),
                    Just([a, b, c]),
                    Just(mode),
                )
            })
    }

    /// mode 0: random; 1: empty; 2: full; 3: a single feature.
    fn apply_mode(f: &mut [bool], mode: u8) {
        match mode {
            1 => f.fill(false),
            2 => f.fill(true),
            3 => {
                let n = f.len();
                f.fill(false);
                f[n / 2] = true;
            }
            _ => {}
        }
    }

    proptest! {
        #[test]
        fn edt_2d_matches_brute_force((w, h, mut f, s, mode) in grid_2d()) {
            apply_mode(&mut f, mode);
            let got = squared_edt_2d(&f, w, h, s);
            let want = brute_2d(&f, w, h, s);
            for (n, (g, e)) in got.iter().zip(&want).enumerate() {
                prop_assert!(close(*g, *e, 1e-12), "pixel {n}: {g} vs {e}");
            }
            let g32 = squared_edt_2d_f32(&f, w, h, s);
            for (g, e) in g32.iter().zip(&want) {
                prop_assert!(close(f64::from(*g), *e, 1e-6));
            }
        }

        #[test]
        fn signed_edt_2d_is_the_distance_to_the_other_class(
            (w, h, mut f, s, mode) in grid_2d(),
            dense in 0.0f64..1.0,
        ) {
            apply_mode(&mut f, mode);
            // Masks of every density, so that rows hold long runs of both
            // classes (the envelopes keep only a run's ends).
            if mode == 0 {
                for (n, x) in f.iter_mut().enumerate() {
                    *x |= ((n * 7919) % 1000) as f64 / 1000.0 < dense;
                }
            }
            let got = signed_edt_2d_f32(&f, w, h, s);
            let to_true = brute_2d(&f, w, h, s);
            let not: Vec<bool> = f.iter().map(|&x| !x).collect();
            let to_false = brute_2d(&not, w, h, s);
            for n in 0..w * h {
                let want = if f[n] { -to_false[n].sqrt() } else { to_true[n].sqrt() };
                prop_assert!(close(f64::from(got[n]), want, 1e-6), "pixel {n}: {} vs {want}", got[n]);
                prop_assert_eq!(got[n] < 0.0, f[n], "pixel {}: the sign is the mask", n);
            }
        }

        #[test]
        fn edt_3d_matches_brute_force((d, mut f, s, mode) in grid_3d()) {
            apply_mode(&mut f, mode);
            let got = squared_edt_3d(&f, d, s);
            let want = brute_3d(&f, d, s);
            for (n, (g, e)) in got.iter().zip(&want).enumerate() {
                prop_assert!(close(*g, *e, 1e-12), "voxel {n}: {g} vs {e}");
            }
            let g32 = squared_edt_3d_f32(&f, d, s);
            for (g, e) in g32.iter().zip(&want) {
                prop_assert!(close(f64::from(*g), *e, 1e-6));
            }
        }
    }

    #[test]
    fn wide_volume_crosses_block_boundaries() {
        // nx * ny > BLOCK so the z pass uses several column blocks.
        let d = [11, 7, 5];
        let mut f = vec![false; 11 * 7 * 5];
        f[3 + 11 * (2 + 7 * 4)] = true;
        f[10 + 11 * 6] = true; // (10, 6, 0)
        let s = [0.5, 1.0, 2.5];
        let got = squared_edt_3d(&f, d, s);
        assert_eq!(got, brute_3d(&f, d, s));
    }

    #[test]
    fn known_values() {
        // One feature at (0, 0) with spacing (2, 3): pixel (2, 1) is at 4² + 3².
        let mut f = vec![false; 4 * 3];
        f[0] = true;
        let d = squared_edt_2d(&f, 4, 3, [2.0, 3.0]);
        assert_eq!(d[2 + 4], 25.0);
        assert_eq!(d[0], 0.0);
        assert!(
            squared_edt_2d(&[false; 6], 3, 2, [1.0, 1.0])
                .iter()
                .all(|x| x.is_infinite())
        );
        assert!(
            squared_edt_3d(&[true; 8], [2, 2, 2], [1.0; 3])
                .iter()
                .all(|&x| x == 0.0)
        );
    }

    #[test]
    fn envelope_sorted_evaluation_matches_full() {
        let f = [
            f64::INFINITY,
            4.0,
            f64::INFINITY,
            0.0,
            9.0,
            f64::INFINITY,
            1.0,
        ];
        let mut env = LowerEnvelope::with_capacity(f.len());
        env.build(&f, 2.0);
        let mut full = vec![0.0; f.len()];
        env.evaluate_into(&mut full);
        let mut sampled = vec![];
        env.evaluate_sorted([0, 2, 5, 6], |p, v| sampled.push((p, v)));
        for (p, v) in sampled {
            assert_eq!(v, full[p]);
        }
        assert_eq!(full[3], 0.0);
        // q = 1 gives 4 + 2·1² = 6, q = 3 gives 0 + 2·3² = 18.
        assert_eq!(full[0], 6.0);
    }
}
