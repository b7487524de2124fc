//! What a request may ask for, over real HTTP: every number and name is
//! bounded with a 400 that says the range; uploads are one file; long work
//! stops when its request is gone and a timeout is a JSON 408; JSON routes
//! want `application/json`; ratings belong to their author and reviewers;
//! a session opened by name is refused where passwords are required; a
//! loopback server answers only loopback `Host` names.
use crate::common;

use common::*;
use interslice_server::RunningServer;
use interslice_store::Role;
use interslice_test_support::client::Client;
use serde_json::json;
use std::io::{Read as _, Write as _};
use std::net::TcpStream;
use std::time::{Duration, Instant};

const PW: &str = TEAM_PASSWORD;

/// Wait until the server computes nothing (a job that is not stopped runs
/// for minutes: the bound is only there to fail instead of hanging).
fn wait_idle(server: &RunningServer) {
    let end = Instant::now() + Duration::from_secs(120);
    while server.state.jobs.running() > 0 {
        assert!(Instant::now() < end, "a job is still running");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// One raw HTTP/1.1 request (any `Host`, any headers); the status and body.
fn raw(server: &RunningServer, request: &str) -> (u16, String) {
    let mut s = TcpStream::connect(server.addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    s.write_all(request.as_bytes()).unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let body = text.split("\r\n\r\n").nth(1).unwrap_or("").to_string();
    (status, body)
}

fn get_with_host(server: &RunningServer, host: &str, cookie: Option<&str>) -> (u16, String) {
    let cookie = cookie
        .map(|c| format!("Cookie: {c}\r\n"))
        .unwrap_or_default();
    raw(
        server,
        &format!("GET /api/me HTTP/1.1\r\nHost: {host}\r\n{cookie}Connection: close\r\n\r\n"),
    )
}

#[test]
fn uploads_are_one_file_with_a_bounded_name() {
    let dir = project();
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    // A detached header names its data file anywhere on the server.
    let mhd = b"ObjectType = Image\nNDims = 3\nDimSize = 32 28 24\nElementType = MET_UCHAR\n\
ElementDataFile = /etc/hostname\n";
    let nhdr = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 32 28 24\nencoding: raw\n\
data file: /etc/hostname\n";
    for (name, body) in [
        ("x.mhd", &mhd[..]),
        ("x.NHDR", &nhdr[..]),
        ("x.raw", b"\0\0\0"),
    ] {
        let a = c
            .send(
                "POST",
                &format!("/api/cells/cell_01/segmentations/upload?name={name}"),
                Some((body, "application/octet-stream")),
            )
            .unwrap();
        expect(&a, 400);
        let e = a.error().unwrap();
        assert!(e.contains(".nii"), "{e}");
        assert!(!e.contains("/tmp") && !e.contains("/etc"), "{e}");
        assert!(!e.contains(&*dir.path().to_string_lossy()), "{e}");
    }
    let long = format!("{}.nii", "a".repeat(5000));
    let a = c
        .send(
            "POST",
            &format!("/api/cells/cell_01/segmentations/upload?name={long}"),
            Some((b"data", "application/octet-stream")),
        )
        .unwrap();
    expect(&a, 400);
    assert!(
        a.error().unwrap().contains("at most 128"),
        "{:?}",
        a.error()
    );
    assert_eq!(
        c.get("/api/cells/cell_01/segmentations").unwrap().json(),
        json!([])
    );
}

#[test]
fn numbers_and_names_are_bounded_with_the_range_in_the_message() {
    let dir = project();
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    let seg = |body: serde_json::Value| {
        c.json("POST", "/api/cells/cell_01/segmentations", &body)
            .unwrap()
    };
    // Cells of the test project have 0.35 µm voxels: σ up to 20 voxels.
    for smooth in [1_000_000.0, 7.5, -1.0] {
        let a = seg(json!({"method": "otsu", "smooth": smooth}));
        expect(&a, 400);
        let e = a.error().unwrap();
        assert!(e.contains("between 0 and 7 µm"), "{e}");
    }
    let a = seg(json!({"method": "kmeans", "classes": 1000}));
    expect(&a, 400);
    assert!(a.error().unwrap().contains("2 to 5"), "{:?}", a.error());
    let a = seg(json!({"method": "otsu", "largest_component": true, "connectivity": 7}));
    expect(&a, 400);
    assert!(a.error().unwrap().contains("6 or 26"), "{:?}", a.error());
    expect(&seg(json!({"method": "otsu", "smooth": 0.7})), 201);

    // Contours on one slice.
    let many: Vec<serde_json::Value> = (0..1001)
        .map(|i| {
            let x = (i % 30) as f64;
            json!({"points": [[x, 1.0], [x + 0.5, 1.0], [x + 0.5, 1.5]]})
        })
        .collect();
    let a = c
        .json(
            "PUT",
            "/api/cells/cell_01/slices/z/3/contours",
            &json!({"label": 1, "contours": many}),
        )
        .unwrap();
    expect(&a, 400);
    assert!(
        a.error().unwrap().contains("at most 1000"),
        "{:?}",
        a.error()
    );
    // Segmentation ids.
    let a = c
        .json(
            "POST",
            "/api/cells/cell_01/ratings",
            &json!({"segmentation": "9".repeat(300), "score": 3}),
        )
        .unwrap();
    expect(&a, 400);
    assert!(
        a.error().unwrap().contains("at most 256"),
        "{:?}",
        a.error()
    );
    assert_eq!(
        c.get("/api/cells/cell_01/contours").unwrap().json(),
        json!([])
    );

    // Passwords (hashing reads all of one).
    drop(server);
    let mut cfg = config(dir.path());
    cfg.require_login = true;
    let server = serve(cfg);
    server
        .state
        .store
        .upsert_user("alice", Role::Tracer, Some(PW))
        .unwrap();
    let mut c = Client::new(&server.url());
    let a = c.login("alice", Some(&"x".repeat(5000))).unwrap();
    expect(&a, 400);
    assert!(
        a.error().unwrap().contains("at most 1024"),
        "{:?}",
        a.error()
    );
}

/// A 160³ cell smoothed with σ = 20 voxels: seconds of work in a test build.
fn slow_project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    interslice_test_support::loadtest::write_cells(dir.path(), 1, [160, 160, 160], false).unwrap();
    dir
}

const SLOW: &str = r#"{"method": "otsu", "smooth": 7}"#;

#[test]
fn a_timed_out_request_is_a_json_408_and_its_work_stops() {
    let dir = slow_project();
    let mut cfg = config(dir.path());
    // An optimised build smooths the cell in well under a second.
    cfg.timeout = if cfg!(debug_assertions) {
        Duration::from_secs(1)
    } else {
        Duration::from_millis(100)
    };
    let server = serve(cfg);
    let c = signed_in(&server, "alice");
    // Load the cell first, so that the timeout falls in the smoothing.
    expect(&c.get("/api/cells/cell_01/histogram").unwrap(), 200);
    let a = c
        .send(
            "POST",
            "/api/cells/cell_01/segmentations",
            Some((SLOW.as_bytes(), "application/json")),
        )
        .unwrap();
    expect(&a, 408);
    assert!(a.error().unwrap().contains("stopped"), "{:?}", a.error());
    wait_idle(&server);
    assert_eq!(server.state.jobs.cancelled(), 1);
    // Nothing was stored after the answer.
    assert!(
        server
            .state
            .store
            .segmentations("cell_01")
            .unwrap()
            .is_empty()
    );
}

#[test]
fn a_request_whose_client_leaves_stops_computing() {
    let dir = slow_project();
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    expect(&c.get("/api/cells/cell_01/histogram").unwrap(), 200);
    let mut s = TcpStream::connect(server.addr).unwrap();
    write!(
        s,
        "POST /api/cells/cell_01/segmentations HTTP/1.1\r\nHost: 127.0.0.1\r\nCookie: {}\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{SLOW}",
        c.cookie().unwrap(),
        SLOW.len()
    )
    .unwrap();
    // Leave once the work has started.
    let end = Instant::now() + Duration::from_secs(60);
    while server.state.jobs.running() == 0 {
        assert!(Instant::now() < end, "the job never started");
        std::thread::sleep(Duration::from_millis(10));
    }
    drop(s);
    wait_idle(&server);
    assert_eq!(server.state.jobs.cancelled(), 1);
    assert!(
        server
            .state
            .store
            .segmentations("cell_01")
            .unwrap()
            .is_empty()
    );
}

#[test]
fn json_routes_want_application_json() {
    let dir = project();
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    let body = serde_json::to_vec(
        &json!({"label": 1, "axis": "z", "index": 3, "points": [[1.0, 1.0], [5.0, 1.0], [5.0, 5.0]]}),
    )
    .unwrap();
    for ct in [
        "text/plain",
        "application/x-www-form-urlencoded",
        "multipart/form-data",
    ] {
        let a = c
            .send("POST", "/api/cells/cell_01/contours", Some((&body, ct)))
            .unwrap();
        expect(&a, 415);
        let a = Client::new(&server.url())
            .send("POST", "/api/login", Some((br#"{"name": "mallory"}"#, ct)))
            .unwrap();
        expect(&a, 415);
    }
    assert_eq!(
        c.get("/api/cells/cell_01/contours").unwrap().json(),
        json!([])
    );
    let a = c
        .send(
            "POST",
            "/api/cells/cell_01/contours",
            Some((&body, "application/json; charset=utf-8")),
        )
        .unwrap();
    expect(&a, 201);
}

#[test]
fn ratings_belong_to_their_author_and_the_reviewers() {
    let dir = project();
    let (_server, [alice, bob, rita]) = team(dir.path());
    let s = alice
        .json(
            "POST",
            "/api/cells/cell_01/segmentations",
            &json!({"method": "otsu"}),
        )
        .unwrap();
    expect(&s, 201);
    let id = s.json()["id"].as_str().unwrap().to_string();
    let rate = |c: &Client, comment: &str| {
        expect(
            &c.json(
                "POST",
                "/api/cells/cell_01/ratings",
                &json!({"segmentation": id, "score": 2, "comment": comment}),
            )
            .unwrap(),
            201,
        )
    };
    rate(&alice, "misses the nucleus");
    rate(&bob, "fine");
    let seen = |c: &Client| -> Vec<(String, String)> {
        let a = c.get("/api/cells/cell_01/ratings").unwrap();
        expect(&a, 200);
        a.json()
            .as_array()
            .unwrap()
            .iter()
            .map(|r| {
                (
                    r["user"].as_str().unwrap().to_string(),
                    r["comment"].as_str().unwrap().to_string(),
                )
            })
            .collect()
    };
    assert_eq!(seen(&bob), [("bob".into(), "fine".into())]);
    assert_eq!(
        seen(&alice),
        [("alice".into(), "misses the nucleus".into())]
    );
    assert_eq!(seen(&rita).len(), 2);
}

#[test]
fn a_session_opened_by_name_is_refused_where_passwords_are_required() {
    let dir = project();
    // On loopback anyone signs in as "alice" by name.
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    let cookie = c.cookie().unwrap().to_string();
    drop(server);
    // Alice gets a password; the project is served to the network.
    let mut cfg = config(dir.path());
    cfg.require_login = true;
    let server = serve(cfg);
    server
        .state
        .store
        .upsert_user("alice", Role::Tracer, Some(PW))
        .unwrap();
    let mut old = Client::new(&server.url());
    old.set_cookie(Some(cookie));
    for path in ["/api/me", "/api/cells/cell_01/contours"] {
        let a = old.get(path).unwrap();
        expect(&a, 401);
        assert!(a.error().unwrap().contains("password"), "{:?}", a.error());
    }
    // Her password opens a session that works there.
    let mut fresh = Client::new(&server.url());
    expect(&fresh.login("alice", Some(PW)).unwrap(), 200);
    expect(&fresh.get("/api/me").unwrap(), 200);
}

#[test]
fn a_loopback_server_answers_only_loopback_host_names() {
    let dir = project();
    let mut cfg = config(dir.path());
    cfg.public_urls = vec!["https://tracing.example.org/".into()];
    let server = serve(cfg);
    let c = signed_in(&server, "alice");
    let cookie = c.cookie();
    // A DNS-rebinding page: its own name, our address.
    for host in [
        "attacker.example",
        "attacker.example:8080",
        "localhost.attacker.example",
    ] {
        let (status, body) = get_with_host(&server, host, cookie);
        assert_eq!(status, 403, "{host}: {body}");
        let e: serde_json::Value = serde_json::from_str(&body).unwrap();
        assert!(
            e["error"].as_str().unwrap().contains("--public-url"),
            "{body}"
        );
        let login = r#"{"name": "alice"}"#;
        let (status, _) = raw(
            &server,
            &format!(
                "POST /api/login HTTP/1.1\r\nHost: {host}\r\nContent-Type: application/json\r\n\
                 Content-Length: {}\r\nConnection: close\r\n\r\n{login}",
                login.len()
            ),
        );
        assert_eq!(status, 403, "{host}");
    }
    let port = server.addr.port();
    for host in [
        format!("127.0.0.1:{port}"),
        format!("localhost:{port}"),
        "tracing.example.org".to_string(),
    ] {
        let (status, body) = get_with_host(&server, &host, cookie);
        assert_eq!(status, 200, "{host}: {body}");
    }
}
