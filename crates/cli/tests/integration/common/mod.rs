//! What the CLI test crates share: the binary, the reference folder, and the
//! checks of a successful JSON answer and of a one-line error.
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `interslice` binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_interslice"))
}

/// `tests/fixtures/refs` at the repository root: the reference cases and
/// values computed by established libraries (see its `PROVENANCE.md`).
pub fn refs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/refs")
}

/// Standard output of a successful run, parsed as JSON.
pub fn stdout_json(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

/// A failed run: exit 1, no panic, one line on stderr starting `error:` and
/// containing `needle`.
pub fn assert_one_line_error(out: &Output, needle: &str) {
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "stderr: {err}");
    assert!(err.starts_with("error: "), "stderr: {err}");
    assert!(err.contains(needle), "stderr lacks {needle:?}: {err}");
    assert!(!err.contains("panicked"), "stderr: {err}");
}
