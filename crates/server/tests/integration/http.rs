//! The tracing workflow over real HTTP on loopback: cells, slices, contours,
//! reload after a restart, undo, interpolation, export and evaluation; the
//! OpenAPI document against the router; a short run of the load test.
use crate::common;

use common::*;
use interslice_core::{Axis, LabelVolume, metrics};
use interslice_test_support::client::Client;
use serde_json::json;
use std::time::Duration;

const DRAWN: [usize; 4] = [4, 8, 12, 16];

/// The contours a route answers, as the client reads them (the flat JSON
/// form of a stored contour).
fn contours_of(c: &Client, path: &str) -> Vec<serde_json::Value> {
    let a = c.get(path).unwrap();
    expect(&a, 200);
    serde_json::from_slice(&a.body).expect("contours JSON")
}

#[test]
fn trace_reload_interpolate_export_evaluate() {
    let dir = project();
    let server = serve(config(dir.path()));
    let alice = signed_in(&server, "alice");

    // Cells with the user's status.
    let cells = alice.get("/api/cells").unwrap().json();
    let ids: Vec<&str> = cells
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids, ["cell_01", "cell_02"]);
    assert_eq!(cells[0]["status"], "not_started");
    assert_eq!(cells[0]["dims"], json!(DIMS));
    assert_eq!(cells[0]["dtype"], "u8");

    // Metadata and histogram.
    let detail = alice.get("/api/cells/cell_01").unwrap().json();
    assert_eq!(detail["labels"].as_array().unwrap().len(), 4);
    assert_eq!(detail["labels"][0]["name"], "Cell");
    let h = alice.get("/api/cells/cell_01/histogram").unwrap().json();
    let counts: u64 = h["counts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .sum();
    assert_eq!(counts as usize, DIMS.iter().product::<usize>());

    // Raw slices along each axis equal the file's voxels.
    let vol = interslice_io::read_volume(&dir.path().join("cell_01.nii")).unwrap();
    let interslice_core::AnyVolume::U8(v) = &vol else {
        panic!("u8 cell")
    };
    for (axis, index, w, h) in [("z", 3, 32, 28), ("y", 5, 32, 24), ("x", 31, 28, 24)] {
        let a = alice
            .get(&format!("/api/cells/cell_01/slices/{axis}/{index}"))
            .unwrap();
        expect(&a, 200);
        assert_eq!(a.slice_header, Some((w, h, "u8".to_string())));
        let want = v.slice(Axis::parse(axis).unwrap(), index).unwrap();
        assert_eq!(a.body, want, "slice {axis}={index}");
    }

    // Trace label 1 on four z slices (with pen data) and mark z=20 empty.
    for (n, &k) in DRAWN.iter().enumerate() {
        let r = 5.0 + n as f64;
        let points = circle(16.0, 14.0, r, 24);
        let a = alice
            .json(
                "POST",
                "/api/cells/cell_01/contours",
                &json!({
                    "label": 1, "axis": "z", "index": k, "points": points,
                    "pressure": vec![0.5; 24],
                    "times_ms": (0..24).map(|t| t as f64 * 20.0).collect::<Vec<_>>(),
                    "tool": "pen", "client_id": format!("c-{k}"),
                }),
            )
            .unwrap();
        expect(&a, 201);
        assert_eq!(a.json()["author"], "alice");
        assert_eq!(a.json()["duration_ms"], 460.0);
    }
    // A retry with the same client_id stores nothing new.
    let retry = alice
        .json(
            "POST",
            "/api/cells/cell_01/contours",
            &json!({"label": 1, "axis": "z", "index": 4,
                    "points": circle(16.0, 14.0, 5.0, 24), "client_id": "c-4"}),
        )
        .unwrap();
    expect(&retry, 200);
    expect(
        &alice
            .json(
                "POST",
                "/api/cells/cell_01/slices/z/20/empty",
                &json!({"label": 1}),
            )
            .unwrap(),
        200,
    );

    // Undo and redo of a change on another slice.
    let extra = alice
        .json(
            "POST",
            "/api/cells/cell_01/contours",
            &json!({"label": 2, "axis": "z", "index": 10, "points": circle(16.0, 14.0, 2.0, 8),
                    "duration_ms": 1500.0}),
        )
        .unwrap();
    expect(&extra, 201);
    assert_eq!(extra.json()["duration_ms"], 1500.0);
    let undo = alice.send("POST", "/api/cells/cell_01/undo", None).unwrap();
    assert_eq!(undo.json()["changed"], true);
    assert_eq!(undo.json()["slice"]["index"], 10);
    assert!(contours_of(&alice, "/api/cells/cell_01/contours?label=2").is_empty());
    let redo = alice.send("POST", "/api/cells/cell_01/redo", None).unwrap();
    assert_eq!(redo.json()["changed"], true);
    let label2 = contours_of(&alice, "/api/cells/cell_01/contours?label=2");
    assert_eq!(label2.len(), 1);
    // Replace that slice with two contours, then delete one of them.
    let replaced = alice
        .json(
            "PUT",
            "/api/cells/cell_01/slices/z/10/contours",
            &json!({"label": 2, "contours": [
                {"points": circle(10.0, 10.0, 2.0, 8)}, {"points": circle(20.0, 20.0, 2.0, 8)}]}),
        )
        .unwrap();
    expect(&replaced, 200);
    let ids: Vec<i64> = replaced
        .json()
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["id"].as_i64().unwrap())
        .collect();
    assert_eq!(ids.len(), 2);
    expect(
        &alice
            .delete(&format!("/api/cells/cell_01/contours/{}", ids[0]))
            .unwrap(),
        204,
    );
    let label2 = contours_of(&alice, "/api/cells/cell_01/contours?label=2");
    assert_eq!(
        label2
            .iter()
            .map(|c| c["id"].as_i64().unwrap())
            .collect::<Vec<_>>(),
        [ids[1]]
    );
    // Clear label 2 again: an empty replace leaves the slice undrawn.
    expect(
        &alice
            .json(
                "PUT",
                "/api/cells/cell_01/slices/z/10/contours",
                &json!({"label": 2, "contours": []}),
            )
            .unwrap(),
        200,
    );
    let before_restart = contours_of(&alice, "/api/cells/cell_01/contours");
    assert_eq!(before_restart.len(), 4);

    // Time spent and status.
    let t = alice
        .json("POST", "/api/cells/cell_01/time", &json!({"seconds": 12.5}))
        .unwrap();
    assert_eq!(t.json()["total_seconds"], 12.5);

    // Reload: a new server process on the same folder sees the same tracing.
    drop(server);
    let server = serve(config(dir.path()));
    let alice = signed_in(&server, "alice");
    let after = contours_of(&alice, "/api/cells/cell_01/contours");
    assert_eq!(after, before_restart);
    assert!(
        after
            .iter()
            .all(|c| c["author"] == "alice" && c["tool"] == "pen")
    );
    assert_eq!(after[0]["pressure"], serde_json::json!(vec![0.5f32; 24]));
    let drawn = alice
        .get("/api/cells/cell_01/drawn?label=1&axis=z")
        .unwrap()
        .json();
    assert_eq!(
        drawn,
        json!([{"index": 4, "empty": false}, {"index": 8, "empty": false},
               {"index": 12, "empty": false}, {"index": 16, "empty": false},
               {"index": 20, "empty": true}])
    );
    let cells = alice.get("/api/cells").unwrap().json();
    assert_eq!(cells[0]["status"], "in_progress");
    assert_eq!(cells[0]["seconds"], 12.5);

    // Interpolate: a preview per slice and a stored result.
    let a = alice
        .json(
            "POST",
            "/api/cells/cell_01/interpolate",
            &json!({"label": 1, "axis": "z", "method": "linear"}),
        )
        .unwrap();
    expect(&a, 200);
    let ans = a.json();
    assert_eq!(ans["method"], "linear");
    assert!(ans["result_id"].as_i64().unwrap() > 0);
    let slices = ans["slices"].as_array().unwrap();
    assert_eq!(slices.len(), DIMS[2]);
    for s in slices {
        let k = s["index"].as_u64().unwrap() as usize;
        let drawn = DRAWN.contains(&k) || k == 20;
        assert_eq!(s["drawn"], drawn, "slice {k}");
        let n = s["contours"].as_array().unwrap().len();
        if (4..=16).contains(&k) {
            assert_eq!(n, 1, "slice {k} has one interpolated outline");
        } else {
            assert_eq!(n, 0, "slice {k} is outside the traced range");
        }
    }
    let (meta, mask) = server
        .state
        .store
        .result(ans["result_id"].as_i64().unwrap())
        .unwrap()
        .unwrap();
    assert_eq!((meta.method.as_str(), meta.label), ("linear", 1));
    assert_eq!(
        meta.voxels,
        mask.data().iter().filter(|&&b| b).count() as u64
    );
    assert_eq!(ans["voxels"], meta.voxels);
    let results = alice.get("/api/cells/cell_01/results").unwrap().json();
    assert_eq!(results.as_array().unwrap().len(), 1);
    assert_eq!(results[0]["id"], ans["result_id"]);
    assert_eq!(results[0]["method"], "linear");
    let stored_export = alice
        .get(&format!(
            "/api/cells/cell_01/export?result={}&format=nii",
            ans["result_id"]
        ))
        .unwrap();
    expect(&stored_export, 200);
    let stored_labels = read_export(&stored_export.body, "r.nii");
    assert!(
        stored_labels
            .data()
            .iter()
            .zip(mask.data())
            .all(|(&l, &m)| l == u16::from(m))
    );

    // Export: the interpolated label volume, exactly the tracing on drawn slices.
    let exp = alice
        .get("/api/cells/cell_01/export?format=nii.gz&method=linear")
        .unwrap();
    expect(&exp, 200);
    let exported = read_export(&exp.body, "e.nii.gz");
    assert_eq!(exported.geometry().dims, DIMS);
    let core: Vec<interslice_core::Contour> = after
        .iter()
        .map(|c| {
            let slice = interslice_core::SliceRef {
                axis: serde_json::from_value(c["axis"].clone()).unwrap(),
                index: c["index"].as_u64().unwrap() as usize,
            };
            let points = serde_json::from_value(c["points"].clone()).unwrap();
            let label = c["label"].as_u64().unwrap() as u16;
            interslice_core::Contour::new(slice, label, points, "alice", "t")
        })
        .collect();
    let raster = interslice_core::raster::contours_to_mask(exported.geometry(), &core, 1).unwrap();
    let mut on_drawn = exported.clone();
    let mut truth = exported.clone();
    for k in 0..DIMS[2] {
        let keep = DRAWN.contains(&k) || k == 20;
        for j in 0..DIMS[1] {
            for i in 0..DIMS[0] {
                let idx = i + DIMS[0] * (j + DIMS[1] * k);
                if !keep {
                    on_drawn.data_mut()[idx] = 0;
                }
                truth.data_mut()[idx] = u16::from(raster.data()[idx]);
            }
        }
    }
    let m = metrics::evaluate_label(&truth, &on_drawn, 1, 1.0).unwrap();
    assert_eq!((m.fp, m.fn_), (0, 0));
    assert!(m.tp > 0);
    assert_eq!(m.dice, Some(1.0));
    assert_eq!(m.hd, Some(0.0));
    // Between drawn slices the export has the interpolated voxels.
    assert_eq!(
        exported.data().iter().filter(|&&v| v == 1).count() as u64,
        meta.voxels
    );

    // The same volume as NRRD and TIFF; the contours as the contours file.
    for (format, name) in [("nrrd", "e.nrrd"), ("tiff", "e.tiff")] {
        let a = alice
            .get(&format!(
                "/api/cells/cell_01/export?format={format}&method=linear"
            ))
            .unwrap();
        expect(&a, 200);
        assert_eq!(
            read_export(&a.body, name).data(),
            exported.data(),
            "{format}"
        );
    }
    let cj = alice
        .get("/api/cells/cell_01/export?format=contours")
        .unwrap();
    expect(&cj, 200);
    let file = interslice_core::contour_file::read(std::str::from_utf8(&cj.body).unwrap()).unwrap();
    assert_eq!(file.contours.len(), 4);
    assert_eq!(file.drawn_empty.len(), 1);

    // Evaluate: the user against a file on disk and against an upload.
    std::fs::create_dir_all(dir.path().join("segmentations/cell_01")).unwrap();
    std::fs::write(
        dir.path().join("segmentations/cell_01/mine.nii.gz"),
        &exp.body,
    )
    .unwrap();
    let ev = alice
        .json(
            "POST",
            "/api/cells/cell_01/evaluate",
            &json!({"label": 1, "method": "linear", "reference": {"user": "alice"},
                    "test": {"path": "segmentations/cell_01/mine.nii.gz"}}),
        )
        .unwrap();
    expect(&ev, 200);
    assert_eq!(ev.json()["dice"], 1.0);
    let up = alice
        .send(
            "POST",
            "/api/cells/cell_01/segmentations/upload?name=truth.nii",
            Some((&exported_truth_bytes(&truth), "application/octet-stream")),
        )
        .unwrap();
    expect(&up, 201);
    let seg = up.json()["id"].as_str().unwrap().to_string();
    let ev = alice
        .json(
            "POST",
            "/api/cells/cell_01/evaluate",
            &json!({"label": 1, "reference": {"segmentation": seg},
                    "test": {"path": "segmentations/cell_01/mine.nii.gz"}}),
        )
        .unwrap();
    expect(&ev, 200);
    let e = ev.json();
    assert_eq!(e["fn"], 0, "the drawn slices are inside the export");
    assert_eq!(e["tp"].as_u64().unwrap(), m.tp);
    assert!(e["dice"].as_f64().unwrap() < 1.0);
    let listed = alice
        .get("/api/cells/cell_01/segmentations")
        .unwrap()
        .json();
    let methods: Vec<&str> = listed
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["method"].as_str().unwrap())
        .collect();
    assert_eq!(methods, ["upload", "file"]);

    // Finished cells leave the user's queue but stay in the list.
    let s = alice
        .json(
            "PUT",
            "/api/cells/cell_01/status",
            &json!({"status": "done"}),
        )
        .unwrap();
    expect(&s, 200);
    let queue = alice.get("/api/cells?queue=true").unwrap().json();
    assert_eq!(queue.as_array().unwrap().len(), 1);
    assert_eq!(queue[0]["id"], "cell_02");
    let all = alice.get("/api/cells").unwrap().json();
    assert_eq!(all[0]["status"], "done");
    // Another user's queue still has it.
    let bob = signed_in(&server, "bob");
    assert_eq!(
        bob.get("/api/cells?queue=true")
            .unwrap()
            .json()
            .as_array()
            .unwrap()
            .len(),
        2
    );

    // Every change is in the append-only audit log.
    let log = server.state.store.audit_log(1000).unwrap();
    for action in [
        "contour.add",
        "slice.empty",
        "undo",
        "redo",
        "slice.replace",
        "contour.delete",
        "interpolate",
        "cell.status",
        "segmentation.add",
    ] {
        assert!(log.iter().any(|e| e.action == action), "{action}");
    }
}

fn exported_truth_bytes(truth: &LabelVolume) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.nii");
    interslice_io::write_labels(&p, truth).unwrap();
    std::fs::read(p).unwrap()
}

/// The OpenAPI document (collected from the handlers' declarations as the
/// router is built) lists exactly the routes of docs/API.md, every one of
/// them answers (not the API's 404 for unknown endpoints, not 405), and every
/// schema it refers to is in it.
#[test]
fn openapi_document_lists_every_route() {
    let dir = project();
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    let doc = c.get("/api/openapi.json").unwrap().json();
    assert!(doc["openapi"].as_str().unwrap().starts_with("3."));
    let paths = doc["paths"].as_object().unwrap();
    // Every schema a route refers to is in the components.
    let text = doc.to_string();
    let schemas = doc["components"]["schemas"].as_object().unwrap();
    let refs: Vec<&str> = text
        .split("\"$ref\":\"#/components/schemas/")
        .skip(1)
        .map(|part| part.split('"').next().unwrap())
        .collect();
    assert!(refs.len() >= 10, "{refs:?}");
    for name in refs {
        assert!(schemas.contains_key(name), "missing schema {name}");
    }

    // The routes of the reference tables in docs/API.md (rows that start
    // with "| `METHOD /api/..."), query strings and optional parts removed.
    let api_md = include_str!("../../../../docs/API.md");
    let mut declared: Vec<(String, String)> = api_md
        .lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| {
            let cell = l.split('`').next()?;
            let (m, path) = cell.split_once(' ')?;
            if !["GET", "POST", "PUT", "DELETE"].contains(&m) || !path.starts_with("/api/") {
                return None;
            }
            let path = path.split(['[', '?']).next()?;
            Some((m.to_string(), path.to_string()))
        })
        .collect();
    declared.sort();
    declared.dedup();
    let mut documented: Vec<(String, String)> = Vec::new();
    for (path, item) in paths {
        for m in item.as_object().unwrap().keys() {
            if ["get", "post", "put", "delete"].contains(&m.as_str()) {
                documented.push((m.to_ascii_uppercase(), path.clone()));
            }
        }
    }
    documented.sort();
    assert_eq!(
        documented, declared,
        "docs/API.md and the served document differ"
    );
    assert!(declared.len() >= 30, "{}", declared.len());

    // Each documented route is served.
    for (m, path) in &documented {
        let url = path
            .replace("{cell}", "cell_01")
            .replace("{axis}", "z")
            .replace("{index}", "0")
            .replace("{id}", "999999")
            .replace("{result}", "999999");
        // A body only where the document declares one: a body the server
        // never reads makes it close the keep-alive connection, and the
        // next request could race that close.
        let takes_body = paths[path.as_str()][m.to_ascii_lowercase()]
            .get("requestBody")
            .is_some();
        let body = takes_body.then_some((&b"{}"[..], "application/json"));
        let a = c.send(m, &url, body).unwrap();
        assert_ne!(a.status, 405, "{m} {path}");
        if a.status == 404 {
            let e = a.error().unwrap_or_default();
            assert!(!e.contains("no such API endpoint"), "{m} {path}: {e}");
        }
    }
    // The logout route signs out.
    assert_eq!(c.send("POST", "/api/logout", None).unwrap().status, 204);
}

/// The load test, short: 20 clients for 3 s; nothing lost or crossed.
#[test]
fn concurrent_clients_lose_and_cross_nothing() {
    let report =
        interslice_test_support::loadtest::run(&interslice_test_support::loadtest::LoadConfig {
            clients: 20,
            duration: Duration::from_secs(3),
            cells: 4,
            size: 32,
        })
        .unwrap();
    eprint!("{report}");
    assert!(report.clean(), "{report}");
    assert!(report.acknowledged_writes > 100, "{report}");
    assert_eq!(report.ops.len(), 5);
}

/// A folder of slice images is one cell; 16-bit slices come as little-endian
/// u16, along every axis.
#[test]
fn slice_folder_cell_with_16_bit_little_endian_slices() {
    let dir = tempfile::tempdir().unwrap();
    let g = interslice_core::Geometry::new(
        [5, 4, 3],
        [0.5, 0.5, 1.0],
        interslice_core::LengthUnit::Micrometre,
    )
    .unwrap();
    let data: Vec<u16> = (0..60).map(|n| 1000 * n as u16 + 7).collect();
    let v = interslice_core::Volume::from_vec(g, data).unwrap();
    interslice_io::write_volume(
        &dir.path().join("stack"),
        &interslice_core::AnyVolume::U16(v.clone()),
    )
    .unwrap();
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    let cells = c.get("/api/cells").unwrap().json();
    assert_eq!(cells[0]["id"], "stack");
    assert_eq!(cells[0]["dtype"], "u16");
    assert_eq!(cells[0]["dims"], json!([5, 4, 3]));
    for (axis, index, w, h) in [("z", 2, 5, 4), ("y", 3, 5, 3), ("x", 4, 4, 3)] {
        let a = c
            .get(&format!("/api/cells/stack/slices/{axis}/{index}"))
            .unwrap();
        expect(&a, 200);
        assert_eq!(a.slice_header, Some((w, h, "u16".to_string())));
        let want: Vec<u8> = v
            .slice(Axis::parse(axis).unwrap(), index)
            .unwrap()
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        assert_eq!(a.body, want, "{axis}={index}");
    }
    expect(&c.get("/api/cells/stack/slices/z/3").unwrap(), 404);
}

/// A live preview is kept in memory for its user: a negative id, its mesh
/// served, no stored result; asking without `preview` stores the result.
#[test]
fn previews_stay_in_memory_and_results_are_stored_when_asked() {
    let dir = common::project();
    let server = common::serve(common::config(dir.path()));
    let mut alice = common::signed_in(&server, "alice");
    for k in [6, 14] {
        let body = json!({"label": 1, "axis": "z", "index": k, "points": common::circle(16.0, 14.0, 6.0, 24)});
        expect(
            &alice
                .json("POST", "/api/cells/cell_01/contours", &body)
                .unwrap(),
            201,
        );
    }
    let ask = |c: &mut Client, preview: bool| {
        let body = json!({"label": 1, "axis": "z", "method": "linear", "preview": preview});
        let a = c
            .json("POST", "/api/cells/cell_01/interpolate", &body)
            .unwrap();
        expect(&a, 200);
        a.json()
    };
    let preview = ask(&mut alice, true);
    let id = preview["result_id"].as_i64().unwrap();
    assert!(id < 0, "{id}");
    let results = alice.get("/api/cells/cell_01/results").unwrap().json();
    assert_eq!(results.as_array().unwrap().len(), 0, "nothing stored");
    let mesh = alice
        .get(&format!("/api/cells/cell_01/results/{id}/mesh"))
        .unwrap();
    expect(&mesh, 200);
    assert!(!mesh.json()["indices"].as_array().unwrap().is_empty());
    let bob = common::signed_in(&server, "bob");
    expect(
        &bob.get(&format!("/api/cells/cell_01/results/{id}/mesh"))
            .unwrap(),
        404,
    );
    let stored = ask(&mut alice, false);
    assert!(stored["result_id"].as_i64().unwrap() > 0);
    assert_eq!(stored["voxels"], preview["voxels"]);
    let results = alice.get("/api/cells/cell_01/results").unwrap().json();
    assert_eq!(results.as_array().unwrap().len(), 1);
}
