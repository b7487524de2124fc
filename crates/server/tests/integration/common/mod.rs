//! A project folder with small synthetic cells and a server on loopback.

use interslice_server::{Config, RunningServer};
use interslice_test_support::client::{Answer, Client};
use std::net::SocketAddr;
use std::path::Path;

/// Cells of the test projects: 32 × 28 × 24, 8-bit.
pub const DIMS: [usize; 3] = [32, 28, 24];

/// A temporary project with two cells.
pub fn project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    interslice_test_support::loadtest::write_cells(dir.path(), 2, DIMS, false).expect("cells");
    dir
}

/// A loopback configuration of `dir` on a free port.
pub fn config(dir: &Path) -> Config {
    let mut c = Config::new(dir);
    c.bind = SocketAddr::from(([127, 0, 0, 1], 0));
    c
}

/// Start a server.
pub fn serve(config: Config) -> RunningServer {
    interslice_server::spawn(config).expect("server starts")
}

/// A client of `server`, signed in as `name` (loopback: no password).
pub fn signed_in(server: &RunningServer, name: &str) -> Client {
    let mut c = Client::new(&server.url());
    let a = c.login(name, None).expect("login");
    assert_eq!(a.status, 200, "{:?}", a.error());
    c
}

/// A polygon approximating a circle, corners rounded to 1/8 pixel (exact in JSON).
pub fn circle(cx: f64, cy: f64, r: f64, n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|k| {
            let t = k as f64 / n as f64 * std::f64::consts::TAU;
            let q = |x: f64| (x * 8.0).round() / 8.0;
            [q(cx + r * t.cos()), q(cy + r * t.sin())]
        })
        .collect()
}

/// Assert a status and that a non-2xx answer is a one-line JSON error.
pub fn expect(a: &Answer, status: u16) {
    assert_eq!(
        a.status,
        status,
        "body: {}",
        String::from_utf8_lossy(&a.body)
    );
    if status >= 400 {
        let e = a.error().expect("a JSON error body");
        assert!(!e.is_empty() && !e.contains('\n'), "{e:?}");
    }
}

/// A downloaded label volume file, read back.
pub fn read_export(bytes: &[u8], name: &str) -> interslice_core::LabelVolume {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    interslice_io::read_labels(&p).unwrap()
}

/// The password of the accounts of [`team`].
pub const TEAM_PASSWORD: &str = "correct horse battery";

/// A server that requires passwords, with tracers alice and bob and reviewer
/// rita, and a client signed in as each (alice, bob, rita).
pub fn team(dir: &Path) -> (RunningServer, [Client; 3]) {
    use interslice_store::Role;
    let mut cfg = config(dir);
    cfg.require_login = true;
    let server = serve(cfg);
    let names = [
        ("alice", Role::Tracer),
        ("bob", Role::Tracer),
        ("rita", Role::Reviewer),
    ];
    for (name, role) in names {
        server
            .state
            .store
            .upsert_user(name, role, Some(TEAM_PASSWORD))
            .unwrap();
    }
    let clients = names.map(|(name, _)| {
        let mut c = Client::new(&server.url());
        expect(&c.login(name, Some(TEAM_PASSWORD)).unwrap(), 200);
        c
    });
    (server, clients)
}
