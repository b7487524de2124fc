//! Voxelisation of closed triangle meshes by parity ray casting.
//!
//! Written here: the crates that voxelise meshes sample on their own grids or
//! use floating-point tests that miss or double-count rays passing exactly
//! through an edge or vertex, which happens all the time for meshes built on
//! the voxel grid (marching-cubes vertices sit on half-voxel positions).
//!
//! A voxel is inside when its centre `((i+0.5) sx, (j+0.5) sy, (k+0.5) sz)`
//! is inside the mesh: the ray from the centre towards -x crosses the mesh an
//! odd number of times. Each row `(j, k)` is handled once: every triangle
//! whose projection on the (y, z) plane contains the row's centre gives one
//! crossing at the exact x where the row meets its plane. The containment
//! test uses exact orientation predicates (`robust::orient2d`) and a
//! symbolic perturbation of the row point by `(ε, ε²)` in (y, z), so a row
//! through a shared edge or vertex is counted in exactly one of the
//! triangles around it, and triangles seen edge-on are never counted. The
//! result is exact for any closed mesh (self-intersections count by parity).
use interslice_core::mesh::TriMesh;
use interslice_core::{Geometry, Mask, Volume};
use rayon::prelude::*;
use robust::{Coord, orient2d};

/// Sign of `orient2d(a, b, q + (ε, ε²))` for an infinitesimal ε: never 0
/// unless `a == b`.
#[inline]
fn perturbed_orient(a: Coord<f64>, b: Coord<f64>, q: Coord<f64>) -> i8 {
    let d = orient2d(a, b, q);
    let s = if d != 0.0 {
        d
    } else if a.y != b.y {
        a.y - b.y
    } else {
        b.x - a.x
    };
    if s > 0.0 {
        1
    } else if s < 0.0 {
        -1
    } else {
        0
    }
}

/// Where the row through `q` = (y, z) crosses triangle `t` (projected corners
/// `p`, x coordinates `xs`), or `None` when it does not; `orient` is the sign
/// of the projected triangle (non-zero).
#[inline]
fn crossing(p: &[Coord<f64>; 3], xs: [f64; 3], orient: i8, q: Coord<f64>) -> Option<f64> {
    for e in 0..3 {
        if perturbed_orient(p[e], p[(e + 1) % 3], q) != orient {
            return None;
        }
    }
    // Barycentric weights from the (floating-point) sub-areas.
    let wa = orient2d(p[1], p[2], q);
    let wb = orient2d(p[2], p[0], q);
    let wc = orient2d(p[0], p[1], q);
    let sum = wa + wb + wc;
    if sum == 0.0 {
        return Some((xs[0] + xs[1] + xs[2]) / 3.0);
    }
    Some((wa * xs[0] + wb * xs[1] + wc * xs[2]) / sum)
}

/// Position of voxel centre `n` along an axis of spacing `s`, computed the
/// same way everywhere (mesh builders place vertices with this formula).
#[inline]
fn centre(n: usize, s: f64) -> f64 {
    (n as f64 + 0.5) * s
}

/// Index range `lo..=hi` of voxel centres `(n + 0.5) * s` within `[a, b]`,
/// clamped to `0..len`; `None` when empty.
///
/// The estimate from `a / s` is corrected by comparing with the centre
/// positions themselves: a vertex placed exactly on a centre plane (as
/// marching-cubes vertices are) must count as touching it, and rounding in
/// `a / s - 0.5` could otherwise move the bound by one (e.g. `26.5 * 0.8`).
fn centre_range(a: f64, b: f64, s: f64, len: usize) -> Option<(usize, usize)> {
    if len == 0 || a.partial_cmp(&b).is_none_or(|o| o.is_gt()) {
        return None;
    }
    let last = len - 1;
    let est = |x: f64| -> usize { (x / s - 0.5).clamp(0.0, last as f64) as usize };
    // Smallest n with centre(n) >= a.
    let mut lo = est(a);
    while lo > 0 && centre(lo - 1, s) >= a {
        lo -= 1;
    }
    while lo <= last && centre(lo, s) < a {
        lo += 1;
    }
    // Largest n with centre(n) <= b.
    let mut hi = est(b);
    while hi < last && centre(hi + 1, s) <= b {
        hi += 1;
    }
    loop {
        if centre(hi, s) <= b {
            break;
        }
        if hi == 0 {
            return None;
        }
        hi -= 1;
    }
    (lo <= hi).then_some((lo, hi))
}

/// Index range `lo..=hi` of voxel centres with `a < centre <= b` (the part
/// of a row between two crossings), clamped to `0..len`.
fn open_closed_range(a: f64, b: f64, s: f64, len: usize) -> Option<(usize, usize)> {
    let (lo, hi) = centre_range(a, b, s, len)?;
    let lo = if centre(lo, s) == a { lo + 1 } else { lo };
    (lo <= hi).then_some((lo, hi))
}

/// Voxelise a closed mesh (physical units, see [`TriMesh`]) into a mask of
/// the given geometry's dims and spacing. An open mesh gives a mask that
/// depends on which way rays leak; callers pass closed meshes.
pub fn voxelize(mesh: &TriMesh, geometry: &Geometry) -> Mask {
    let [nx, ny, nz] = geometry.dims;
    let [sx, sy, sz] = geometry.spacing;
    // Triangles whose z-extent covers each row plane k.
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); nz];
    for t in 0..mesh.triangles.len() {
        let c = mesh.corners(t);
        let zmin = c[0][2].min(c[1][2]).min(c[2][2]);
        let zmax = c[0][2].max(c[1][2]).max(c[2][2]);
        if let Some((k0, k1)) = centre_range(zmin, zmax, sz, nz) {
            for b in &mut buckets[k0..=k1] {
                b.push(t as u32);
            }
        }
    }
    let mut data = vec![false; nx * ny * nz];
    data.par_chunks_mut(nx * ny)
        .zip(buckets.par_iter())
        .enumerate()
        .for_each(|(k, (plane, bucket))| {
            if bucket.is_empty() {
                return;
            }
            let z = centre(k, sz);
            let mut hits: Vec<(u32, f64)> = Vec::new();
            for &t in bucket {
                let c = mesh.corners(t as usize);
                let p = c.map(|v| Coord { x: v[1], y: v[2] });
                let area = orient2d(p[0], p[1], p[2]);
                if area == 0.0 {
                    continue;
                }
                let orient = if area > 0.0 { 1 } else { -1 };
                let ymin = c[0][1].min(c[1][1]).min(c[2][1]);
                let ymax = c[0][1].max(c[1][1]).max(c[2][1]);
                let Some((j0, j1)) = centre_range(ymin, ymax, sy, ny) else {
                    continue;
                };
                let xs = [c[0][0], c[1][0], c[2][0]];
                for j in j0..=j1 {
                    let q = Coord {
                        x: centre(j, sy),
                        y: z,
                    };
                    if let Some(x) = crossing(&p, xs, orient, q) {
                        hits.push((j as u32, x));
                    }
                }
            }
            hits.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
            for row in hits.chunk_by(|a, b| a.0 == b.0) {
                let j = row[0].0 as usize;
                let line = &mut plane[nx * j..nx * (j + 1)];
                for pair in row.chunks(2) {
                    if pair.len() < 2 {
                        break;
                    }
                    // Centres with x0 < x <= x1 are inside.
                    if let Some((lo, hi)) = open_closed_range(pair[0].1, pair[1].1, sx, nx) {
                        line[lo..=hi].fill(true);
                    }
                }
            }
        });
    Volume::from_vec(geometry.clone(), data).expect("data length matches the geometry")
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::LengthUnit;

    #[test]
    fn centre_range_is_inclusive_and_clamped() {
        assert_eq!(centre_range(0.5, 2.5, 1.0, 10), Some((0, 2)));
        assert_eq!(centre_range(0.6, 1.4, 1.0, 10), None);
        assert_eq!(centre_range(-5.0, 50.0, 1.0, 10), Some((0, 9)));
        assert_eq!(centre_range(-5.0, -1.0, 1.0, 10), None);
        assert_eq!(centre_range(11.0, 12.0, 1.0, 10), None);
        // 26.5 * 0.8 / 0.8 - 0.5 rounds above 26: the centre must still count.
        let z = centre(26, 0.8);
        assert!(z / 0.8 - 0.5 > 26.0);
        assert_eq!(centre_range(z, z + 0.1, 0.8, 40), Some((26, 26)));
        assert_eq!(centre_range(z - 0.1, z, 0.8, 40), Some((26, 26)));
        assert_eq!(open_closed_range(z, z + 0.9, 0.8, 40), Some((27, 27)));
    }

    #[test]
    fn perturbation_breaks_ties_consistently() {
        // q on the shared edge of two triangles: exactly one contains it.
        let a = Coord { x: 0.0, y: 0.0 };
        let b = Coord { x: 2.0, y: 2.0 };
        let c = Coord { x: 2.0, y: 0.0 };
        let d = Coord { x: 0.0, y: 2.0 };
        let q = Coord { x: 1.0, y: 1.0 };
        let t1 = [a, b, c];
        let t2 = [a, d, b];
        let o = |t: &[Coord<f64>; 3]| {
            if orient2d(t[0], t[1], t[2]) > 0.0 {
                1
            } else {
                -1
            }
        };
        let h1 = crossing(&t1, [0.0; 3], o(&t1), q).is_some();
        let h2 = crossing(&t2, [0.0; 3], o(&t2), q).is_some();
        assert!(h1 ^ h2);
    }

    #[test]
    fn box_mesh_fills_its_voxels() {
        let g = Geometry::new([6, 5, 4], [1.0, 0.5, 2.0], LengthUnit::Micrometre).unwrap();
        // Box [1, 4] x [0.5, 2.0] x [2, 6]: centres i in 1..=3, j in 1..=3, k in 1..=2.
        let (lo, hi) = ([1.0, 0.5, 2.0], [4.0, 2.0, 6.0]);
        let v: Vec<[f64; 3]> = (0..8)
            .map(|c| {
                [
                    if c & 1 == 0 { lo[0] } else { hi[0] },
                    if c & 2 == 0 { lo[1] } else { hi[1] },
                    if c & 4 == 0 { lo[2] } else { hi[2] },
                ]
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut m = TriMesh {
            vertices: v,
            triangles: vec![],
        };
        for q in quads {
            m.triangles.push([q[0], q[1], q[2]]);
            m.triangles.push([q[0], q[2], q[3]]);
        }
        let mask = voxelize(&m, &g);
        for k in 0..4 {
            for j in 0..5 {
                for i in 0..6 {
                    let want = (1..=3).contains(&i) && (1..=3).contains(&j) && (1..=2).contains(&k);
                    assert_eq!(mask.get(i, j, k), want, "voxel {i} {j} {k}");
                }
            }
        }
    }
}
