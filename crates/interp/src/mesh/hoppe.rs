//! `unorganized-points`: surface reconstruction from unorganized points
//! (Hoppe, DeRose, Duchamp, McDonald & Stuetzle, SIGGRAPH 1992), the
//! original system's fifth method.
//!
//! Written here: no crate implements Hoppe's reconstruction. Steps:
//! 1. Points: the contours of the drawn slices, resampled every
//!    `max(pixel, min(gap / 2, median perimeter / 16))` so that a point's
//!    neighbourhood reaches the adjacent drawn slices (otherwise all
//!    neighbours lie on one contour line and the tangent plane is
//!    undetermined) yet stays a patch of the contours.
//! 2. Tangent planes: for each point, the centroid `o` and the covariance of
//!    its `k` nearest neighbours (k-d tree, `kiddo`); the normal is the
//!    eigenvector of the smallest eigenvalue (Jacobi rotations on the 3×3
//!    matrix).
//! 3. Orientation: a minimum spanning tree of the Riemannian graph (the
//!    symmetric k-nearest-neighbour graph, which contains the Euclidean MST
//!    edges between close points) with weights `1 - |n_i · n_j|`, traversed
//!    from a seed whose normal is set to point outwards (the point whose
//!    plane faces the centroid of its component most squarely, normal away
//!    from the centroid); each child's normal is flipped to agree with its
//!    parent. Every connected component (e.g. each of two far-apart
//!    nucleoli) gets its own seed.
//! 4. Signed distance of every grid sample to the tangent plane of the
//!    nearest centroid, `(p - o) · n`; undefined (treated as outside) where
//!    the projection of `p` on that plane is further than `ρ + δ` from `o`
//!    (`ρ + δ` = the gap between drawn slices plus one point spacing). The
//!    field is evaluated exactly near the data (found with core's distance
//!    transform) and once per 2³ (further out 4³) samples beyond, where the surface
//!    can only be the end caps.
//! 5. Marching cubes of the zero set, voxelised; drawn slices restored.
//!
//! The surface is smooth but cuts corners and caps the ends flat; the
//! original study found it less accurate than linear interpolation. Two
//! objects closer than about the gap between drawn slices can merge: between
//! them the nearest tangent plane may belong to either, and the sign flips. Objects
//! not much wider than the gap between drawn slices (small nucleoli when
//! many slices are skipped) get no usable tangent planes — the `k`
//! neighbours then span the whole object and the covariance has no clear
//! normal — and the surface degenerates into a blob around them; only the
//! drawn slices stay exact there.
use super::{
    FieldBox, Frame, contour_points, drawn_contours, mean_gap, point_bounds, voxelise_surface,
};
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::Mask;
use interslice_core::mesh::TriMesh;
use interslice_core::regions::UnionFind;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZero;

/// A tangent plane: centroid and unit normal.
type Plane = ([f64; 3], [f64; 3]);

/// Hoppe's reconstruction and its parameters.
#[derive(Debug, Clone, Copy)]
pub struct UnorganizedPoints {
    /// Neighbours per tangent plane.
    pub k: usize,
}

impl Default for UnorganizedPoints {
    fn default() -> Self {
        UnorganizedPoints { k: 16 }
    }
}

/// Eigenvector of the smallest eigenvalue of a symmetric 3×3 matrix, by
/// cyclic Jacobi rotations (a few sweeps converge to machine precision).
pub fn smallest_eigenvector(m: [[f64; 3]; 3]) -> [f64; 3] {
    let mut a = m;
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off <= 1e-300 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A' = J^T A J with J the rotation in the (p, q) plane.
            for row in &mut a {
                let (arp, arq) = (row[p], row[q]);
                row[p] = c * arp - s * arq;
                row[q] = s * arp + c * arq;
            }
            let (rp, rq) = (a[p], a[q]);
            for r in 0..3 {
                a[p][r] = c * rp[r] - s * rq[r];
                a[q][r] = s * rp[r] + c * rq[r];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let i = (0..3)
        .min_by(|&x, &y| a[x][x].total_cmp(&a[y][y]))
        .unwrap_or(0);
    [v[0][i], v[1][i], v[2][i]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl UnorganizedPoints {
    /// Tangent planes `(centroid, unit normal)` of the points, consistently
    /// oriented outwards.
    pub fn tangent_planes(&self, points: &[[f64; 3]]) -> Vec<Plane> {
        let n = points.len();
        if n == 0 {
            return Vec::new();
        }
        let k = self.k.clamp(1, n);
        let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(points);
        let kk = NonZero::new(k).expect("k >= 1");
        let (neigh, mut planes): (Vec<Vec<u32>>, Vec<Plane>) = points
            .par_iter()
            .map(|p| {
                let nn = tree.nearest_n::<SquaredEuclidean>(p, kk);
                let ids: Vec<u32> = nn.iter().map(|x| x.item as u32).collect();
                let mut o = [0.0; 3];
                for &i in &ids {
                    for d in 0..3 {
                        o[d] += points[i as usize][d] / ids.len() as f64;
                    }
                }
                let mut cov = [[0.0; 3]; 3];
                for &i in &ids {
                    let q = points[i as usize];
                    let e = [q[0] - o[0], q[1] - o[1], q[2] - o[2]];
                    for r in 0..3 {
                        for c in 0..3 {
                            cov[r][c] += e[r] * e[c];
                        }
                    }
                }
                (ids, (o, smallest_eigenvector(cov)))
            })
            .unzip();
        // Riemannian graph edges, lightest first (ties broken by index).
        let mut edges: Vec<(f64, u32, u32)> = Vec::with_capacity(n * k);
        for (i, ids) in neigh.iter().enumerate() {
            for &j in ids {
                if j as usize != i {
                    let (a, b) = (i.min(j as usize) as u32, i.max(j as usize) as u32);
                    let w = 1.0 - dot(planes[a as usize].1, planes[b as usize].1).abs();
                    edges.push((w, a, b));
                }
            }
        }
        edges.par_sort_unstable_by(|x, y| {
            x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2))
        });
        edges.dedup_by(|x, y| x.1 == y.1 && x.2 == y.2);
        // Kruskal: the minimum spanning forest.
        let mut uf: UnionFind<u32> = UnionFind::new(n);
        let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
        for &(_, a, b) in &edges {
            if uf.union(a, b) {
                adj[a as usize].push(b);
                adj[b as usize].push(a);
            }
        }
        // One seed per component: the point whose tangent plane faces the
        // component's centroid most squarely from furthest away (largest
        // |n · (p - c)|), its normal turned away from the centroid. On a
        // closed surface that point is on the outer hull, so its outward
        // side is unambiguous (unlike "largest u", whose normal may be
        // perpendicular to u at a corner).
        let mut roots: Vec<u32> = (0..n as u32).map(|i| uf.find_mut(i)).collect();
        let mut sum: std::collections::HashMap<u32, ([f64; 3], f64)> =
            std::collections::HashMap::new();
        for (i, &r) in roots.iter().enumerate() {
            let e = sum.entry(r).or_insert(([0.0; 3], 0.0));
            for (acc, x) in e.0.iter_mut().zip(points[i]) {
                *acc += x;
            }
            e.1 += 1.0;
        }
        let mut best: std::collections::HashMap<u32, (f64, u32)> = std::collections::HashMap::new();
        for (i, &r) in roots.iter().enumerate() {
            let (s, m) = sum[&r];
            let c = s.map(|x| x / m);
            let rel = [
                points[i][0] - c[0],
                points[i][1] - c[1],
                points[i][2] - c[2],
            ];
            let score = dot(planes[i].1, rel).abs();
            let e = best.entry(r).or_insert((f64::NEG_INFINITY, i as u32));
            if score > e.0 {
                *e = (score, i as u32);
            }
        }
        roots.clear();
        let mut seeds: Vec<u32> = best.into_values().map(|(_, i)| i).collect();
        seeds.sort_unstable();
        for &s in &seeds {
            let r = uf.find_mut(s);
            let (sm, m) = sum[&r];
            let c = sm.map(|x| x / m);
            let p = points[s as usize];
            if dot(
                planes[s as usize].1,
                [p[0] - c[0], p[1] - c[1], p[2] - c[2]],
            ) < 0.0
            {
                planes[s as usize].1 = planes[s as usize].1.map(|x| -x);
            }
        }
        let mut done = vec![false; n];
        for s in seeds {
            done[s as usize] = true;
            let mut stack = vec![s];
            while let Some(p) = stack.pop() {
                let np = planes[p as usize].1;
                for &c in &adj[p as usize] {
                    if !done[c as usize] {
                        done[c as usize] = true;
                        if dot(planes[c as usize].1, np) < 0.0 {
                            planes[c as usize].1 = planes[c as usize].1.map(|x| -x);
                        }
                        stack.push(c);
                    }
                }
            }
        }
        // A safeguard the paper does not need with dense samples: when most
        // normals of a component point towards its centroid, the propagation
        // went wrong from the start (a small object whose neighbourhoods span
        // all of it), so the whole component is turned outwards.
        let mut vote: std::collections::HashMap<u32, f64> = std::collections::HashMap::new();
        for i in 0..n {
            let r = uf.find_mut(i as u32);
            let (sm, m) = sum[&r];
            let rel: [f64; 3] = std::array::from_fn(|d| points[i][d] - sm[d] / m);
            *vote.entry(r).or_insert(0.0) += dot(planes[i].1, rel).signum();
        }
        for (i, plane) in planes.iter_mut().enumerate() {
            let r = uf.find_mut(i as u32);
            if vote[&r] < 0.0 {
                plane.1 = plane.1.map(|x| -x);
            }
        }
        planes
    }

    /// Hoppe's surface of the input, in physical (x, y, z).
    pub fn surface(&self, input: &SparseMask<'_>) -> TriMesh {
        let frame = Frame::of(input);
        let pixel = frame.spacing[0].min(frame.spacing[1]);
        let gap = mean_gap(input, &frame);
        // Half a gap between points along the contours, but at least 16
        // points on the median contour, so that the k neighbours of a point
        // span a patch of its own contour and the adjacent ones rather than
        // whole small contours (whose covariance has no clear normal).
        let perimeter = median_perimeter(input, &frame);
        let step = pixel.max((0.5 * gap).min(perimeter / 16.0));
        let points = contour_points(input, &frame, step);
        let Some((lo, hi)) = point_bounds(&points) else {
            return TriMesh::new();
        };
        let planes = self.tangent_planes(&points);
        let centres: Vec<[f64; 3]> = planes.iter().map(|p| p.0).collect();
        let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&centres);
        // How far along its plane a tangent plane is trusted (Hoppe's
        // rho + delta): the gap between drawn slices plus one point spacing,
        // so that every point of the surface between two drawn slices is
        // within reach of a centre on one of them; beyond it f is undefined
        // and taken as outside, which caps the ends about that far out.
        let reach = gap + step;
        let reach2 = reach * reach;
        let fbox = FieldBox::around(&frame, lo, hi, reach);
        let signed = |p: [f64; 3]| -> f32 {
            let i = tree.nearest_one::<SquaredEuclidean>(&p).item as usize;
            let (o, n) = planes[i];
            let e = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
            let s = dot(e, n);
            let along2 = dot(e, e) - s * s;
            // Value = minus the signed distance: inside is > 0.
            if along2 > reach2 { -1.0 } else { -s as f32 }
        };
        // f is evaluated exactly (one k-d tree query per sample) within reach
        // of the tangent-plane centres, plus the error of the seed distance
        // and one sample, so that every edge the surface can cross near the
        // data has exact values at both ends. Further out (the interior of a
        // large object, the space around it, the end caps), where the nearest
        // centre is far and every query expensive, f is evaluated once per
        // 2×2×2 block of samples and shared by the block.
        let (dist, e) = fbox.seed_distance(&centres);
        let s_max = frame.spacing.iter().copied().fold(0.0, f64::max);
        let near = reach + e + s_max;
        let [nu, nv, nw] = fbox.size;
        // Coarse evaluations: once per 2³ samples beyond `near`, once per 4³
        // samples beyond `near + 8 s` (deep inside large objects and far
        // outside, where every query is expensive and the sign is all that
        // matters).
        let coarse = |block: usize, limit: f64| -> Vec<f32> {
            let (cu, cv, cw) = (nu.div_ceil(block), nv.div_ceil(block), nw.div_ceil(block));
            let mut out = vec![0f32; cu * cv * cw];
            out.par_chunks_mut(cu * cv)
                .enumerate()
                .for_each(|(c, plane)| {
                    for b in 0..cv {
                        for a in 0..cu {
                            let (ia, ib, ic) = (block * a, block * b, block * c);
                            if f64::from(dist[ia + nu * (ib + nv * ic)]) > limit {
                                let q =
                                    [fbox.coords[0][ia], fbox.coords[1][ib], fbox.coords[2][ic]];
                                plane[a + cu * b] = signed(q);
                            }
                        }
                    }
                });
            out
        };
        // A corner lies within sqrt(3) (block - 1) samples of its block.
        let far4 = near + 8.0 * s_max;
        let coarse2 = coarse(2, near - 2.0 * s_max);
        let coarse4 = coarse(4, far4 - 6.0 * s_max);
        let values = fbox.evaluate_guided(
            -1.0,
            |i| {
                let d = f64::from(dist[i]);
                let (a, b, c) = (i % nu, (i / nu) % nv, i / (nu * nv));
                if d > far4 {
                    let (cu, cv) = (nu.div_ceil(4), nv.div_ceil(4));
                    Some(coarse4[a / 4 + cu * (b / 4 + cv * (c / 4))])
                } else if d > near {
                    let (cu, cv) = (nu.div_ceil(2), nv.div_ceil(2));
                    Some(coarse2[a / 2 + cu * (b / 2 + cv * (c / 2))])
                } else {
                    None
                }
            },
            signed,
        );
        frame.to_xyz(fbox.iso_surface(&values, 0.0))
    }
}

/// The median perimeter (physical) of the contours of the drawn slices.
fn median_perimeter(input: &SparseMask<'_>, frame: &Frame) -> f64 {
    let pixel = frame.spacing[0].min(frame.spacing[1]);
    let mut per: Vec<f64> = drawn_contours(input, frame, pixel)
        .map(|pts| {
            let n = pts.len();
            (0..n)
                .map(|i| {
                    let (a, b) = (pts[i], pts[(i + 1) % n]);
                    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
                })
                .sum::<f64>()
        })
        .collect();
    per.sort_by(f64::total_cmp);
    per.get(per.len() / 2).copied().unwrap_or(0.0)
}

impl Interpolator for UnorganizedPoints {
    fn name(&self) -> &'static str {
        "unorganized-points"
    }
    fn description(&self) -> &'static str {
        "original: Hoppe 1992 surface from the contour points (tangent planes, MST orientation), voxelised"
    }
    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        voxelise_surface(self, input)
    }
    fn surface_mesh(&self, input: SparseMask<'_>) -> Result<Option<TriMesh>, InterpError> {
        input.validate()?;
        Ok(Some(self.surface(&input)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvector_of_a_flat_cloud_is_its_normal() {
        let m = [[4.0, 1.0, 0.0], [1.0, 3.0, 0.0], [0.0, 0.0, 0.01]];
        let v = smallest_eigenvector(m);
        assert!((v[2].abs() - 1.0).abs() < 1e-9, "{v:?}");
        // A rotated diagonal matrix.
        let (c, s) = (0.6f64, 0.8f64);
        let m = [
            [c * c * 1.0 + s * s * 5.0, c * s * (1.0 - 5.0), 0.0],
            [c * s * (1.0 - 5.0), s * s + c * c * 5.0, 0.0],
            [0.0, 0.0, 3.0],
        ];
        let v = smallest_eigenvector(m);
        assert!(
            (v[0].abs() - c).abs() < 1e-9 && (v[1].abs() - s).abs() < 1e-9,
            "{v:?}"
        );
    }

    #[test]
    fn sphere_normals_point_outwards() {
        let mut pts = Vec::new();
        for a in 0..20 {
            for b in 1..20 {
                let (t, p) = (
                    a as f64 * std::f64::consts::TAU / 20.0,
                    b as f64 * std::f64::consts::PI / 20.0,
                );
                pts.push([
                    10.0 * p.sin() * t.cos(),
                    10.0 * p.sin() * t.sin(),
                    10.0 * p.cos(),
                ]);
            }
        }
        let planes = UnorganizedPoints::default().tangent_planes(&pts);
        let outward = planes.iter().filter(|(o, n)| dot(*o, *n) > 0.0).count();
        assert_eq!(outward, pts.len());
    }
}
