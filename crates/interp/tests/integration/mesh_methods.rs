//! The four mesh-based methods of the original system: accuracy floors on an
//! ellipsoid and a two-lobed nucleus traced on every 5th slice, the
//! invariants along every axis with anisotropic spacing, and their surfaces.
use interslice_core::mesh::TriMesh;
use interslice_core::{Axis, Mask};
use interslice_interp::mesh::mesh_methods;
use interslice_interp::{InterpError, Interpolator, SparseMask, by_name};

use crate::common;
use common::{dice, every, in_ellipsoid, shape, sparse};

fn ellipsoid() -> Mask {
    shape([64, 64, 64], [1.0; 3], |p| {
        in_ellipsoid(p, [32.0, 31.0, 33.0], [21.0, 15.0, 24.0])
    })
}

/// Two overlapping lobes with a waist between them (a bilobed nucleus).
fn two_lobes() -> Mask {
    shape([64, 64, 64], [1.0; 3], |p| {
        in_ellipsoid(p, [22.0, 32.0, 32.0], [13.0, 12.0, 20.0])
            || in_ellipsoid(p, [42.0, 32.0, 31.0], [12.0, 13.0, 18.0])
    })
}

fn count(m: &Mask) -> usize {
    m.data().iter().filter(|&&v| v).count()
}

fn method(name: &str) -> Box<dyn Interpolator> {
    mesh_methods()
        .into_iter()
        .find(|m| m.name() == name)
        .expect("mesh method")
}

/// The surface of the method called `name`; an error for an unknown method
/// or one that builds no surface.
fn surface(name: &str, input: SparseMask<'_>) -> Result<TriMesh, InterpError> {
    by_name(name)?
        .surface_mesh(input)?
        .ok_or_else(|| InterpError::Input(format!("method '{name}' builds no surface")))
}

/// The names of the mesh methods, in the order of the original system.
fn mesh_names() -> Vec<&'static str> {
    mesh_methods().iter().map(|m| m.name()).collect()
}

fn run(name: &str, full: &Mask, axis: Axis, step: usize) -> (Mask, Vec<usize>) {
    let drawn = every(full.slice_count(axis), step);
    let sp = sparse(full, axis, &drawn);
    let out = method(name)
        .interpolate(SparseMask::new(&sp, axis, &drawn))
        .unwrap();
    (out, drawn)
}

/// Dice floors from every 5th slice, each a little below the value measured
/// (in the comment). On these smooth convex shapes Delaunay is the most
/// accurate of the four at this gap; its holes appear as the gap grows (see
/// `delaunay_loses_volume_and_marching_cubes_degrades_as_gaps_grow`). The
/// splat is the least accurate because it inflates, Hoppe's surface trails
/// marching cubes (smooth but shrunk).
const FLOORS: [(&str, f64, f64); 4] = [
    // (method, ellipsoid, two lobes)
    ("marching-cubes", 0.95, 0.945),     // measured 0.9616, 0.9552
    ("gaussian-splat", 0.80, 0.765),     // measured 0.8148, 0.7796
    ("delaunay", 0.97, 0.935),           // measured 0.9842, 0.9485
    ("unorganized-points", 0.945, 0.93), // measured 0.9576, 0.9422
];

#[test]
fn dice_floors_from_every_fifth_slice() {
    let (e, l) = (ellipsoid(), two_lobes());
    for (name, fe, fl) in FLOORS {
        let de = dice(&run(name, &e, Axis::Z, 5).0, &e);
        let dl = dice(&run(name, &l, Axis::Z, 5).0, &l);
        eprintln!("{name}: ellipsoid {de:.4}, two lobes {dl:.4}");
        assert!(de >= fe, "{name}: ellipsoid Dice {de:.4} < {fe}");
        assert!(dl >= fl, "{name}: two-lobed Dice {dl:.4} < {fl}");
    }
}

#[test]
fn delaunay_loses_volume_and_marching_cubes_degrades_as_gaps_grow() {
    let e = ellipsoid();
    // Delaunay: the alpha criterion drops the large tetrahedra of wide gaps,
    // leaving holes (measured volume ratio 0.85 from every 10th slice).
    let (out, _) = run("delaunay", &e, Axis::Z, 10);
    let ratio = count(&out) as f64 / count(&e) as f64;
    assert!(ratio < 0.92, "delaunay volume ratio {ratio:.3}");
    // Marching cubes: accuracy falls with every slice skipped
    // (measured 0.989, 0.962, 0.926 from every 2nd, 5th, 10th slice).
    let d: Vec<f64> = [2, 5, 10]
        .iter()
        .map(|&s| dice(&run("marching-cubes", &e, Axis::Z, s).0, &e))
        .collect();
    assert!(d[0] > d[1] && d[1] > d[2], "marching cubes Dice {d:?}");
}

#[test]
fn splat_inflates_the_volume() {
    let e = ellipsoid();
    let (out, _) = run("gaussian-splat", &e, Axis::Z, 5);
    assert!(
        count(&out) as f64 > 1.05 * count(&e) as f64,
        "{} vs {}",
        count(&out),
        count(&e)
    );
}

#[test]
fn drawn_slices_exact_and_empty_slices_empty_on_every_axis() {
    // Anisotropic spacing; an off-centre ellipsoid so that some drawn slices are empty.
    let spacing = [0.5, 0.8, 1.3];
    let full = shape([40, 34, 28], spacing, |p| {
        in_ellipsoid(p, [9.0, 13.0, 17.0], [7.0, 9.0, 9.0])
    });
    for axis in Axis::ALL {
        for name in mesh_names() {
            let (out, drawn) = run(name, &full, axis, 4);
            let mut empty_seen = false;
            for &d in &drawn {
                let want = full.slice(axis, d).unwrap();
                empty_seen |= want.iter().all(|&v| !v);
                assert_eq!(
                    out.slice(axis, d).unwrap(),
                    want,
                    "{name} along {axis}: drawn slice {d} changed"
                );
            }
            assert!(
                empty_seen,
                "test shape must have empty drawn slices along {axis}"
            );
            let dc = dice(&out, &full);
            assert!(dc > 0.6, "{name} along {axis}: Dice {dc:.3}");
        }
    }
}

#[test]
fn two_far_apart_nucleoli_stay_two_objects() {
    let full = shape([48, 40, 40], [1.0; 3], |p| {
        in_ellipsoid(p, [12.0, 20.0, 20.0], [6.0, 6.0, 8.0])
            || in_ellipsoid(p, [36.0, 20.0, 20.0], [6.0, 7.0, 8.0])
    });
    for name in mesh_names() {
        let (out, _) = run(name, &full, Axis::Z, 3);
        // Nothing in the gap between the two nucleoli.
        for k in 0..40 {
            for j in 0..40 {
                for i in 22..26 {
                    assert!(
                        !out.get(i, j, k),
                        "{name}: voxel {i} {j} {k} joins the nucleoli"
                    );
                }
            }
        }
        let left = (0..40 * 40 * 48)
            .filter(|&n| out.data()[n] && n % 48 < 24)
            .count();
        let right = (0..40 * 40 * 48)
            .filter(|&n| out.data()[n] && n % 48 >= 24)
            .count();
        assert!(left > 500 && right > 500, "{name}: {left} {right}");
    }
}

#[test]
fn surfaces_are_closed_and_enclose_the_object() {
    let e = ellipsoid();
    let drawn = every(64, 5);
    let sp = sparse(&e, Axis::Y, &drawn);
    let true_volume = count(&e) as f64;
    for name in ["marching-cubes", "gaussian-splat", "unorganized-points"] {
        let m = surface(name, SparseMask::new(&sp, Axis::Y, &drawn)).unwrap();
        assert!(m.is_closed_and_oriented(), "{name}: surface not closed");
        let v = m.signed_volume();
        assert!(
            v > 0.7 * true_volume && v < 1.6 * true_volume,
            "{name}: volume {v} vs {true_volume}"
        );
    }
    let m = surface("delaunay", SparseMask::new(&sp, Axis::Y, &drawn)).unwrap();
    assert!(m.signed_volume() > 0.5 * true_volume);
    assert!(surface("linear", SparseMask::new(&sp, Axis::Y, &drawn)).is_err());
}

#[test]
fn fewer_than_two_drawn_slices_is_an_error() {
    let e = ellipsoid();
    for m in mesh_methods() {
        let r = m.interpolate(SparseMask::new(&e, Axis::Z, &[30]));
        assert!(r.is_err(), "{}", m.name());
    }
}

mod random_shapes {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]

        /// Random ellipsoids, axes, spacings and gaps: every method keeps the
        /// drawn slices (empty ones empty), and the surfaces of marching
        /// cubes, the splat and Hoppe's method are closed and oriented.
        #[test]
        fn invariants_on_random_ellipsoids(
            c in prop::array::uniform3(6.0f64..14.0),
            r in prop::array::uniform3(2.5f64..7.0),
            spacing in prop::array::uniform3(0.6f64..1.4),
            axis in 0usize..3,
            step in 2usize..5,
        ) {
            let axis = Axis::ALL[axis];
            let full = shape([20, 18, 16], spacing, |p| {
                in_ellipsoid(p, [c[0] * spacing[0], c[1] * spacing[1], c[2] * spacing[2]],
                    [r[0] * spacing[0], r[1] * spacing[1], r[2] * spacing[2]])
            });
            let drawn = every(full.slice_count(axis), step);
            let sp = sparse(&full, axis, &drawn);
            let input = SparseMask::new(&sp, axis, &drawn);
            for name in mesh_names() {
                let out = method(name).interpolate(input).unwrap();
                for &d in &drawn {
                    prop_assert_eq!(out.slice(axis, d).unwrap(), full.slice(axis, d).unwrap(),
                        "{} along {}: drawn slice {}", name, axis, d);
                }
                if name != "delaunay" {
                    let m = surface(name, input).unwrap();
                    prop_assert!(m.is_closed_and_oriented(), "{} surface not closed", name);
                    prop_assert!(m.is_empty() || m.signed_volume() > 0.0, "{}", name);
                }
            }
        }
    }
}
