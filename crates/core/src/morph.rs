//! Binary morphology on masks: connected components (6- or 26-connected),
//! the largest component, hole filling (in 3D or slice by slice), and
//! separable Gaussian smoothing with physical spacing.
//!
//! Components are found on *runs* (maximal stretches of foreground along x)
//! rather than voxels: runs of neighbouring rows are merged with a union-find,
//! which needs memory proportional to the number of runs, not to the volume,
//! and touches every voxel once. Written here because no maintained crate
//! labels 3D masks in this storage order with anisotropy-aware smoothing;
//! the algorithms are classic (Rosenfeld & Pfaltz two-pass labelling on runs).
use crate::regions::UnionFind;
use crate::{Axis, Cancel, CoreError, Geometry, Mask, Volume, Voxel};
use rayon::prelude::*;

/// Which neighbours touch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Connectivity {
    /// Face neighbours only (6 in 3D, 4 in a slice).
    #[default]
    Face,
    /// Face, edge and corner neighbours (26 in 3D, 8 in a slice).
    Full,
}

impl Connectivity {
    /// The 3D neighbour count: 6 or 26 (how the CLI and the API name it).
    pub fn neighbours(self) -> u8 {
        match self {
            Connectivity::Face => 6,
            Connectivity::Full => 26,
        }
    }

    /// Parse "6" / "face" or "26" / "full".
    pub fn parse(s: &str) -> Result<Connectivity, CoreError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "6" | "4" | "face" => Ok(Connectivity::Face),
            "26" | "8" | "full" => Ok(Connectivity::Full),
            o => Err(CoreError::Invalid(format!(
                "unknown connectivity '{o}' (expected 6 or 26)"
            ))),
        }
    }
}

/// Runs of one value along x, grouped by row (`row = j + ny * k`).
struct Runs {
    /// `row_start[r]..row_start[r + 1]` are the runs of row r.
    row_start: Vec<usize>,
    /// Start (inclusive) and end (exclusive) x of every run.
    span: Vec<(u32, u32)>,
}

fn runs_of(data: &[bool], dims: [usize; 3], value: bool) -> Runs {
    let [nx, ny, _] = dims;
    // Per z-slab in parallel, then concatenated in order.
    type SlabRuns = (Vec<usize>, Vec<(u32, u32)>);
    let per_slab: Vec<SlabRuns> = data
        .par_chunks(nx * ny)
        .map(|slab| {
            let mut counts = Vec::with_capacity(ny);
            let mut span = Vec::new();
            for row in slab.chunks(nx) {
                let before = span.len();
                // Each run found by two searches (start, then end): tight
                // loops over the row, one comparison per pixel.
                let mut i = 0;
                while let Some(n) = row[i..].iter().position(|&x| x == value) {
                    let s = i + n;
                    i = row[s..]
                        .iter()
                        .position(|&x| x != value)
                        .map_or(nx, |n| s + n);
                    span.push((s as u32, i as u32));
                }
                counts.push(span.len() - before);
            }
            (counts, span)
        })
        .collect();
    let mut row_start = Vec::with_capacity(data.len() / nx.max(1) + 1);
    let total: usize = per_slab.iter().map(|s| s.1.len()).sum();
    let mut span = Vec::with_capacity(total);
    row_start.push(0);
    for (counts, s) in per_slab {
        let mut acc = span.len();
        for c in counts {
            acc += c;
            row_start.push(acc);
        }
        span.extend(s);
    }
    Runs { row_start, span }
}

/// Components of the runs: a compact component id (0-based, in scan order of
/// first voxels) for every run, and the number of components.
fn connect(runs: &Runs, dims: [usize; 3], conn: Connectivity) -> (Vec<u32>, usize) {
    let [_, ny, nz] = dims;
    let n = runs.span.len();
    let mut uf: UnionFind<u32> = UnionFind::new(n);
    let full = conn == Connectivity::Full;
    let prev: &[(i64, i64)] = if full {
        &[(-1, 0), (-1, -1), (0, -1), (1, -1)]
    } else {
        &[(-1, 0), (0, -1)]
    };
    for k in 0..nz {
        for j in 0..ny {
            let r = j + ny * k;
            let (a0, a1) = (runs.row_start[r], runs.row_start[r + 1]);
            if a0 == a1 {
                continue;
            }
            for &(dj, dk) in prev {
                let (jj, kk) = (j as i64 + dj, k as i64 + dk);
                if jj < 0 || kk < 0 || jj >= ny as i64 {
                    continue;
                }
                let q = jj as usize + ny * kk as usize;
                let (mut i, mut b) = (a0, runs.row_start[q]);
                let b1 = runs.row_start[q + 1];
                while i < a1 && b < b1 {
                    let (ax0, ax1) = runs.span[i];
                    let (bx0, bx1) = runs.span[b];
                    let touch = if full {
                        ax0 <= bx1 && bx0 <= ax1
                    } else {
                        ax0 < bx1 && bx0 < ax1
                    };
                    if touch {
                        uf.union(i as u32, b as u32);
                    }
                    if ax1 < bx1 {
                        i += 1;
                    } else {
                        b += 1;
                    }
                }
            }
        }
    }
    // The first run of each component in run order numbers it, so components
    // are numbered in scan order whichever run the union-find made the root.
    let mut id = vec![u32::MAX; n];
    let mut next = 0u32;
    for r in 0..n {
        let root = uf.find_mut(r as u32) as usize;
        if id[root] == u32::MAX {
            id[root] = next;
            next += 1;
        }
        id[r] = id[root];
    }
    (id, next as usize)
}

/// Write `f(component)` of every run into a new volume, in parallel per slab.
fn paint_runs<T: Voxel>(
    geometry: &Geometry,
    runs: &Runs,
    mut base: Vec<T>,
    value: impl Fn(usize) -> Option<T> + Sync,
) -> Volume<T> {
    let [nx, ny, _] = geometry.dims;
    base.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, slab)| {
            for j in 0..ny {
                let r = j + ny * k;
                for run in runs.row_start[r]..runs.row_start[r + 1] {
                    if let Some(v) = value(run) {
                        let (x0, x1) = runs.span[run];
                        slab[j * nx + x0 as usize..j * nx + x1 as usize].fill(v);
                    }
                }
            }
        });
    Volume::from_vec(geometry.clone(), base).expect("same geometry")
}

/// The components of a mask held as its runs: every run of foreground
/// along x with the component it belongs to. A caller that wants more than
/// the id of every voxel (a component's area, centroid or box) sums it per
/// run instead of per voxel.
pub struct ComponentRuns {
    runs: Runs,
    /// Component (0-based, in scan order of first voxels) of every run.
    id: Vec<u32>,
    count: usize,
    dims: [usize; 3],
}

impl ComponentRuns {
    /// The components of `data` (x fastest, `dims`); a slice of a volume is
    /// `[w, h, 1]`, where `conn` is 4- or 8-connectivity.
    pub fn of(data: &[bool], dims: [usize; 3], conn: Connectivity) -> ComponentRuns {
        let runs = runs_of(data, dims, true);
        let (id, count) = connect(&runs, dims, conn);
        ComponentRuns {
            runs,
            id,
            count,
            dims,
        }
    }

    /// Number of components.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The voxel count of every component.
    pub fn sizes(&self) -> Vec<u64> {
        let mut sizes = vec![0u64; self.count];
        for (&c, &(x0, x1)) in self.id.iter().zip(&self.runs.span) {
            sizes[c as usize] += u64::from(x1 - x0);
        }
        sizes
    }

    /// Every run as `(component, row, x0, x1)`: voxels `x0..x1` of row
    /// `row = j + ny * k`, in scan order.
    pub fn runs(&self) -> impl Iterator<Item = (u32, usize, usize, usize)> + '_ {
        let rows = self.runs.row_start.len() - 1;
        (0..rows).flat_map(move |r| {
            (self.runs.row_start[r]..self.runs.row_start[r + 1]).map(move |run| {
                let (x0, x1) = self.runs.span[run];
                (self.id[run], r, x0 as usize, x1 as usize)
            })
        })
    }

    /// The component id + 1 of every voxel (0 = background).
    pub fn ids(&self) -> Vec<u32> {
        let nx = self.dims[0];
        let mut out = vec![0u32; self.dims.iter().product()];
        for (c, r, x0, x1) in self.runs() {
            out[r * nx + x0..r * nx + x1].fill(c + 1);
        }
        out
    }
}

/// Connected components of `mask`: a volume of component ids (1..=n in scan
/// order of their first voxel, 0 = background) and the voxel count of each
/// (`sizes[id - 1]`).
pub fn label_components(mask: &Mask, conn: Connectivity) -> (Volume<u32>, Vec<u64>) {
    let c = ComponentRuns::of(mask.data(), mask.dims(), conn);
    let labels = paint_runs(
        mask.geometry(),
        &c.runs,
        vec![0u32; mask.data().len()],
        |r| Some(c.id[r] + 1),
    );
    (labels, c.sizes())
}

/// The largest connected component of `mask` (the first one in scan order on
/// ties); an empty mask stays empty.
pub fn largest_component(mask: &Mask, conn: Connectivity) -> Mask {
    let c = ComponentRuns::of(mask.data(), mask.dims(), conn);
    if c.count == 0 {
        return mask.clone();
    }
    let sizes = c.sizes();
    let mut best = 0;
    for (k, &s) in sizes.iter().enumerate() {
        if s > sizes[best] {
            best = k;
        }
    }
    paint_runs(
        mask.geometry(),
        &c.runs,
        vec![false; mask.data().len()],
        |r| (c.id[r] as usize == best).then_some(true),
    )
}

/// Fill the holes of `mask`: background components (connected by
/// `background`) that do not touch the border of the volume become
/// foreground. Only dimensions longer than one voxel have a border, so a
/// single-slice volume is filled as a 2D image. Face connectivity of the
/// background is the usual choice (as `scipy.ndimage.binary_fill_holes`).
pub fn fill_holes(mask: &Mask, background: Connectivity) -> Mask {
    let dims = mask.dims();
    let [nx, ny, nz] = dims;
    let runs = runs_of(mask.data(), dims, false);
    let (id, n) = connect(&runs, dims, background);
    let mut open = vec![false; n];
    for k in 0..nz {
        for j in 0..ny {
            let r = j + ny * k;
            let edge_row =
                (ny > 1 && (j == 0 || j == ny - 1)) || (nz > 1 && (k == 0 || k == nz - 1));
            for run in runs.row_start[r]..runs.row_start[r + 1] {
                let (x0, x1) = runs.span[run];
                if edge_row || (nx > 1 && (x0 == 0 || x1 as usize == nx)) {
                    open[id[run] as usize] = true;
                }
            }
        }
    }
    paint_runs(mask.geometry(), &runs, mask.data().to_vec(), |r| {
        (!open[id[r] as usize]).then_some(true)
    })
}

/// Fill holes in every slice along `axis` separately (2D holes, face-connected
/// background, i.e. 4-connected in the slice); slices run in parallel.
pub fn fill_holes_per_slice(mask: &Mask, axis: Axis) -> Mask {
    let (w, h) = mask.slice_shape(axis);
    let n = mask.slice_count(axis);
    let filled: Vec<Vec<bool>> = (0..n)
        .into_par_iter()
        .map(|idx| {
            let s = mask.slice(axis, idx).expect("index in range");
            let g = Geometry::new([w, h, 1], [1.0; 3], mask.geometry().unit).expect("valid dims");
            let m = Volume::from_vec(g, s).expect("slice size");
            fill_holes(&m, Connectivity::Face).into_parts().1
        })
        .collect();
    let mut out = mask.clone();
    for (idx, s) in filled.iter().enumerate() {
        out.set_slice(axis, idx, s).expect("slice size");
    }
    out
}

/// Gaussian smoothing with standard deviation `sigma` in physical units
/// (voxels of size `spacing` get `sigma / spacing` voxels per axis), separable,
/// kernels truncated at 4 σ and normalised, borders mirrored (`d c b a | a b c d`,
/// scipy's default). An axis whose σ is below 0.1 voxel is left alone. The
/// result is f32; memory is one f32 copy of the volume plus one slab per thread.
/// `cancel` is checked before every plane of every pass (a large σ on a large
/// volume takes minutes).
pub fn gaussian_smooth<T: Voxel>(
    v: &Volume<T>,
    sigma: f64,
    cancel: &Cancel,
) -> Result<Volume<f32>, CoreError> {
    if !(sigma.is_finite() && sigma >= 0.0) {
        return Err(CoreError::Invalid(format!(
            "smoothing sigma must be a finite number >= 0, not {sigma}"
        )));
    }
    let g = v.geometry().clone();
    let [nx, ny, nz] = g.dims;
    let kernels: Vec<Vec<f32>> = (0..3).map(|a| kernel(sigma / g.spacing[a])).collect();
    let plane = nx * ny;
    let src = v.data();
    // z pass straight from the source into the f32 result.
    let mut out = vec![0f32; g.len()];
    let kz = &kernels[2];
    let rz = kz.len() / 2;
    out.par_chunks_mut(plane).enumerate().for_each(|(k, dst)| {
        if cancel.is_cancelled() {
            return;
        }
        for (t, &w) in kz.iter().enumerate() {
            let kk = mirror(k as i64 + t as i64 - rz as i64, nz);
            let s = &src[kk * plane..(kk + 1) * plane];
            for (d, &x) in dst.iter_mut().zip(s) {
                *d += w * x.to_f64() as f32;
            }
        }
    });
    cancel.check()?;
    // y and x passes in place, slab by slab.
    let (ky, kx) = (&kernels[1], &kernels[0]);
    let (ry, rx) = (ky.len() / 2, kx.len() / 2);
    out.par_chunks_mut(plane).for_each_init(
        || (vec![0f32; plane], vec![0f32; nx]),
        |(scratch, row), slab| {
            if cancel.is_cancelled() {
                return;
            }
            if ky.len() > 1 {
                scratch.copy_from_slice(slab);
                slab.fill(0.0);
                for j in 0..ny {
                    let dst = &mut slab[j * nx..(j + 1) * nx];
                    for (t, &w) in ky.iter().enumerate() {
                        let jj = mirror(j as i64 + t as i64 - ry as i64, ny);
                        for (d, &x) in dst.iter_mut().zip(&scratch[jj * nx..(jj + 1) * nx]) {
                            *d += w * x;
                        }
                    }
                }
            }
            if kx.len() > 1 {
                for j in 0..ny {
                    let dst = &mut slab[j * nx..(j + 1) * nx];
                    row.copy_from_slice(dst);
                    for (i, d) in dst.iter_mut().enumerate() {
                        let mut acc = 0f32;
                        for (t, &w) in kx.iter().enumerate() {
                            acc += w * row[mirror(i as i64 + t as i64 - rx as i64, nx)];
                        }
                        *d = acc;
                    }
                }
            }
        },
    );
    cancel.check()?;
    Volume::from_vec(g, out)
}

/// A normalised Gaussian kernel of `s` voxels, radius `ceil(4 s)`; `[1]` when `s < 0.1`.
fn kernel(s: f64) -> Vec<f32> {
    if s < 0.1 {
        return vec![1.0];
    }
    let r = (4.0 * s).ceil() as i64;
    let w: Vec<f64> = (-r..=r)
        .map(|x| (-(x * x) as f64 / (2.0 * s * s)).exp())
        .collect();
    let sum: f64 = w.iter().sum();
    w.iter().map(|x| (x / sum) as f32).collect()
}

/// Mirror an index into `0..n` (`d c b a | a b c d`), any distance away.
#[inline]
fn mirror(i: i64, n: usize) -> usize {
    let n = n as i64;
    let p = 2 * n;
    let m = i.rem_euclid(p);
    (if m < n { m } else { p - 1 - m }) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LengthUnit;
    use proptest::prelude::*;

    fn mask(dims: [usize; 3], data: Vec<bool>) -> Mask {
        Volume::from_vec(
            Geometry::new(dims, [1.0; 3], LengthUnit::Micrometre).unwrap(),
            data,
        )
        .unwrap()
    }

    /// Flood-fill labelling, voxel by voxel: the slow, obvious reference.
    fn flood_count(m: &Mask, full: bool) -> (usize, Vec<u64>) {
        let [nx, ny, nz] = m.dims();
        let mut seen = vec![false; m.data().len()];
        let mut sizes = Vec::new();
        for start in 0..seen.len() {
            if !m.data()[start] || seen[start] {
                continue;
            }
            let mut stack = vec![start];
            seen[start] = true;
            let mut size = 0;
            while let Some(p) = stack.pop() {
                size += 1;
                let [i, j, k] = m.geometry().ijk(p);
                for dk in -1i64..=1 {
                    for dj in -1i64..=1 {
                        for di in -1i64..=1 {
                            let nonzero = (di != 0) as i32 + (dj != 0) as i32 + (dk != 0) as i32;
                            if nonzero == 0 || (!full && nonzero > 1) {
                                continue;
                            }
                            let (a, b, c) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                            if a < 0
                                || b < 0
                                || c < 0
                                || a >= nx as i64
                                || b >= ny as i64
                                || c >= nz as i64
                            {
                                continue;
                            }
                            let q = m.geometry().index(a as usize, b as usize, c as usize);
                            if m.data()[q] && !seen[q] {
                                seen[q] = true;
                                stack.push(q);
                            }
                        }
                    }
                }
            }
            sizes.push(size);
        }
        (sizes.len(), sizes)
    }

    /// Hole filling by brute force: flood the face-connected background from
    /// every border voxel (of dimensions longer than one voxel, as
    /// `fill_holes` defines the border); whatever background is not reached is a hole.
    fn brute_fill(m: &Mask) -> Vec<bool> {
        let [nx, ny, nz] = m.dims();
        let g = m.geometry();
        let on_border = |i: usize, j: usize, k: usize| {
            (nx > 1 && (i == 0 || i == nx - 1))
                || (ny > 1 && (j == 0 || j == ny - 1))
                || (nz > 1 && (k == 0 || k == nz - 1))
        };
        let mut reached = vec![false; m.data().len()];
        let mut stack: Vec<usize> = (0..reached.len())
            .filter(|&p| {
                let [i, j, k] = g.ijk(p);
                !m.data()[p] && on_border(i, j, k)
            })
            .collect();
        for &p in &stack {
            reached[p] = true;
        }
        while let Some(p) = stack.pop() {
            let [i, j, k] = g.ijk(p);
            let steps: [(i64, i64, i64); 6] = [
                (-1, 0, 0),
                (1, 0, 0),
                (0, -1, 0),
                (0, 1, 0),
                (0, 0, -1),
                (0, 0, 1),
            ];
            for (di, dj, dk) in steps {
                let (a, b, c) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                if a < 0 || b < 0 || c < 0 || a >= nx as i64 || b >= ny as i64 || c >= nz as i64 {
                    continue;
                }
                let q = g.index(a as usize, b as usize, c as usize);
                if !m.data()[q] && !reached[q] {
                    reached[q] = true;
                    stack.push(q);
                }
            }
        }
        m.data()
            .iter()
            .zip(&reached)
            .map(|(&f, &r)| f || !r)
            .collect()
    }

    proptest! {
        #[test]
        fn fill_holes_matches_brute_force(nx in 1usize..8, ny in 1usize..8, nz in 1usize..7, seed in any::<u64>(), density in 1u64..4) {
            let n = nx * ny * nz;
            // Dense masks (up to 3/4 foreground) so that enclosed background occurs.
            let data: Vec<bool> = (0..n).map(|i| (seed.wrapping_mul(6364136223846793005).wrapping_add((i as u64).wrapping_mul(1442695040888963407)) >> 62) < density).collect();
            let m = mask([nx, ny, nz], data);
            let f = fill_holes(&m, Connectivity::Face);
            let want = brute_fill(&m);
            prop_assert_eq!(f.data(), want.as_slice());
        }
    }

    proptest! {
        #[test]
        fn components_match_flood_fill(nx in 1usize..7, ny in 1usize..7, nz in 1usize..6, seed in any::<u64>(), full in any::<bool>()) {
            let n = nx * ny * nz;
            let data: Vec<bool> = (0..n).map(|i| (seed.wrapping_mul(6364136223846793005).wrapping_add((i as u64).wrapping_mul(1442695040888963407)) >> 61) < 3).collect();
            let m = mask([nx, ny, nz], data);
            let conn = if full { Connectivity::Full } else { Connectivity::Face };
            let (labels, sizes) = label_components(&m, conn);
            let (count, ref_sizes) = flood_count(&m, full);
            prop_assert_eq!(sizes.len(), count);
            prop_assert_eq!(&sizes, &ref_sizes);
            // Every foreground voxel has a label, background none.
            for (l, &f) in labels.data().iter().zip(m.data()) {
                prop_assert_eq!(*l > 0, f);
            }
            let largest = largest_component(&m, conn);
            let want = ref_sizes.iter().copied().max().unwrap_or(0);
            prop_assert_eq!(largest.data().iter().filter(|&&b| b).count() as u64, want);
        }

        #[test]
        fn filled_mask_contains_the_mask_and_has_no_enclosed_background(nx in 1usize..7, ny in 1usize..7, nz in 1usize..6, seed in any::<u64>()) {
            let n = nx * ny * nz;
            let data: Vec<bool> = (0..n).map(|i| (seed.wrapping_mul(2862933555777941757).wrapping_add((i as u64).wrapping_mul(3037000493)) >> 62) != 0).collect();
            let m = mask([nx, ny, nz], data);
            let f = fill_holes(&m, Connectivity::Face);
            for (a, b) in m.data().iter().zip(f.data()) {
                prop_assert!(!*a || *b);
            }
            // Filling again changes nothing.
            let again = fill_holes(&f, Connectivity::Face);
            prop_assert_eq!(again.data(), f.data());
        }
    }

    #[test]
    fn diagonal_voxels_join_only_with_full_connectivity() {
        let mut d = vec![false; 8];
        d[0] = true; // (0,0,0)
        d[7] = true; // (1,1,1)
        let m = mask([2, 2, 2], d);
        assert_eq!(label_components(&m, Connectivity::Face).1, vec![1, 1]);
        assert_eq!(label_components(&m, Connectivity::Full).1, vec![2]);
    }

    #[test]
    fn hollow_cube_is_filled_in_3d_and_per_slice() {
        let n = 5;
        let mut m = Volume::<bool>::zeros(
            Geometry::new([n, n, n], [1.0; 3], LengthUnit::Micrometre).unwrap(),
        );
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let shell = [i, j, k].iter().any(|&c| c == 0 || c == n - 1);
                    m.set(i, j, k, shell);
                }
            }
        }
        let f = fill_holes(&m, Connectivity::Face);
        assert!(f.data().iter().all(|&b| b));
        // Per z slice, the inner slices are rings whose centres fill too.
        let s = fill_holes_per_slice(&m, Axis::Z);
        assert!(s.data().iter().all(|&b| b));
        // A ring open to the border is not a hole.
        let mut open = m.clone();
        open.set(0, 2, 2, false);
        open.set(1, 2, 2, false);
        let g = fill_holes(&open, Connectivity::Face);
        assert!(!g.get(2, 2, 2));
    }

    #[test]
    fn smoothing_preserves_constants_and_mass() {
        let g = Geometry::new([9, 8, 7], [0.5, 1.0, 2.0], LengthUnit::Micrometre).unwrap();
        let c = Volume::<u16>::filled(g.clone(), 300);
        let s = gaussian_smooth(&c, 1.5, &Cancel::new()).unwrap();
        assert!(s.data().iter().all(|&x| (x - 300.0).abs() < 1e-3));
        // An impulse far from the borders spreads with unit total weight,
        // symmetric about its voxel, wider along x (finer spacing).
        let mut imp = Volume::<f32>::zeros(
            Geometry::new([21, 21, 21], [0.5, 1.0, 1.0], LengthUnit::Micrometre).unwrap(),
        );
        imp.set(10, 10, 10, 1000.0);
        let s = gaussian_smooth(&imp, 1.0, &Cancel::new()).unwrap();
        let total: f32 = s.data().iter().sum();
        assert!((total - 1000.0).abs() < 0.5, "{total}");
        assert!((s.get(9, 10, 10) - s.get(11, 10, 10)).abs() < 1e-4);
        assert!(s.get(11, 10, 10) > s.get(10, 11, 10));
        assert!(gaussian_smooth(&imp, -1.0, &Cancel::new()).is_err());
        assert_eq!(mirror(-1, 4), 0);
        assert_eq!(mirror(4, 4), 3);
        assert_eq!(mirror(9, 4), 1);
    }
}
