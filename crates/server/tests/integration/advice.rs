//! `GET /api/cells/{cell}/advice`: which slice of a label to trace next, from
//! the signed-in user's own tracing, as `interslice advise` ranks them.
use crate::common;

use common::*;
use serde_json::json;

fn trace(c: &interslice_test_support::client::Client, z: usize, r: f64) {
    let a = c
        .json(
            "POST",
            "/api/cells/cell_01/contours",
            &json!({"label": 2, "axis": "z", "index": z, "points": circle(16.0, 14.0, r, 32)}),
        )
        .unwrap();
    expect(&a, 201);
}

#[test]
fn advice_suggests_undrawn_slices_of_the_users_own_tracing() {
    let dir = project();
    let server = serve(config(dir.path()));
    let alice = signed_in(&server, "alice");
    let bob = signed_in(&server, "bob");
    let url = "/api/cells/cell_01/advice?label=2&axis=z&count=3";

    // One drawn slice is not enough, and the answer says what to do.
    trace(&alice, 2, 4.0);
    let a = alice.get(url).unwrap();
    expect(&a, 400);
    assert!(a.error().unwrap().contains("at least two drawn slices"));

    // Two slices: the best slice is the middle of the gap between them.
    trace(&alice, 20, 10.0);
    let a = alice.get(url).unwrap();
    expect(&a, 200);
    let advice = a.json();
    assert_eq!(advice["axis"], "z");
    assert_eq!(advice["drawn"], json!([2, 20]));
    let s = advice["suggestions"].as_array().unwrap();
    assert_eq!(s.len(), 3);
    assert_eq!(s[0]["slice"], 11);
    assert_eq!(s[0]["between"], json!([2, 20]));
    let gains: Vec<f64> = s.iter().map(|x| x["dice_gain"].as_f64().unwrap()).collect();
    assert!(
        gains[0] > 0.0 && gains.windows(2).all(|w| w[0] >= w[1]),
        "{gains:?}"
    );
    let predicted = advice["predicted_dice"].as_f64().unwrap();
    assert!(predicted > 0.0 && predicted < 1.0, "{predicted}");

    // Tracing the suggestion moves the advice elsewhere and raises the
    // predicted Dice.
    trace(&alice, 11, 7.0);
    let after = alice.get(url).unwrap().json();
    // (the three slices left are spread over both halves).
    let picks: Vec<u64> = after["suggestions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["slice"].as_u64().unwrap())
        .collect();
    assert!(
        picks.iter().all(|&s| s != 11 && s != 2 && s != 20),
        "{after}"
    );
    assert!(
        picks.iter().any(|&s| s < 11) && picks.iter().any(|&s| s > 11),
        "{after}"
    );
    assert!(
        after["predicted_dice"].as_f64().unwrap() > predicted,
        "{after}"
    );

    // Bob has traced nothing: alice's tracing is not his.
    expect(&bob.get(url).unwrap(), 400);

    // Bounds: count, label, axis, method.
    for bad in ["count=0", "count=51", "count=-1", "axis=w", "method=nope"] {
        let a = alice
            .get(&format!("/api/cells/cell_01/advice?label=2&{bad}"))
            .unwrap();
        expect(&a, 400);
    }
    expect(
        &alice.get("/api/cells/cell_01/advice?label=99").unwrap(),
        400,
    );
    expect(&alice.get("/api/cells/nope/advice?label=2").unwrap(), 404);
}
