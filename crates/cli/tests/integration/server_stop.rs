//! `interslice serve` stops on SIGTERM within seconds even while a request
//! computes: the signal cancels the running work instead of waiting for it.
#![cfg(unix)]
use interslice_test_support::client::Client;
use std::io::{BufRead, BufReader, Write as _};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_interslice");

#[test]
fn sigterm_stops_the_server_while_a_request_computes() {
    let dir = tempfile::tempdir().unwrap();
    // 256³ smoothed with σ = 20 voxels: many seconds of work in a test build
    // (192³ finished within 2 s on a fast run of the machine).
    interslice_test_support::loadtest::write_cells(dir.path(), 1, [256, 256, 256], false).unwrap();
    let mut child = Command::new(BIN)
        .arg("serve")
        .arg(dir.path())
        .args(["--bind", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run interslice serve");
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let url = loop {
        let line = lines.next().expect("serve prints its URL").unwrap();
        if let Some(rest) = line.split("serving on ").nth(1) {
            break rest
                .split_whitespace()
                .next()
                .unwrap()
                .trim_end_matches('/')
                .to_string();
        }
    };
    let mut c = Client::new(&url);
    assert_eq!(c.login("alice", None).unwrap().status, 200);
    assert_eq!(c.get("/api/cells/cell_01/histogram").unwrap().status, 200);

    let body = r#"{"method": "otsu", "smooth": 7}"#;
    let mut s = TcpStream::connect(url.trim_start_matches("http://")).unwrap();
    write!(
        s,
        "POST /api/cells/cell_01/segmentations HTTP/1.1\r\nHost: 127.0.0.1\r\nCookie: {}\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        c.cookie().unwrap(),
        body.len()
    )
    .unwrap();
    // Let the smoothing start (the cell is loaded: the work begins at once).
    std::thread::sleep(Duration::from_millis(500));
    let sent = Instant::now();
    let kill = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let status = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break Some(st);
        }
        if sent.elapsed() > Duration::from_secs(15) {
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let Some(status) = status else {
        let _ = child.kill();
        let _ = child.wait();
        panic!("the server did not stop within 15 s of SIGTERM");
    };
    assert!(status.success(), "{status:?}");
    eprintln!(
        "stopped {:.2} s after SIGTERM",
        sent.elapsed().as_secs_f64()
    );
    // The computation was stopped, not finished: its request got the 503.
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut answer = String::new();
    let _ = std::io::Read::read_to_string(&mut s, &mut answer);
    assert!(answer.starts_with("HTTP/1.1 503"), "{answer}");
}
