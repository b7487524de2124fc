//! Border voxels: foreground voxels with a 6-neighbour outside the mask, the
//! outside of the image counting as background (the medpy/MONAI convention:
//! `mask XOR erode(mask, 6-connected cross, border_value = 0)`).
use rayon::prelude::*;

/// Read access to a binary mask given as any voxel array plus a test, so the
/// metrics run directly on label volumes without allocating masks.
pub trait MaskView: Sync {
    /// Dims `(nx, ny, nz)`.
    fn dims(&self) -> [usize; 3];
    /// True when the voxel at linear index `idx` is foreground.
    fn fg(&self, idx: usize) -> bool;
    /// `out[n] = self.fg(start + n)` for every `n`: the views implement it as
    /// one loop over a slice, which the compiler vectorises.
    fn fg_run(&self, start: usize, out: &mut [bool]) {
        for (o, idx) in out.iter_mut().zip(start..) {
            *o = self.fg(idx);
        }
    }
}

/// The voxels of `data` equal to `value`.
#[derive(Debug, Clone, Copy)]
pub struct EqualTo<'a, T> {
    /// Voxels, x-fastest.
    pub data: &'a [T],
    /// Dims `(nx, ny, nz)`; `data.len()` must be their product.
    pub dims: [usize; 3],
    /// The foreground value.
    pub value: T,
}

impl<T: Copy + PartialEq + Sync> MaskView for EqualTo<'_, T> {
    #[inline]
    fn dims(&self) -> [usize; 3] {
        self.dims
    }
    #[inline]
    fn fg(&self, idx: usize) -> bool {
        self.data[idx] == self.value
    }
    #[inline]
    fn fg_run(&self, start: usize, out: &mut [bool]) {
        let data = &self.data[start..start + out.len()];
        for (o, v) in out.iter_mut().zip(data) {
            *o = *v == self.value;
        }
    }
}

/// The voxels of `data` that are not zero (any label): the union of all labels.
#[derive(Debug, Clone, Copy)]
pub struct NonZero<'a, T> {
    /// Voxels, x-fastest.
    pub data: &'a [T],
    /// Dims `(nx, ny, nz)`; `data.len()` must be their product.
    pub dims: [usize; 3],
}

impl<T: Copy + PartialEq + Default + Sync> MaskView for NonZero<'_, T> {
    #[inline]
    fn dims(&self) -> [usize; 3] {
        self.dims
    }
    #[inline]
    fn fg(&self, idx: usize) -> bool {
        self.data[idx] != T::default()
    }
    #[inline]
    fn fg_run(&self, start: usize, out: &mut [bool]) {
        let data = &self.data[start..start + out.len()];
        let zero = T::default();
        for (o, v) in out.iter_mut().zip(data) {
            *o = *v != zero;
        }
    }
}

/// True when voxel `(i, j, k)` is a border voxel of `m`.
#[inline]
pub fn is_border<M: MaskView>(m: &M, i: usize, j: usize, k: usize) -> bool {
    let [nx, ny, nz] = m.dims();
    let sy = nx;
    let sz = nx * ny;
    let idx = i + sy * j + sz * k;
    if !m.fg(idx) {
        return false;
    }
    i == 0
        || j == 0
        || k == 0
        || i + 1 == nx
        || j + 1 == ny
        || k + 1 == nz
        || !m.fg(idx - 1)
        || !m.fg(idx + 1)
        || !m.fg(idx - sy)
        || !m.fg(idx + sy)
        || !m.fg(idx - sz)
        || !m.fg(idx + sz)
}

/// Voxels of a row handled together by [`mark_border_row`] and [`bounding_box`].
const RUN: usize = 64;

/// True when any of `v` is set (a branch-free fold, vectorised).
#[inline]
fn any(v: &[bool]) -> bool {
    v.iter().fold(false, |a, &b| a | b)
}

/// Sets `bit` in `out[x - x0]` for every border voxel `(x, y, z)` of `m` with
/// `x` in `x0..x0 + out.len()`: [`is_border`] for a run of one row, computed
/// `RUN` voxels at a time from whole runs of the row and of its four
/// neighbour rows (runs without foreground are skipped after one read).
pub fn mark_border_row<M: MaskView>(m: &M, y: usize, z: usize, x0: usize, out: &mut [u8], bit: u8) {
    let [nx, ny, nz] = m.dims();
    let sy = nx;
    let sz = nx * ny;
    let base = sy * y + sz * z;
    // A voxel on a face of the image always has a neighbour outside it.
    let edge = y == 0 || z == 0 || y + 1 == ny || z + 1 == nz;
    let mut c = [false; RUN + 2];
    let mut inner = [false; RUN];
    let mut nb = [false; RUN];
    for (n, o) in out.chunks_mut(RUN).enumerate() {
        let a = x0 + n * RUN;
        let len = o.len();
        // The run with one voxel either side; outside the image is background.
        m.fg_run(base + a, &mut c[1..=len]);
        if !any(&c[1..=len]) {
            continue;
        }
        c[0] = a > 0 && m.fg(base + a - 1);
        c[len + 1] = a + len < nx && m.fg(base + a + len);
        if edge {
            for (o, &f) in o.iter_mut().zip(&c[1..=len]) {
                *o |= bit * u8::from(f);
            }
            continue;
        }
        let inner = &mut inner[..len];
        let nb = &mut nb[..len];
        m.fg_run(base + a - sy, inner);
        for off in [base + a + sy, base + a - sz, base + a + sz] {
            m.fg_run(off, nb);
            for (i, &b) in inner.iter_mut().zip(nb.iter()) {
                *i &= b;
            }
        }
        // Bitwise, not short-circuit, operators: one branch-free vector loop.
        let (l, r) = (&c[..len], &c[2..len + 2]);
        let mid = &c[1..=len];
        for ((((o, &i), &l), &m), &r) in o.iter_mut().zip(inner.iter()).zip(l).zip(mid).zip(r) {
            let border = m & !(l & r & i);
            *o |= bit * u8::from(border);
        }
    }
}

/// Half-open box `[lo, hi)` of voxel indices along x, y, z.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoundingBox {
    /// First index along each axis.
    pub lo: [usize; 3],
    /// One past the last index along each axis.
    pub hi: [usize; 3],
}

impl BoundingBox {
    /// The smallest box holding both.
    pub fn union(self, o: BoundingBox) -> BoundingBox {
        BoundingBox {
            lo: [0, 1, 2].map(|a| self.lo[a].min(o.lo[a])),
            hi: [0, 1, 2].map(|a| self.hi[a].max(o.hi[a])),
        }
    }

    /// Extent along each axis.
    pub fn dims(&self) -> [usize; 3] {
        [0, 1, 2].map(|a| self.hi[a] - self.lo[a])
    }
}

/// The bounding box of the foreground of `m` (which is also the bounding box of
/// its border voxels: the extreme voxels along each axis are border voxels), or
/// `None` when the mask is empty. One parallel pass over z-slabs.
pub fn bounding_box<M: MaskView>(m: &M) -> Option<BoundingBox> {
    let [nx, ny, nz] = m.dims();
    (0..nz)
        .into_par_iter()
        .map_init(
            || vec![false; nx],
            |row, k| {
                let mut bb: Option<BoundingBox> = None;
                for j in 0..ny {
                    let base = nx * (j + ny * k);
                    m.fg_run(base, row);
                    // Whole runs first: most rows of a box are empty or full.
                    let Some(c) = row.chunks(RUN).position(any) else {
                        continue;
                    };
                    let first = c * RUN + row[c * RUN..].iter().position(|&f| f).unwrap_or(0);
                    let last = row.iter().rposition(|&f| f).unwrap_or(first);
                    let r = BoundingBox {
                        lo: [first, j, k],
                        hi: [last + 1, j + 1, k + 1],
                    };
                    bb = Some(bb.map_or(r, |b| b.union(r)));
                }
                bb
            },
        )
        .flatten()
        .reduce_with(BoundingBox::union)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn border_of_a_cube_and_image_edges() {
        // A 3x3x3 cube inside 5x5x5: all but the centre voxel are border.
        let d = [5, 5, 5];
        let mut data = vec![0u8; 125];
        for k in 1..4 {
            for j in 1..4 {
                for i in 1..4 {
                    data[i + 5 * (j + 5 * k)] = 1;
                }
            }
        }
        let m = EqualTo {
            data: &data,
            dims: d,
            value: 1,
        };
        let n = (0..125)
            .filter(|&x| is_border(&m, x % 5, (x / 5) % 5, x / 25))
            .count();
        assert_eq!(n, 26);
        assert!(!is_border(&m, 2, 2, 2));
        assert_eq!(
            bounding_box(&m),
            Some(BoundingBox {
                lo: [1, 1, 1],
                hi: [4, 4, 4]
            })
        );
        // A full volume: only the image faces are border.
        let full = vec![1u8; 125];
        let m = EqualTo {
            data: &full,
            dims: d,
            value: 1,
        };
        let n = (0..125)
            .filter(|&x| is_border(&m, x % 5, (x / 5) % 5, x / 25))
            .count();
        assert_eq!(n, 125 - 27);
        // The row version agrees with the voxel version, on any row segment.
        let mut pattern = vec![0u8; 125];
        for (n, v) in pattern.iter_mut().enumerate() {
            *v = u8::from((n * 7919) % 5 < 3);
        }
        let m = EqualTo {
            data: &pattern,
            dims: d,
            value: 1,
        };
        for z in 0..5 {
            for y in 0..5 {
                let mut row = vec![0u8; 4];
                mark_border_row(&m, y, z, 1, &mut row, 2);
                for (x, r) in (1..5).zip(&row) {
                    assert_eq!(*r == 2, is_border(&m, x, y, z), "{x},{y},{z}");
                }
            }
        }
        // Rows longer than a run: every row segment, against the voxel test,
        // and the bounding box against a naive one.
        let pattern: Vec<u16> = (0..150 * 20)
            .map(|n: usize| u16::from((n * 7919 + n / 150) % 7 < 4 && (n % 150) > 20))
            .collect();
        let m = EqualTo {
            data: &pattern,
            dims: [150, 4, 5],
            value: 1,
        };
        for z in 0..5 {
            for y in 0..4 {
                for x0 in [0, 1, 37, 64] {
                    let mut row = vec![0u8; 150 - x0];
                    mark_border_row(&m, y, z, x0, &mut row, 4);
                    for (x, r) in (x0..150).zip(&row) {
                        assert_eq!(*r == 4, is_border(&m, x, y, z), "{x},{y},{z}");
                    }
                }
            }
        }
        let fg: Vec<usize> = (0..pattern.len()).filter(|&n| pattern[n] == 1).collect();
        let lo = [0, 1, 2].map(|a| {
            fg.iter()
                .map(|&n| [n % 150, (n / 150) % 4, n / 600][a])
                .min()
                .unwrap()
        });
        let hi = [0, 1, 2].map(|a| {
            fg.iter()
                .map(|&n| [n % 150, (n / 150) % 4, n / 600][a])
                .max()
                .unwrap()
                + 1
        });
        assert_eq!(bounding_box(&m), Some(BoundingBox { lo, hi }));
        let empty = vec![0u8; 125];
        assert_eq!(
            bounding_box(&EqualTo {
                data: &empty,
                dims: d,
                value: 1
            }),
            None
        );
    }
}
