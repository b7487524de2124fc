//! The image-guided method through the server: it reads the cell's own
//! intensities wherever a `method` is named (interpolate, export, advice,
//! the tracing summary, evaluation) and keeps every drawn slice.
use crate::common;

use common::*;
use interslice_core::Axis;
use interslice_core::trace::{mask_polygons, signed_area};
use serde_json::json;

#[test]
fn image_guided_is_listed_and_used_on_the_cells_own_image() {
    let dir = project();
    let server = serve(config(dir.path()));
    let alice = signed_in(&server, "alice");

    let methods = alice.get("/api/methods").unwrap().json();
    let names: Vec<&str> = methods
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert!(names.contains(&"image-guided"), "{names:?}");
    assert_eq!(names[0], "shape-auto");

    // An ellipsoid traced on every 4th z slice, exact crack outlines.
    let g = interslice_core::Geometry::new(DIMS, [1.0; 3], interslice_core::LengthUnit::Micrometre)
        .unwrap();
    let mut truth: interslice_core::Mask = interslice_core::Volume::zeros(g);
    for k in 0..DIMS[2] {
        for j in 0..DIMS[1] {
            for i in 0..DIMS[0] {
                let (x, y, z) = (i as f64 - 15.5, j as f64 - 13.5, k as f64 - 11.5);
                truth.set(i, j, k, x * x / 100.0 + y * y / 49.0 + z * z / 100.0 <= 1.0);
            }
        }
    }
    let zs = [2usize, 6, 10, 14, 18, 21];
    let (w, h) = truth.slice_shape(Axis::Z);
    for &k in &zs {
        let s = truth.slice(Axis::Z, k).unwrap();
        for points in mask_polygons(&s, w, h)
            .into_iter()
            .filter(|p| signed_area(p) > 0.0)
        {
            let body = json!({"label": 1, "axis": "z", "index": k, "points": points});
            expect(
                &alice
                    .json("POST", "/api/cells/cell_01/contours", &body)
                    .unwrap(),
                201,
            );
        }
    }

    let body = json!({"label": 1, "axis": "z", "method": "image-guided"});
    let a = alice
        .json("POST", "/api/cells/cell_01/interpolate", &body)
        .unwrap();
    expect(&a, 200);

    let exp = alice
        .get("/api/cells/cell_01/export?format=nii.gz&method=image-guided")
        .unwrap();
    expect(&exp, 200);
    let exported = read_export(&exp.body, "e.nii.gz");
    for &k in &zs {
        let want: Vec<u16> = truth
            .slice(Axis::Z, k)
            .unwrap()
            .into_iter()
            .map(u16::from)
            .collect();
        assert_eq!(exported.slice(Axis::Z, k).unwrap(), want, "z={k}");
    }
    // Skipped slices inside the drawn range are filled, nothing past it.
    assert!(exported.slice(Axis::Z, 12).unwrap().contains(&1));
    assert!(!exported.slice(Axis::Z, 23).unwrap().contains(&1));

    for url in [
        "/api/cells/cell_01/advice?label=1&axis=z&count=2&method=image-guided",
        "/api/cells/cell_01/summary?label=1&method=image-guided",
    ] {
        expect(&alice.get(url).unwrap(), 200);
    }
    let advice = alice
        .get("/api/cells/cell_01/advice?label=1&axis=z&count=2&method=image-guided")
        .unwrap()
        .json();
    assert_eq!(
        advice["suggestions"].as_array().unwrap().len(),
        2,
        "{advice}"
    );
    let body = json!({
        "reference": {"user": "alice"},
        "test": {"user": "alice"},
        "label": 1,
        "method": "image-guided"
    });
    let m = alice
        .json("POST", "/api/cells/cell_01/evaluate", &body)
        .unwrap();
    expect(&m, 200);
    assert_eq!(m.json()["dice"], 1.0);
}
