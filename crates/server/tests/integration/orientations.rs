//! Tracings on slices of several orientations through the server: one
//! result that honours every drawn slice of every axis.
use crate::common;

use common::*;
use interslice_core::Axis;
use interslice_test_support::client::Client;
use serde_json::json;

/// A ball traced on z slices and on x slices (exact crack outlines of the
/// same ball, so the crossings agree): the export is one result that keeps
/// the drawn slices of both orientations, and contradicting x slices are a
/// one-line 400.
#[test]
fn contours_on_z_and_x_slices_are_both_honoured_by_the_export() {
    use interslice_core::trace::{mask_polygons, signed_area};
    let dir = project();
    let server = serve(config(dir.path()));
    let mut alice = signed_in(&server, "alice");
    let ball = |shift: f64| {
        let mut m: interslice_core::Mask = interslice_core::Volume::zeros(
            interslice_core::Geometry::new(DIMS, [1.0; 3], interslice_core::LengthUnit::Micrometre)
                .unwrap(),
        );
        for k in 0..DIMS[2] {
            for j in 0..DIMS[1] {
                for i in 0..DIMS[0] {
                    let (x, y, z) = (i as f64 - 15.5, j as f64 - 13.5 - shift, k as f64 - 11.5);
                    m.set(i, j, k, x * x / 100.0 + y * y / 64.0 + z * z / 81.0 <= 1.0);
                }
            }
        }
        m
    };
    let post = |c: &mut Client, m: &interslice_core::Mask, axis: Axis, index: usize| {
        let (w, h) = m.slice_shape(axis);
        let s = m.slice(axis, index).unwrap();
        for points in mask_polygons(&s, w, h)
            .into_iter()
            .filter(|p| signed_area(p) > 0.0)
        {
            let body =
                json!({"label": 1, "axis": axis.to_string(), "index": index, "points": points});
            expect(
                &c.json("POST", "/api/cells/cell_01/contours", &body)
                    .unwrap(),
                201,
            );
        }
    };
    let truth = ball(0.0);
    let (zs, xs) = ([5usize, 11, 17], [8usize, 15, 22]);
    for &k in &zs {
        post(&mut alice, &truth, Axis::Z, k);
    }
    for &i in &xs {
        post(&mut alice, &truth, Axis::X, i);
    }
    let exp = alice
        .get("/api/cells/cell_01/export?format=nii.gz&method=shape-based")
        .unwrap();
    expect(&exp, 200);
    let exported = read_export(&exp.body, "e.nii.gz");
    let want = |axis, s| -> Vec<u16> {
        truth
            .slice(axis, s)
            .unwrap()
            .into_iter()
            .map(u16::from)
            .collect()
    };
    for &k in &zs {
        assert_eq!(
            exported.slice(Axis::Z, k).unwrap(),
            want(Axis::Z, k),
            "z={k}"
        );
    }
    for &i in &xs {
        assert_eq!(
            exported.slice(Axis::X, i).unwrap(),
            want(Axis::X, i),
            "x={i}"
        );
    }
    // Bob's x slices are shifted by 5 voxels: they contradict his z slices.
    let mut bob = signed_in(&server, "bob");
    post(&mut bob, &truth, Axis::Z, 11);
    post(&mut bob, &truth, Axis::Z, 14);
    let shifted = ball(5.0);
    post(&mut bob, &shifted, Axis::X, 15);
    post(&mut bob, &shifted, Axis::X, 17);
    let a = bob
        .get("/api/cells/cell_01/export?format=nii.gz&method=shape-based")
        .unwrap();
    expect(&a, 400);
    assert!(
        a.error().unwrap().contains("contradict where they cross"),
        "{:?}",
        a.error()
    );
}
