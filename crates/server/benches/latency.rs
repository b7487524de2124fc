//! Latency of the two requests a tracer makes most, over loopback HTTP with
//! keep-alive, one request at a time: a 512×512 16-bit slice, and saving a
//! contour of a pen stroke (200 points with pressure and per-point times).
//! Target: p99 under 5 ms for both.
//!
//! `cargo bench -p interslice-server --bench latency [-- REQUESTS]`
use interslice_test_support::client::{Client, quantile};
use std::time::Instant;

fn report(what: &str, mut ms: Vec<f64>) -> bool {
    ms.sort_by(f64::total_cmp);
    let p50 = quantile(&ms, 0.5).unwrap_or(f64::NAN);
    let p99 = quantile(&ms, 0.99).unwrap_or(f64::NAN);
    let max = ms.last().copied().unwrap_or(f64::NAN);
    let ok = p99 < 5.0;
    println!(
        "{what:<34} n={:<6} p50 {p50:>6.3} ms  p99 {p99:>6.3} ms  max {max:>7.3} ms  {}",
        ms.len(),
        if ok { "(< 5 ms)" } else { "(OVER 5 ms)" }
    );
    ok
}

fn main() -> anyhow::Result<()> {
    // `cargo bench` passes `--bench`; the first number, if any, is the count.
    let n: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(3000);
    let dir = tempfile::tempdir()?;
    interslice_test_support::loadtest::write_cells(dir.path(), 1, [512, 512, 16], true)?;
    let mut config = interslice_server::Config::new(dir.path());
    config.bind = std::net::SocketAddr::from(([127, 0, 0, 1], 0));
    let server = interslice_server::spawn(config)?;
    let mut c = Client::new(&server.url());
    let a = c.login("bench", None)?;
    anyhow::ensure!(a.ok(), "login: {:?}", a.error());

    // Load the cell once (the first request reads the file).
    let a = c.get("/api/cells/cell_01/slices/z/0")?;
    anyhow::ensure!(
        a.ok() && a.body.len() == 512 * 512 * 2,
        "slice: {}",
        a.status
    );

    for _ in 0..200 {
        c.get("/api/cells/cell_01/slices/z/3")?;
    }
    let mut slice_ms = Vec::with_capacity(n);
    for i in 0..n {
        let t = Instant::now();
        let a = c.get(&format!("/api/cells/cell_01/slices/z/{}", i % 16))?;
        slice_ms.push(t.elapsed().as_secs_f64() * 1e3);
        anyhow::ensure!(a.body.len() == 512 * 512 * 2, "slice {}", a.status);
    }
    let mut y_ms = Vec::with_capacity(n / 4);
    for i in 0..n / 4 {
        let t = Instant::now();
        let a = c.get(&format!("/api/cells/cell_01/slices/y/{}", i % 512))?;
        y_ms.push(t.elapsed().as_secs_f64() * 1e3);
        anyhow::ensure!(a.body.len() == 512 * 16 * 2, "slice {}", a.status);
    }

    // A tracer's stroke lands on a slice holding few contours: spread the
    // saves over every (axis, slice, label), so each slice gets one or two.
    let keys: Vec<(&str, usize, usize)> = ["x", "y"]
        .into_iter()
        .flat_map(|a| (0..512).map(move |k| (a, k)))
        .chain((0..16).map(|k| ("z", k)))
        .flat_map(|(a, k)| (1..=4).map(move |l| (a, k, l)))
        .collect();
    let stroke = |i: usize| {
        let (axis, index, label) = keys[i % keys.len()];
        let (w, h) = if axis == "z" {
            (512.0, 512.0)
        } else {
            (512.0, 16.0)
        };
        let points: Vec<[f64; 2]> = (0..200)
            .map(|k| {
                let t = k as f64 / 200.0 * std::f64::consts::TAU;
                [w / 2.0 + w / 4.0 * t.cos(), h / 2.0 + h / 4.0 * t.sin()]
            })
            .collect();
        serde_json::json!({
            "label": label, "axis": axis, "index": index, "points": points,
            "pressure": vec![0.6; 200],
            "times_ms": (0..200).map(|k| k as f64 * 16.0).collect::<Vec<_>>(),
            "tool": "pen", "client_id": format!("bench-{i}"),
        })
    };
    let mut save_ms = Vec::with_capacity(n);
    for i in 0..n {
        let body = stroke(i);
        let t = Instant::now();
        let a = c.json("POST", "/api/cells/cell_01/contours", &body)?;
        save_ms.push(t.elapsed().as_secs_f64() * 1e3);
        anyhow::ensure!(a.status == 201, "save: {} {:?}", a.status, a.error());
    }

    let ok = [
        report("GET 512x512 u16 slice (z)", slice_ms),
        report("GET 512x16 u16 slice (y, gathered)", y_ms),
        report("POST contour (200-point stroke)", save_ms),
    ];
    if ok.contains(&false) {
        eprintln!("latency: a p99 is over 5 ms on this machine");
    }
    Ok(())
}
