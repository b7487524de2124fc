//! Marching cubes (Lorensen & Cline 1987) with a consistent topology.
//!
//! Written here: no crate offers marching cubes on a rectilinear grid with
//! non-uniform sample positions (needed to stretch the drawn-slice stack back
//! to full size) and a guaranteed closed, consistently oriented output.
//!
//! # The case table
//!
//! The 256-case table is *generated* from the cube's faces when first used
//! (see [`case_table`]), not copied: for each corner configuration, each face
//! of the cube is walked counter-clockwise (seen from outside the cube) and
//! every maximal run of inside corners gives one directed segment from the
//! edge where the walk enters the run to the edge where it leaves. On an
//! ambiguous face (two inside corners on a diagonal) the two corners form two
//! runs, so inside corners that touch only diagonally are always kept apart.
//! Because that rule depends only on the face's four corners, the two cubes
//! sharing a face produce the same segments with opposite directions, which
//! makes the surface closed and consistently oriented (every edge used by
//! exactly two triangles, once in each direction). The segments of one cube
//! chain into closed loops (each edge point has one outgoing and one incoming
//! segment); a loop of 3 or 4 points becomes 1 or 2 triangles, a longer loop
//! a fan around its centroid (an extra vertex), so no triangle edge can
//! coincide with a segment of a neighbouring cube.
//!
//! Orientation: loops run counter-clockwise seen from outside the inside
//! region, so triangle normals point from inside (value > iso) to outside.
use interslice_core::mesh::TriMesh;
use rayon::prelude::*;
use std::sync::OnceLock;

/// The two corners of each of the 12 cube edges. Corner `c` sits at
/// `(c & 1, (c >> 1) & 1, (c >> 2) & 1)`. Edges 0..4 run along x, 4..8
/// along y, 8..12 along z.
pub const EDGES: [(u8, u8); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// The six faces of the cube, corners counter-clockwise seen from outside.
const FACES: [[u8; 4]; 6] = [
    [0, 2, 3, 1], // z = 0
    [4, 5, 7, 6], // z = 1
    [0, 1, 5, 4], // y = 0
    [2, 6, 7, 3], // y = 1
    [0, 4, 6, 2], // x = 0
    [1, 3, 7, 5], // x = 1
];

fn edge_of(a: u8, b: u8) -> u8 {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    EDGES
        .iter()
        .position(|&e| e == (a, b))
        .expect("adjacent corners") as u8
}

/// For each of the 256 corner configurations (bit `c` set = corner `c`
/// inside), the closed loops of intersected edges, each oriented
/// counter-clockwise seen from outside the inside region.
pub fn case_table() -> &'static [Vec<Vec<u8>>; 256] {
    static TABLE: OnceLock<[Vec<Vec<u8>>; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|case| loops_of_case(case as u8)))
}

fn loops_of_case(case: u8) -> Vec<Vec<u8>> {
    let inside = |c: u8| case >> c & 1 == 1;
    let mut next = [u8::MAX; 12];
    for f in FACES {
        for i in 0..4 {
            let (a, b) = (f[i], f[(i + 1) % 4]);
            if inside(a) || !inside(b) {
                continue;
            }
            // Enter the run at edge (a, b); walk to its last inside corner.
            let mut j = (i + 1) % 4;
            while inside(f[(j + 1) % 4]) {
                j = (j + 1) % 4;
            }
            next[edge_of(a, b) as usize] = edge_of(f[j], f[(j + 1) % 4]);
        }
    }
    let mut loops = Vec::new();
    let mut seen = [false; 12];
    for start in 0..12u8 {
        if next[start as usize] == u8::MAX || seen[start as usize] {
            continue;
        }
        let mut lp = Vec::new();
        let mut e = start;
        while !seen[e as usize] {
            seen[e as usize] = true;
            lp.push(e);
            e = next[e as usize];
        }
        loops.push(lp);
    }
    loops
}

/// A scalar field sampled on a rectilinear grid: `values[i + nx*(j + ny*k)]`
/// at the physical point `(xs[i], ys[j], zs[k])`. Sample positions must
/// increase along each axis (they need not be evenly spaced).
#[derive(Debug, Clone, Copy)]
pub struct Grid<'a, T> {
    /// Samples, x-fastest (`f32` fields, or `u8` 0/1 masks to save memory).
    pub values: &'a [T],
    /// Sample positions along x.
    pub xs: &'a [f64],
    /// Sample positions along y.
    pub ys: &'a [f64],
    /// Sample positions along z.
    pub zs: &'a [f64],
}

/// Vertices created on one grid plane: the crossed x/y edges in plane k and
/// the crossed z edges from plane k to k + 1, keyed by `3 * (i + nx*j) + dir`.
struct PlaneVerts {
    keys: Vec<u32>,
    pos: Vec<[f64; 3]>,
}

impl PlaneVerts {
    fn find(&self, key: u32) -> u32 {
        self.keys
            .binary_search(&key)
            .expect("crossed edge has a vertex") as u32
    }
}

const EXTRA: u32 = 1 << 31;

/// The triangles of one layer of cubes and the extra (loop centre) vertices
/// they refer to with the `EXTRA` bit.
type Layer = (Vec<[u32; 3]>, Vec<[f64; 3]>);

/// The iso-surface `value = iso` of a grid: a closed, outward-oriented mesh
/// around the region `value > iso` (open only where that region touches the
/// grid border; pad the grid with an outside layer to close it). Work is
/// spread over the grid's z planes with rayon.
pub fn marching_cubes<T: Copy + Into<f32> + Sync>(grid: Grid<'_, T>, iso: f32) -> TriMesh {
    let (nx, ny, nz) = (grid.xs.len(), grid.ys.len(), grid.zs.len());
    assert_eq!(
        grid.values.len(),
        nx * ny * nz,
        "grid values must match the coordinates"
    );
    if nx < 2 || ny < 2 || nz < 2 {
        return TriMesh::new();
    }
    assert!(3 * nx * ny < EXTRA as usize, "grid plane too large");
    let v = grid.values;
    let at = |i: usize, j: usize, k: usize| -> f32 { v[i + nx * (j + ny * k)].into() };
    let lerp = |a: f32, b: f32, pa: f64, pb: f64| -> f64 {
        let t = f64::from((iso - a) / (b - a)).clamp(0.0, 1.0);
        pa + t * (pb - pa)
    };
    // Pass 1: the vertices owned by each plane.
    let planes: Vec<PlaneVerts> = (0..nz)
        .into_par_iter()
        .map(|k| {
            let mut pv = PlaneVerts {
                keys: Vec::new(),
                pos: Vec::new(),
            };
            let z = grid.zs[k];
            for j in 0..ny {
                let y = grid.ys[j];
                for i in 0..nx {
                    let a = at(i, j, k);
                    let ain = a > iso;
                    let base = (3 * (i + nx * j)) as u32;
                    if i + 1 < nx {
                        let b = at(i + 1, j, k);
                        if ain != (b > iso) {
                            pv.keys.push(base);
                            pv.pos.push([lerp(a, b, grid.xs[i], grid.xs[i + 1]), y, z]);
                        }
                    }
                    if j + 1 < ny {
                        let b = at(i, j + 1, k);
                        if ain != (b > iso) {
                            pv.keys.push(base + 1);
                            pv.pos.push([grid.xs[i], lerp(a, b, y, grid.ys[j + 1]), z]);
                        }
                    }
                    if k + 1 < nz {
                        let b = at(i, j, k + 1);
                        if ain != (b > iso) {
                            pv.keys.push(base + 2);
                            pv.pos.push([grid.xs[i], y, lerp(a, b, z, grid.zs[k + 1])]);
                        }
                    }
                }
            }
            pv
        })
        .collect();
    let mut offsets = Vec::with_capacity(nz + 1);
    let mut total = 0usize;
    for p in &planes {
        offsets.push(total as u32);
        total += p.pos.len();
    }
    let table = case_table();
    // Pass 2: the triangles of each layer of cubes (between planes k and k+1).
    let layers: Vec<Layer> = (0..nz - 1)
        .into_par_iter()
        .map(|k| {
            let mut tris = Vec::new();
            let mut extra: Vec<[f64; 3]> = Vec::new();
            let (p0, p1) = (&planes[k], &planes[k + 1]);
            let (o0, o1) = (offsets[k], offsets[k + 1]);
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let mut case = 0u8;
                    for c in 0..8u8 {
                        let (di, dj, dk) = (
                            (c & 1) as usize,
                            (c >> 1 & 1) as usize,
                            (c >> 2 & 1) as usize,
                        );
                        if at(i + di, j + dj, k + dk) > iso {
                            case |= 1 << c;
                        }
                    }
                    if case == 0 || case == 255 {
                        continue;
                    }
                    // Global vertex index of cube edge e.
                    let vert = |e: u8| -> u32 {
                        let (a, b) = EDGES[e as usize];
                        let (ci, cj, ck) = (
                            (a & 1) as usize,
                            (a >> 1 & 1) as usize,
                            (a >> 2 & 1) as usize,
                        );
                        let dir = match a ^ b {
                            1 => 0,
                            2 => 1,
                            _ => 2,
                        };
                        let key = (3 * ((i + ci) + nx * (j + cj)) + dir) as u32;
                        if ck == 0 {
                            o0 + p0.find(key)
                        } else {
                            o1 + p1.find(key)
                        }
                    };
                    for lp in &table[case as usize] {
                        let ids: Vec<u32> = lp.iter().map(|&e| vert(e)).collect();
                        match ids.len() {
                            3 => tris.push([ids[0], ids[1], ids[2]]),
                            4 => {
                                tris.push([ids[0], ids[1], ids[2]]);
                                tris.push([ids[0], ids[2], ids[3]]);
                            }
                            n => {
                                let pos = |g: u32| -> [f64; 3] {
                                    let kk = offsets.partition_point(|&o| o <= g) - 1;
                                    planes[kk].pos[(g - offsets[kk]) as usize]
                                };
                                let mut c = [0.0; 3];
                                for &g in &ids {
                                    let p = pos(g);
                                    for d in 0..3 {
                                        c[d] += p[d] / n as f64;
                                    }
                                }
                                let cid = EXTRA | extra.len() as u32;
                                extra.push(c);
                                for t in 0..n {
                                    tris.push([ids[t], ids[(t + 1) % n], cid]);
                                }
                            }
                        }
                    }
                }
            }
            (tris, extra)
        })
        .collect();
    let mut mesh = TriMesh::new();
    mesh.vertices
        .reserve(total + layers.iter().map(|l| l.1.len()).sum::<usize>());
    for p in planes {
        mesh.vertices.extend(p.pos);
    }
    for (tris, extra) in layers {
        let base = mesh.vertices.len() as u32;
        mesh.vertices.extend(extra);
        mesh.triangles.extend(tris.into_iter().map(|t| {
            t.map(|g| {
                if g & EXTRA != 0 {
                    base + (g & !EXTRA)
                } else {
                    g
                }
            })
        }));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_has_all_cases_and_complements_mirror() {
        let t = case_table();
        assert!(t[0].is_empty() && t[255].is_empty());
        for (case, loops) in t.iter().enumerate().take(255).skip(1) {
            assert!(!loops.is_empty(), "case {case} has a surface");
            // Each crossed edge appears in exactly one loop.
            let crossed: usize = EDGES
                .iter()
                .filter(|&&(a, b)| (case >> a & 1) != (case >> b & 1))
                .count();
            let used: usize = loops.iter().map(|l| l.len()).sum();
            assert_eq!(crossed, used, "case {case}");
            assert!(loops.iter().all(|l| l.len() >= 3));
        }
        // A single corner gives one triangle; the checkerboard four.
        assert_eq!(t[1].len(), 1);
        assert_eq!(t[1][0].len(), 3);
        assert_eq!(t[0b1001_0110].len(), 4);
        assert_eq!(t[0b0110_1001].len(), 4);
    }

    #[test]
    fn single_voxel_is_a_closed_octahedron() {
        let mut values = vec![0f32; 27];
        values[13] = 1.0;
        let c = [0.0, 1.0, 2.0];
        let m = marching_cubes(
            Grid {
                values: &values,
                xs: &c,
                ys: &c,
                zs: &c,
            },
            0.5,
        );
        assert_eq!(m.triangles.len(), 8);
        assert!(m.is_closed_and_oriented());
        // Octahedron with half-diagonals 0.5: volume 4/3 * 0.5^3.
        assert!((m.signed_volume() - 4.0 / 3.0 * 0.125).abs() < 1e-12);
    }
}
