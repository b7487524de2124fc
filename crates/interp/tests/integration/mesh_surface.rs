//! Marching cubes of masks and voxelisation of meshes.
use interslice_core::mesh::TriMesh;
use interslice_core::{Geometry, LengthUnit, Mask, Volume};
use interslice_interp::mesh::{mask_surface, voxelize::voxelize};
use proptest::prelude::*;

use crate::common;
use common::dice;

fn sphere(n: usize, spacing: [f64; 3], r: f64) -> Mask {
    let g = Geometry::new([n, n, n], spacing, LengthUnit::Micrometre).unwrap();
    let c: Vec<f64> = (0..3).map(|d| n as f64 * spacing[d] / 2.0).collect();
    let mut m: Mask = Volume::zeros(g);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = [
                    (i as f64 + 0.5) * spacing[0],
                    (j as f64 + 0.5) * spacing[1],
                    (k as f64 + 0.5) * spacing[2],
                ];
                m.set(
                    i,
                    j,
                    k,
                    (0..3).map(|d| (p[d] - c[d]).powi(2)).sum::<f64>() <= r * r,
                );
            }
        }
    }
    m
}

#[test]
fn sphere_surface_is_closed_oriented_and_has_the_right_volume() {
    for spacing in [[1.0f64, 1.0, 1.0], [0.35, 0.5, 0.8]] {
        let r = 14.0 * spacing[0].max(spacing[1]).max(spacing[2]);
        let m = sphere(48, spacing, r.min(0.45 * 48.0 * spacing[0]));
        let r = r.min(0.45 * 48.0 * spacing[0]);
        let mesh = mask_surface(&m);
        assert!(mesh.is_closed_and_oriented(), "spacing {spacing:?}");
        let v = mesh.signed_volume();
        let exact = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        assert!(
            (v - exact).abs() < 0.04 * exact,
            "volume {v} vs sphere {exact}"
        );
        // Every vertex within a voxel of the sphere.
        let c = 24.0;
        let s = spacing.iter().cloned().fold(0.0, f64::max);
        for p in &mesh.vertices {
            let d = ((p[0] - c * spacing[0]).powi(2)
                + (p[1] - c * spacing[1]).powi(2)
                + (p[2] - c * spacing[2]).powi(2))
            .sqrt();
            assert!((d - r).abs() < s, "vertex at {d}, radius {r}");
        }
        let back = voxelize(&mesh, m.geometry());
        let d = dice(&back, &m);
        assert!(d > 0.98, "Dice {d}");
    }
}

#[test]
fn masks_touching_the_border_and_diagonal_voxels_give_closed_surfaces() {
    let g = Geometry::new([4, 4, 3], [1.0; 3], LengthUnit::Millimetre).unwrap();
    let mut m: Mask = Volume::zeros(g);
    // Two voxels touching only along an edge, one only at a corner, one on the border.
    m.set(0, 0, 0, true);
    m.set(1, 1, 0, true);
    m.set(2, 2, 1, true);
    m.set(3, 3, 2, true);
    let mesh = mask_surface(&m);
    assert!(mesh.is_closed_and_oriented());
    // Four separate octahedra of volume 1/6 each.
    assert!(
        (mesh.signed_volume() - 4.0 / 6.0).abs() < 1e-9,
        "{}",
        mesh.signed_volume()
    );
    assert_eq!(voxelize(&mesh, m.geometry()), m);
    let empty: Mask = Volume::zeros(m.geometry().clone());
    assert!(mask_surface(&empty).is_empty());
}

/// Inside test by brute force: the signed solid angle sum (winding number)
/// of a closed mesh at a point, independent of the ray casting.
fn winding_number(mesh: &TriMesh, p: [f64; 3]) -> f64 {
    let mut total = 0.0;
    for t in 0..mesh.triangles.len() {
        let c = mesh.corners(t);
        let a: Vec<[f64; 3]> = c
            .iter()
            .map(|q| [q[0] - p[0], q[1] - p[1], q[2] - p[2]])
            .collect();
        let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let (la, lb, lc) = (len(a[0]), len(a[1]), len(a[2]));
        let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        let den = la * lb * lc + dot(a[0], a[1]) * lc + dot(a[1], a[2]) * la + dot(a[2], a[0]) * lb;
        total += 2.0 * det.atan2(den);
    }
    total / (4.0 * std::f64::consts::PI)
}

fn box_mesh(lo: [f64; 3], hi: [f64; 3]) -> TriMesh {
    let vertices = (0..8)
        .map(|c| {
            [
                if c & 1 == 0 { lo[0] } else { hi[0] },
                if c & 2 == 0 { lo[1] } else { hi[1] },
                if c & 4 == 0 { lo[2] } else { hi[2] },
            ]
        })
        .collect();
    let mut triangles = Vec::new();
    for q in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
    }
    TriMesh {
        vertices,
        triangles,
    }
}

fn tetra_mesh(p: [[f64; 3]; 4]) -> TriMesh {
    let o = {
        let a = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
        let b = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
        let c = [p[3][0] - p[0][0], p[3][1] - p[0][1], p[3][2] - p[0][2]];
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    // Faces outward for a positively oriented (a, b, c, d) in the right-handed sense.
    let tris = if o > 0.0 {
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
    } else {
        vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]]
    };
    TriMesh {
        vertices: p.to_vec(),
        triangles: tris,
    }
}

fn check_against_winding(mesh: &TriMesh, g: &Geometry) -> Result<(), TestCaseError> {
    let m = voxelize(mesh, g);
    let [nx, ny, nz] = g.dims;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = [
                    (i as f64 + 0.5) * g.spacing[0],
                    (j as f64 + 0.5) * g.spacing[1],
                    (k as f64 + 0.5) * g.spacing[2],
                ];
                let w = winding_number(mesh, p);
                // Points very close to the surface are ambiguous for the brute-force test.
                if (w.abs() - 0.5).abs() < 0.45 {
                    continue;
                }
                prop_assert_eq!(
                    m.get(i, j, k),
                    w.abs() > 0.5,
                    "voxel {} {} {} winding {}",
                    i,
                    j,
                    k,
                    w
                );
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn voxelised_boxes_match_the_brute_force_inside_test(
        lo in prop::array::uniform3(0.0f64..6.0),
        size in prop::array::uniform3(0.2f64..6.0),
        // Half-integer corners land exactly on voxel-centre rows: the hard case.
        snap in any::<bool>(),
    ) {
        let g = Geometry::new([10, 9, 8], [1.0, 1.0, 1.0], LengthUnit::Micrometre).unwrap();
        let mut lo = lo;
        let mut hi = [lo[0] + size[0], lo[1] + size[1], lo[2] + size[2]];
        if snap {
            lo = lo.map(|x| (x * 2.0).round() / 2.0);
            hi = hi.map(|x| (x * 2.0).round() / 2.0 + 0.5);
        }
        let mesh = box_mesh(lo, hi);
        let m = voxelize(&mesh, &g);
        for k in 0..8 {
            for j in 0..9 {
                for i in 0..10 {
                    let p = [i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5];
                    // Half-open on the far side in x (crossings with x0 < x <= x1),
                    // perturbed towards +y and +z on the other axes.
                    let inside = p[0] > lo[0] && p[0] <= hi[0]
                        && p[1] >= lo[1] && p[1] < hi[1]
                        && p[2] >= lo[2] && p[2] < hi[2];
                    prop_assert_eq!(m.get(i, j, k), inside, "voxel {} {} {} box {:?} {:?}", i, j, k, lo, hi);
                }
            }
        }
    }

    #[test]
    fn voxelised_tetrahedra_match_the_winding_number(
        p in prop::array::uniform4(prop::array::uniform3(0.0f64..8.0)),
        spacing in prop::array::uniform3(0.5f64..1.5),
    ) {
        let g = Geometry::new([9, 9, 9], spacing, LengthUnit::Micrometre).unwrap();
        let p = p.map(|q| [q[0] * spacing[0], q[1] * spacing[1], q[2] * spacing[2]]);
        check_against_winding(&tetra_mesh(p), &g)?;
    }

    #[test]
    fn voxelised_random_masks_come_back_unchanged(bits in prop::collection::vec(any::<bool>(), 5 * 4 * 3)) {
        let g = Geometry::new([5, 4, 3], [0.7, 1.0, 1.3], LengthUnit::Micrometre).unwrap();
        let m = Volume::from_vec(g, bits).unwrap();
        let mesh = mask_surface(&m);
        prop_assert!(mesh.is_closed_and_oriented());
        prop_assert_eq!(voxelize(&mesh, m.geometry()), m);
    }
}
