//! The preview's confidence and the recommended method: `confidence: true`
//! outlines the uncertain pixels of the skipped slices only, beside the
//! preview contour; `recommend: true` names the image-guided method on a
//! phantom cell whose image shows the nucleus and the shape default on a
//! cell whose image is noise.
use crate::common;

use common::*;
use interslice_core::phantom::{PhantomParams, generate};
use interslice_core::trace::{mask_polygons, signed_area};
use interslice_core::{AnyVolume, Axis, Mask, Volume};
use interslice_test_support::client::Client;
use serde_json::{Value, json};

/// Trace `truth` on the z slices `zs` (exact crack outlines, holes left out).
fn trace(client: &Client, cell: &str, truth: &Mask, zs: &[usize]) {
    trace_along(client, cell, truth, Axis::Z, zs);
}

fn trace_along(client: &Client, cell: &str, truth: &Mask, axis: Axis, zs: &[usize]) {
    let (w, h) = truth.slice_shape(axis);
    for &k in zs {
        let s = truth.slice(axis, k).unwrap();
        for points in mask_polygons(&s, w, h)
            .into_iter()
            .filter(|p| signed_area(p) > 0.0)
        {
            let body = json!({"label": 1, "axis": axis.to_string(), "index": k, "points": points});
            let url = format!("/api/cells/{cell}/contours");
            expect(&client.json("POST", &url, &body).unwrap(), 201);
        }
    }
}

fn interpolate(client: &Client, cell: &str, body: Value) -> Value {
    let a = client
        .json("POST", &format!("/api/cells/{cell}/interpolate"), &body)
        .unwrap();
    expect(&a, 200);
    a.json()
}

/// The distance from `p` to the nearest edge of any polygon of `polys`.
fn distance_to(polys: &[Vec<[f64; 2]>], p: [f64; 2]) -> f64 {
    let mut best = f64::INFINITY;
    for poly in polys {
        for (i, &a) in poly.iter().enumerate() {
            let b = poly[(i + 1) % poly.len()];
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = dx * dx + dy * dy;
            let t = if len2 > 0.0 {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (x, y) = (a[0] + t * dx - p[0], a[1] + t * dy - p[1]);
            best = best.min((x * x + y * y).sqrt());
        }
    }
    best
}

fn polygons(v: &Value) -> Vec<Vec<[f64; 2]>> {
    serde_json::from_value(v.clone()).unwrap()
}

#[test]
fn confidence_outlines_the_uncertain_pixels_of_skipped_slices_beside_the_contour() {
    let dir = project();
    let server = serve(config(dir.path()));
    let alice = signed_in(&server, "alice");
    // An ellipsoid traced on every 5th z slice: the gaps are wide enough for
    // doubt in their middle.
    let g = interslice_core::Geometry::new(DIMS, [1.0; 3], interslice_core::LengthUnit::Micrometre)
        .unwrap();
    let mut truth: Mask = Volume::zeros(g);
    for k in 0..DIMS[2] {
        for j in 0..DIMS[1] {
            for i in 0..DIMS[0] {
                let (x, y, z) = (i as f64 - 15.5, j as f64 - 13.5, k as f64 - 11.5);
                let r = 1.0 + 0.25 * (z * 0.7).sin();
                truth.set(
                    i,
                    j,
                    k,
                    x * x / (100.0 * r) + y * y / (49.0 * r) + z * z / 100.0 <= 1.0,
                );
            }
        }
    }
    let zs = [2usize, 7, 12, 17, 21];
    trace(&alice, "cell_01", &truth, &zs);

    let plain = interpolate(
        &alice,
        "cell_01",
        json!({"label": 1, "axis": "z", "preview": true}),
    );
    for s in plain["slices"].as_array().unwrap() {
        assert!(s.get("uncertain").is_none(), "asked for no confidence: {s}");
    }
    assert!(plain.get("recommended_method").is_none());

    let a = interpolate(
        &alice,
        "cell_01",
        json!({"label": 1, "axis": "z", "preview": true, "confidence": true}),
    );
    assert_eq!(a["method"], "shape-auto");
    let mut outlined = 0;
    for s in a["slices"].as_array().unwrap() {
        let index = s["index"].as_u64().unwrap() as usize;
        if zs.contains(&index) {
            assert_eq!(s["drawn"], true);
            assert!(s.get("uncertain").is_none(), "drawn slice {index}: {s}");
            continue;
        }
        let uncertain = polygons(&s["uncertain"]);
        let contours = polygons(&s["contours"]);
        if index < zs[0] || index > zs[zs.len() - 1] {
            assert!(uncertain.is_empty(), "z={index} is outside the drawn range");
            continue;
        }
        // Two slices or more from a drawn one (the middle of each gap), the
        // shape is unsure along its contour; next to a drawn slice the
        // confidence fitted on the drawn slices may call it sure.
        let delta = zs.iter().map(|&d| d.abs_diff(index)).min().unwrap();
        if delta >= 2 {
            assert!(!uncertain.is_empty(), "z={index}: no uncertain band");
            outlined += 1;
        }
        // The uncertain band lies along the preview contour.
        for p in uncertain.iter().flatten() {
            let d = distance_to(&contours, *p);
            assert!(
                d <= 4.0,
                "z={index}: uncertain point {p:?} is {d} px from the contour"
            );
        }
    }
    assert_eq!(outlined, 7, "the slices in the middle of the gaps");
    // Far from the drawn slices the band is wider than next to them.
    let band = |k: usize| {
        let s = &a["slices"][k];
        polygons(&s["uncertain"])
            .iter()
            .map(|p| signed_area(p))
            .sum::<f64>()
            .abs()
    };
    assert!(band(14) > band(13), "{} vs {}", band(14), band(13));

    // Also drawn across the axis: the combined mask's confidence, still
    // none on the drawn z slices.
    trace_along(&alice, "cell_01", &truth, Axis::X, &[15]);
    let both = interpolate(
        &alice,
        "cell_01",
        json!({"label": 1, "axis": "z", "preview": true, "confidence": true}),
    );
    let slices = both["slices"].as_array().unwrap();
    for s in slices {
        let drawn = s["drawn"].as_bool().unwrap();
        assert_eq!(s.get("uncertain").is_some(), !drawn, "{}", s["index"]);
    }
    assert!(
        slices
            .iter()
            .filter(|s| s["drawn"] == false)
            .any(|s| !polygons(&s["uncertain"]).is_empty())
    );
}

/// A 64³ phantom cell (noise 10 %) with its nucleus, and a cell of the same
/// grid whose image is uniform noise; returns the nucleus mask.
fn phantom_cells(dir: &std::path::Path) -> Mask {
    let p = generate(&PhantomParams {
        size: 64,
        seed: 2,
        bits: 8,
        noise: 0.10,
    })
    .unwrap();
    interslice_io::write_volume(&dir.join("phantom.nii"), &p.intensity).unwrap();
    let g = p.labels.geometry().clone();
    // SplitMix64 of the voxel index: the same bytes on every run.
    let noise: Vec<u8> = (0..g.len() as u64)
        .map(|i| {
            let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as u8
        })
        .collect();
    let noise = AnyVolume::U8(Volume::from_vec(g, noise).unwrap());
    interslice_io::write_volume(&dir.join("noise.nii"), &noise).unwrap();
    p.labels.map(|l| l >= 2)
}

#[test]
fn the_recommended_method_is_image_guided_where_the_image_shows_the_nucleus_only() {
    let dir = tempfile::tempdir().unwrap();
    let nucleus = phantom_cells(dir.path());
    let server = serve(config(dir.path()));
    let alice = signed_in(&server, "alice");
    let zs: Vec<usize> = (0..64)
        .filter(|&k| nucleus.slice(Axis::Z, k).unwrap().contains(&true))
        .collect();
    let (first, last) = (zs[0], zs[zs.len() - 1]);
    // Every 7th slice: gaps where the shape alone drifts from the nucleus.
    let mut drawn: Vec<usize> = (first..=last).step_by(7).collect();
    if *drawn.last().unwrap() != last {
        drawn.push(last);
    }
    for cell in ["phantom", "noise"] {
        trace(&alice, cell, &nucleus, &drawn);
    }
    let body = json!({"label": 1, "axis": "z", "preview": true, "recommend": true});
    let a = interpolate(&alice, "phantom", body.clone());
    assert_eq!(
        a["recommended_method"], "image-guided",
        "{}",
        a["image_weight"]
    );
    assert!(a["image_weight"].as_f64().unwrap() > 0.0);
    assert_eq!(
        a["method"], "image-guided",
        "no method named: the recommended one"
    );
    // Planned once for the recommendation and reused: the same result as
    // the image-guided method named.
    let named = interpolate(
        &alice,
        "phantom",
        json!({"label": 1, "axis": "z", "preview": true, "method": "image-guided"}),
    );
    assert_eq!(named["voxels"], a["voxels"]);
    assert_eq!(named["slices"], a["slices"]);
    let b = interpolate(&alice, "noise", body);
    assert_eq!(b["recommended_method"], "shape-auto");
    assert_eq!(b["image_weight"], 0.0);
    assert_eq!(b["method"], "shape-auto");
    // A named method is used as named; the recommendation is still given.
    let c = interpolate(
        &alice,
        "noise",
        json!({"label": 1, "axis": "z", "method": "image-guided", "recommend": true}),
    );
    assert_eq!(c["method"], "image-guided");
    assert_eq!(c["recommended_method"], "shape-auto");
    // Bit for bit the same mask where the image does not help.
    assert_eq!(c["voxels"], b["voxels"]);
}
