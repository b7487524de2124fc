//! `interslice serve`, `user`, `export` and `demo` as a user runs them, and the
//! durability of the annotation database: the server process is killed with
//! SIGKILL while clients write contours, then restarted.
use interslice_store::Store;
use interslice_test_support::client::Client;
use serde_json::json;
use std::collections::{BTreeMap, BTreeSet};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

const BIN: &str = env!("CARGO_BIN_EXE_interslice");

/// A running `interslice serve` child and its URL.
struct Served {
    child: Child,
    url: String,
}

/// Start `interslice serve DIR --bind BIND ...` and wait for the line that
/// says where it listens.
fn serve(dir: &Path, bind: &str, extra: &[&str]) -> Served {
    let mut child = Command::new(BIN)
        .arg("serve")
        .arg(dir)
        .args(["--bind", bind])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run interslice serve");
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let url = loop {
        let line = lines
            .next()
            .expect("serve prints its URL")
            .expect("stdout is text");
        if let Some(rest) = line.split("serving on ").nth(1) {
            break rest
                .split_whitespace()
                .next()
                .unwrap()
                .trim_end_matches('/')
                .to_string();
        }
    };
    Served { child, url }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    interslice_test_support::loadtest::write_cells(dir.path(), 1, [32, 32, 24], false).unwrap();
    dir
}

/// Points unique to a write, on a 1/4-pixel grid (exact through JSON).
fn points(writer: usize, seq: usize) -> Vec<[f64; 2]> {
    let x = 1.0 + (seq % 80) as f64 * 0.25;
    let y = 1.0 + writer as f64 * 8.0 + (seq / 80 % 20) as f64 * 0.25;
    vec![[x, y], [x + 4.0, y], [x + 4.0, y + 3.0], [x, y + 3.0]]
}

/// What one writer sent and what it was told.
#[derive(Default)]
struct Log {
    /// client_id → points, of every request sent.
    sent: BTreeMap<String, Vec<[f64; 2]>>,
    /// client_ids answered 201.
    acked: BTreeSet<String>,
    /// The request that got no answer (cut by the kill), if any.
    in_flight: Option<String>,
}

/// Write contours in a loop until the server stops answering.
fn write_until_killed(url: String, writer: usize, round: usize) -> Log {
    let mut c = Client::new(&url);
    assert_eq!(c.login(&format!("w{writer}"), None).unwrap().status, 200);
    let mut log = Log::default();
    for seq in 0.. {
        let id = format!("w{writer}-r{round}-{seq}");
        let p = points(writer, seq);
        log.sent.insert(id.clone(), p.clone());
        let body = json!({"label": 1 + (seq % 2), "axis": "z", "index": seq % 24,
                          "points": p, "client_id": id});
        match c.json("POST", "/api/cells/cell_01/contours", &body) {
            Ok(a) if a.status == 201 => {
                log.acked.insert(id);
            }
            Ok(a) => panic!("write refused: {} {:?}", a.status, a.error()),
            Err(_) => {
                log.in_flight = Some(id);
                break;
            }
        }
    }
    log
}

/// The writer's contours as stored: client_id → points (ids must be unique).
fn stored(url: &str, writer: usize) -> BTreeMap<String, Vec<[f64; 2]>> {
    let mut c = Client::new(url);
    assert_eq!(c.login(&format!("w{writer}"), None).unwrap().status, 200);
    let a = c.get("/api/cells/cell_01/contours").unwrap();
    assert_eq!(a.status, 200);
    let rows = a.json();
    let rows = rows.as_array().unwrap();
    let mut out = BTreeMap::new();
    for r in rows {
        assert_eq!(r["author"], format!("w{writer}"));
        let id = r["client_id"].as_str().unwrap().to_string();
        let p: Vec<[f64; 2]> = serde_json::from_value(r["points"].clone()).unwrap();
        assert!(out.insert(id, p).is_none(), "a write is stored twice");
    }
    out
}

#[test]
fn sigkill_loses_no_acknowledged_write_and_invents_none() {
    let dir = project();
    let db = interslice_store::default_db_path(dir.path());
    let mut all_sent: Vec<BTreeMap<String, Vec<[f64; 2]>>> = vec![BTreeMap::new(); 2];
    let mut all_acked: Vec<BTreeSet<String>> = vec![BTreeSet::new(); 2];
    let mut unanswered: Vec<BTreeSet<String>> = vec![BTreeSet::new(); 2];
    for round in 0..3 {
        let mut server = serve(dir.path(), "127.0.0.1:0", &[]);
        let writers: Vec<_> = (0..2)
            .map(|w| {
                let url = server.url.clone();
                std::thread::spawn(move || write_until_killed(url, w, round))
            })
            .collect();
        // Let them write for a while, then kill -9 in the middle of it.
        std::thread::sleep(Duration::from_millis(1200));
        server.child.kill().unwrap();
        server.child.wait().unwrap();
        for (w, h) in writers.into_iter().enumerate() {
            let log = h.join().unwrap();
            assert!(log.acked.len() > 20, "round {round}: too few writes");
            eprintln!(
                "round {round}, writer {w}: {} acknowledged, cut by the kill: {:?}",
                log.acked.len(),
                log.in_flight
            );
            all_sent[w].extend(log.sent);
            all_acked[w].extend(log.acked);
            unanswered[w].extend(log.in_flight);
        }
        // The database as the kill left it is sound.
        {
            let store = Store::open(&db).unwrap();
            assert_eq!(store.integrity_check().unwrap(), "ok");
        }
        let server = serve(dir.path(), "127.0.0.1:0", &[]);
        for w in 0..2 {
            let got = stored(&server.url, w);
            for id in &all_acked[w] {
                assert_eq!(got.get(id), all_sent[w].get(id), "acknowledged {id}");
            }
            for (id, p) in &got {
                assert!(
                    all_acked[w].contains(id) || unanswered[w].contains(id),
                    "{id} is stored but was never acknowledged"
                );
                assert_eq!(Some(p), all_sent[w].get(id), "{id} changed");
            }
        }
        // A retry of an unanswered write is stored exactly once.
        let mut c = Client::new(&server.url);
        assert_eq!(c.login("w0", None).unwrap().status, 200);
        if let Some(id) = unanswered[0].iter().next_back().cloned() {
            let p = all_sent[0][&id].clone();
            let body = json!({"label": 1, "axis": "z", "index": 0, "points": p, "client_id": id});
            let a = c
                .json("POST", "/api/cells/cell_01/contours", &body)
                .unwrap();
            assert!(a.status == 200 || a.status == 201, "{}", a.status);
            assert_eq!(stored(&server.url, 0).get(&id), Some(&p));
            all_acked[0].insert(id);
        }
    }
    let store = Store::open(&db).unwrap();
    assert_eq!(store.integrity_check().unwrap(), "ok");
}

#[test]
fn off_loopback_serve_needs_accounts_made_by_user_add() {
    let dir = project();
    let add = Command::new(BIN)
        .args(["user", "add", "alice", "--dir"])
        .arg(dir.path())
        .env("INTERSLICE_PASSWORD", "a long password")
        .output()
        .unwrap();
    assert!(
        add.status.success(),
        "{}",
        String::from_utf8_lossy(&add.stderr)
    );
    let short = Command::new(BIN)
        .args(["user", "add", "bob", "--dir"])
        .arg(dir.path())
        .env("INTERSLICE_PASSWORD", "short")
        .output()
        .unwrap();
    assert_eq!(short.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&short.stderr).starts_with("error: "));
    let list = Command::new(BIN)
        .args(["user", "list", "--dir"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert_eq!(String::from_utf8_lossy(&list.stdout), "alice\ttracer\n");

    // Any address but loopback: passwords required.
    let server = serve(dir.path(), "0.0.0.0:0", &[]);
    let url = server.url.replace("0.0.0.0", "127.0.0.1");
    let mut c = Client::new(&url);
    assert_eq!(c.get("/api/cells").unwrap().status, 401);
    assert_eq!(c.login("alice", None).unwrap().status, 401);
    assert_eq!(c.login("alice", Some("wrong")).unwrap().status, 401);
    assert_eq!(
        c.login("alice", Some("a long password")).unwrap().status,
        200
    );
    let cells = c.get("/api/cells").unwrap();
    assert_eq!(cells.status, 200);
    assert_eq!(cells.json()[0]["id"], "cell_01");
}

#[test]
fn export_command_writes_what_the_server_exports() {
    let dir = project();
    let mut config = interslice_server::Config::new(dir.path());
    config.bind = std::net::SocketAddr::from(([127, 0, 0, 1], 0));
    let server = interslice_server::spawn(config).unwrap();
    let mut c = Client::new(&server.url());
    assert_eq!(c.login("alice", None).unwrap().status, 200);
    for (k, r) in [(6, 6.0), (12, 8.0), (18, 5.0)] {
        for (label, scale) in [(1, 1.0), (2, 0.5)] {
            let p: Vec<[f64; 2]> = (0..16)
                .map(|n| {
                    let t = n as f64 / 16.0 * std::f64::consts::TAU;
                    [16.0 + r * scale * t.cos(), 16.0 + r * scale * t.sin()]
                })
                .collect();
            let a = c
                .json(
                    "POST",
                    "/api/cells/cell_01/contours",
                    &json!({"label": label, "axis": "z", "index": k, "points": p}),
                )
                .unwrap();
            assert_eq!(a.status, 201);
        }
    }
    let http = c
        .get("/api/cells/cell_01/export?format=nii.gz&method=linear")
        .unwrap();
    assert_eq!(http.status, 200);
    drop(server);

    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let web = out.join("web.nii.gz");
    std::fs::write(&web, &http.body).unwrap();
    let cli = out.join("cli.nii.gz");
    let run = |args: &[&str]| {
        Command::new(BIN)
            .arg("export")
            .arg(dir.path())
            .args(args)
            .output()
            .unwrap()
    };
    let o = run(&[
        "--cell",
        "cell_01",
        "--user",
        "alice",
        "--method",
        "linear",
        "--out",
        cli.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = interslice_io::read_labels(&web).unwrap();
    let b = interslice_io::read_labels(&cli).unwrap();
    assert_eq!(a.geometry(), b.geometry());
    assert_eq!(a.data(), b.data());
    assert!(a.data().contains(&1) && a.data().contains(&2));

    // One label only.
    let one = out.join("nucleus.nrrd");
    let o = run(&[
        "--cell",
        "cell_01",
        "--user",
        "alice",
        "--label",
        "2",
        "--method",
        "linear",
        "--out",
        one.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let n = interslice_io::read_labels(&one).unwrap();
    assert!(n.data().iter().all(|&v| v == 0 || v == 2));
    assert_eq!(
        n.data().iter().filter(|&&v| v == 2).count(),
        a.data().iter().filter(|&&v| v == 2).count()
    );

    // Errors are one line with exit 1.
    for args in [
        &["--cell", "nope", "--user", "alice"][..],
        &["--cell", "cell_01", "--user", "nobody"][..],
        &["--cell", "../cell_01", "--user", "alice"][..],
    ] {
        let mut all = args.to_vec();
        all.extend(["--out", "x.nii.gz"]);
        let o = run(&all);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.starts_with("error: ") && err.lines().count() == 1,
            "{err}"
        );
    }
}

#[test]
fn demo_writes_cells_and_their_truth() {
    let dir = tempfile::tempdir().unwrap();
    let project = dir.path().join("p");
    let o = Command::new(BIN)
        .arg("demo")
        .arg(&project)
        .args(["--no-serve", "--size", "32", "--count", "2"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for n in 1..=2 {
        let image =
            interslice_io::read_volume(&project.join(format!("cell_{n:03}.nii.gz"))).unwrap();
        let labels = interslice_io::read_labels(
            &project.join(format!("ground_truth/cell_{n:03}_labels.nii.gz")),
        )
        .unwrap();
        assert_eq!(image.geometry().dims, [32; 3]);
        assert_eq!(labels.geometry().dims, [32; 3]);
        // Cell and nucleus always; the nucleoli may be too small at 32³.
        for l in 1..=2u16 {
            assert!(labels.data().contains(&l), "cell {n} has label {l}");
        }
        assert!(labels.data().iter().all(|&l| l <= 4));
    }
    // The server lists the cells, never the ground truth folder.
    let state =
        interslice_server::AppState::open(&interslice_server::Config::new(&project)).unwrap();
    let ids: Vec<String> = state.cells.read().unwrap().keys().cloned().collect();
    assert_eq!(ids, ["cell_001", "cell_002"]);
}

/// A circle of radius `r` around (`cu`, `cv`) on a slice, 24 points.
fn circle(cu: f64, cv: f64, r: f64) -> Vec<[f64; 2]> {
    (0..24)
        .map(|n| {
            let t = n as f64 / 24.0 * std::f64::consts::TAU;
            [cu + r * t.cos(), cv + r * t.sin()]
        })
        .collect()
}

#[test]
fn a_contours_file_interpolates_to_the_same_labels_through_the_cli_and_the_server() {
    use interslice_core::contour_file::{ContourFile, DrawnEmpty, default_labels};
    use interslice_core::{Axis, Contour, SliceRef};
    let dir = project();
    let cell = dir.path().join("cell_01.nii");
    let geometry = interslice_io::read_volume(&cell)
        .unwrap()
        .geometry()
        .clone();
    // Each label has its own drawn slices: the cell (1) on z = 4, 12, 20,
    // the nucleus (2) on z = 8, 14 and drawn empty on z = 18, a nucleolus
    // (3) across x = 12, 18. A slice drawn for one label says nothing about
    // the others.
    let slice = |axis, index| SliceRef { axis, index };
    let traced = |s, label, points| Contour::new(s, label, points, "alice", "2026-01-01T00:00:00Z");
    let mut contours = Vec::new();
    for (k, r) in [(4, 6.0), (12, 9.0), (20, 5.0)] {
        contours.push(traced(slice(Axis::Z, k), 1, circle(16.0, 16.0, r)));
    }
    for (k, r) in [(8, 4.0), (14, 4.5)] {
        contours.push(traced(slice(Axis::Z, k), 2, circle(16.0, 16.0, r)));
    }
    for (i, r) in [(12, 2.0), (18, 2.5)] {
        contours.push(traced(slice(Axis::X, i), 3, circle(20.0, 16.0, r)));
    }
    let file = ContourFile {
        geometry,
        labels: default_labels(),
        contours: contours.clone(),
        drawn_empty: vec![DrawnEmpty {
            slice: slice(Axis::Z, 18),
            label: 2,
            author: "alice".into(),
        }],
    };
    let out = tempfile::tempdir().unwrap();
    let json_path = out.path().join("tracing.contours.json");
    std::fs::write(
        &json_path,
        interslice_core::contour_file::write(&file).unwrap(),
    )
    .unwrap();

    // The CLI, straight from the file.
    let cli = out.path().join("cli.nii.gz");
    let o = Command::new(BIN)
        .arg("interpolate")
        .arg(&json_path)
        .args(["--method", "linear", "--out"])
        .arg(&cli)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    // The server, the same contours traced through the API.
    let mut config = interslice_server::Config::new(dir.path());
    config.bind = std::net::SocketAddr::from(([127, 0, 0, 1], 0));
    let server = interslice_server::spawn(config).unwrap();
    let mut c = Client::new(&server.url());
    assert_eq!(c.login("alice", None).unwrap().status, 200);
    for ct in &contours {
        let body = json!({
            "label": ct.label, "axis": ct.slice.axis.to_string(),
            "index": ct.slice.index, "points": ct.points,
        });
        let a = c
            .json("POST", "/api/cells/cell_01/contours", &body)
            .unwrap();
        assert_eq!(a.status, 201);
    }
    let e = c
        .json(
            "POST",
            "/api/cells/cell_01/slices/z/18/empty",
            &json!({"label": 2}),
        )
        .unwrap();
    assert_eq!(e.status, 200);
    let http = c
        .get("/api/cells/cell_01/export?format=nii.gz&method=linear")
        .unwrap();
    assert_eq!(http.status, 200);
    drop(server);
    let web = out.path().join("web.nii.gz");
    std::fs::write(&web, &http.body).unwrap();

    let a = interslice_io::read_labels(&cli).unwrap();
    let b = interslice_io::read_labels(&web).unwrap();
    assert_eq!(a.geometry(), b.geometry());
    assert_eq!(a.data(), b.data(), "voxel for voxel");
    // The nucleus fills the slices between its own drawn ones (z = 12 is
    // drawn only for the cell) and is gone where it was drawn empty.
    let at = |i: usize, j: usize, k: usize| a.data()[i + 32 * (j + 32 * k)];
    assert_eq!(at(16, 16, 12), 2);
    assert_eq!(at(16, 16, 11), 2);
    assert_eq!(at(16, 16, 18), 1);
    assert!(a.data().contains(&3));
}
