//! `GET /api/cells/{cell}/summary`: a tracing's slices, time and predicted
//! Dice, read like every tracing (a tracer their own, a reviewer anyone's).
use crate::common;

use common::*;
use interslice_test_support::client::Client;
use serde_json::json;

#[test]
fn summary_counts_slices_time_and_predicts_the_dice() {
    let dir = project();
    let (_server, [alice, bob, rita]) = team(dir.path());
    let summary = |c: &Client, query: &str| {
        let a = c
            .get(&format!("/api/cells/cell_01/summary?{query}"))
            .unwrap();
        (a.status, a.json())
    };
    // Nothing traced yet: no slices, no time, no prediction.
    let (status, s) = summary(&alice, "label=1");
    assert_eq!(status, 200);
    assert_eq!(s["traced_slices"], 0);
    assert_eq!(s["seconds"], 0.0);
    assert!(s["predicted_dice"].is_null(), "{s}");

    // A cone of circles on five z slices, 30 s of drawing each.
    for (n, k) in [4usize, 8, 12, 16, 20].into_iter().enumerate() {
        let body = json!({"label": 1, "axis": "z", "index": k,
            "points": circle(16.0, 14.0, 5.0 + n as f64, 48), "duration_ms": 30000.0});
        expect(
            &alice
                .json("POST", "/api/cells/cell_01/contours", &body)
                .unwrap(),
            201,
        );
    }
    for k in [6usize, 10] {
        let body = json!({"label": 2, "axis": "z", "index": k,
            "points": circle(16.0, 14.0, 3.0, 24)});
        expect(
            &alice
                .json("POST", "/api/cells/cell_01/contours", &body)
                .unwrap(),
            201,
        );
    }
    let (status, s) = summary(&alice, "label=1");
    assert_eq!(status, 200, "{s}");
    assert_eq!(s["label"], 1);
    assert_eq!(s["axis"], "z");
    assert_eq!(s["traced_slices"], 5);
    assert_eq!(s["empty_slices"], 0);
    // No recorded cell time yet: the contours' drawing time.
    assert_eq!(s["contour_seconds"], 150.0);
    assert_eq!(s["seconds"], 150.0);
    let predicted = s["predicted_dice"].as_f64().unwrap();
    assert!(predicted > 0.95 && predicted <= 1.0, "{s}");

    // The recorded time of the cell wins; a drawn-empty slice is counted.
    expect(
        &alice
            .json(
                "POST",
                "/api/cells/cell_01/time",
                &json!({"seconds": 600.0}),
            )
            .unwrap(),
        200,
    );
    expect(
        &alice
            .json(
                "POST",
                "/api/cells/cell_01/slices/z/22/empty",
                &json!({"label": 1}),
            )
            .unwrap(),
        200,
    );
    let (_, s) = summary(&alice, "label=1");
    assert_eq!(s["seconds"], 600.0);
    assert_eq!(s["empty_slices"], 1);
    assert_eq!(s["traced_slices"], 5);
    // Two drawn slices: nothing to hold out, no prediction.
    let (_, s2) = summary(&alice, "label=2");
    assert_eq!(s2["traced_slices"], 2);
    assert!(s2["predicted_dice"].is_null(), "{s2}");

    // A reviewer reads Alice's summary; another tracer may not.
    let (status, r) = summary(&rita, "label=1&user=alice");
    assert_eq!(status, 200);
    assert_eq!(r, s);
    let (status, _) = summary(&bob, "label=1&user=alice");
    assert_eq!(status, 403);
    let (status, b) = summary(&bob, "label=1");
    assert_eq!(status, 200);
    assert_eq!(b["traced_slices"], 0);
    // Bad requests are one-line errors.
    for (q, want) in [
        ("label=99", 400),
        ("", 400),
        ("label=1&method=nope", 400),
        ("label=1&user=nobody", 404),
    ] {
        let (status, e) = summary(&rita, q);
        assert_eq!(status, want, "{q}: {e}");
        assert!(
            e["error"].as_str().is_some_and(|m| !m.contains('\n')),
            "{e}"
        );
    }
    let a = rita.get("/api/cells/nope/summary?label=1").unwrap();
    assert_eq!(a.status, 404);
}
