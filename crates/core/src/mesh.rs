//! Triangle surface meshes in physical units.
//!
//! Mesh coordinates share one frame with the voxel grid: a point `(x, y, z)`
//! is `(continuous index) * spacing`, where voxel `(i, j, k)` covers
//! `[i, i+1) x [j, j+1) x [k, k+1)` in continuous index units, so its centre
//! is at `((i + 0.5) sx, (j + 0.5) sy, (k + 0.5) sz)`. Origin and direction
//! of the volume are not applied (exporters may apply them on request).
//!
//! Triangles are wound counter-clockwise seen from outside, so normals point
//! out of the enclosed region and the signed volume of a closed mesh is > 0.
use std::collections::HashMap;

/// A triangle mesh: shared vertices and index triples.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions in physical units.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as indices into `vertices`, counter-clockwise from outside.
    pub triangles: Vec<[u32; 3]>,
}

#[inline]
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n > 0.0 {
        [a[0] / n, a[1] / n, a[2] / n]
    } else {
        [0.0; 3]
    }
}

impl TriMesh {
    /// An empty mesh.
    pub fn new() -> TriMesh {
        TriMesh::default()
    }

    /// True when the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The three corner positions of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [[f64; 3]; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Append another mesh (its indices shifted); used to collect the
    /// surfaces of several objects into one mesh.
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * dot(cross(sub(b, a), sub(c, a)), cross(sub(b, a), sub(c, a))).sqrt()
            })
            .sum()
    }

    /// Signed enclosed volume (divergence theorem). Positive for a closed,
    /// outward-oriented mesh; meaningless for an open one.
    pub fn signed_volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                dot(a, cross(b, c)) / 6.0
            })
            .sum()
    }

    /// Unit normal of every triangle (zero for a degenerate triangle).
    pub fn face_normals(&self) -> Vec<[f64; 3]> {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                normalize(cross(sub(b, a), sub(c, a)))
            })
            .collect()
    }

    /// Unit normal of every vertex: the area-weighted mean of the normals of
    /// its triangles (zero for an isolated vertex).
    pub fn vertex_normals(&self) -> Vec<[f64; 3]> {
        let mut acc = vec![[0.0f64; 3]; self.vertices.len()];
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t);
            // The cross product's length is twice the area: area weighting for free.
            let n = cross(sub(b, a), sub(c, a));
            for &v in &self.triangles[t] {
                let s = &mut acc[v as usize];
                s[0] += n[0];
                s[1] += n[1];
                s[2] += n[2];
            }
        }
        acc.into_iter().map(normalize).collect()
    }

    /// Axis-aligned bounds `(min, max)`; `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let first = *self.vertices.first()?;
        Some(self.vertices.iter().fold((first, first), |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            )
        }))
    }

    /// True when every edge is used by exactly two triangles, once in each
    /// direction: the mesh is closed and consistently oriented.
    pub fn is_closed_and_oriented(&self) -> bool {
        let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(self.triangles.len() * 3);
        for t in &self.triangles {
            for e in 0..3 {
                *edges.entry((t[e], t[(e + 1) % 3])).or_insert(0) += 1;
            }
        }
        edges
            .iter()
            .all(|(&(a, b), &n)| n == 1 && a != b && edges.get(&(b, a)) == Some(&1))
    }

    /// Check that every index is in range; returns the first bad triangle.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.vertices.len() as u64;
        if let Some((i, t)) = self
            .triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| u64::from(v) >= n))
        {
            return Err(format!("triangle {i} {t:?} refers to a vertex >= {n}"));
        }
        if self
            .vertices
            .iter()
            .any(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err("mesh has a non-finite vertex".into());
        }
        Ok(())
    }

    /// Apply an affine map `p -> m * p + t` to every vertex (e.g. to world
    /// coordinates); flips the winding when the map reverses orientation so
    /// that normals keep pointing outwards.
    pub fn transform(&mut self, m: [[f64; 3]; 3], t: [f64; 3]) {
        for p in &mut self.vertices {
            let q = *p;
            *p = [
                dot(m[0], q) + t[0],
                dot(m[1], q) + t[1],
                dot(m[2], q) + t[2],
            ];
        }
        let det = dot(m[0], cross(m[1], m[2]));
        if det < 0.0 {
            for tri in &mut self.triangles {
                tri.swap(1, 2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube with outward winding.
    pub(crate) fn cube(s: f64) -> TriMesh {
        let v = (0..8)
            .map(|i| {
                [
                    s * (i & 1) as f64,
                    s * ((i >> 1) & 1) as f64,
                    s * ((i >> 2) & 1) as f64,
                ]
            })
            .collect();
        let quads = [
            [0, 2, 3, 1], // z = 0, normal -z
            [4, 5, 7, 6], // z = 1
            [0, 1, 5, 4], // y = 0
            [2, 6, 7, 3], // y = 1
            [0, 4, 6, 2], // x = 0
            [1, 3, 7, 5], // x = 1
        ];
        let mut triangles = Vec::new();
        for q in quads {
            triangles.push([q[0], q[1], q[2]]);
            triangles.push([q[0], q[2], q[3]]);
        }
        TriMesh {
            vertices: v,
            triangles,
        }
    }

    #[test]
    fn cube_measures() {
        let m = cube(2.0);
        assert!((m.area() - 24.0).abs() < 1e-12);
        assert!((m.signed_volume() - 8.0).abs() < 1e-12);
        assert!(m.is_closed_and_oriented());
        let n = m.face_normals();
        assert_eq!(n[0], [0.0, 0.0, -1.0]);
        let vn = m.vertex_normals();
        let s = 1.0 / 3f64.sqrt();
        assert!((vn[7][0] - s).abs() < 1e-12 && (vn[7][2] - s).abs() < 1e-12);
        assert_eq!(m.bounds(), Some(([0.0; 3], [2.0; 3])));
    }

    #[test]
    fn open_mesh_is_detected_and_mirror_keeps_orientation() {
        let mut m = cube(1.0);
        m.transform(
            [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [0.0; 3],
        );
        assert!((m.signed_volume() - 1.0).abs() < 1e-12);
        m.triangles.pop();
        assert!(!m.is_closed_and_oriented());
        m.triangles.push([0, 1, 99]);
        assert!(m.validate().is_err());
    }
}
