//! `interslice phantom` as a user runs it: the files it writes, their geometry
//! and labels, byte-for-byte reproducibility on any thread count, and errors.
use interslice_core::{AnyVolume, LengthUnit};
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::path::Path;
use std::process::Command;

fn phantom(out: &Path, args: &[&str], threads: Option<usize>) -> std::process::Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_interslice"));
    c.arg("phantom").arg("--out").arg(out).args(args);
    if let Some(t) = threads {
        c.env("RAYON_NUM_THREADS", t.to_string());
    }
    c.output().expect("run interslice")
}

fn digest(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap();
    Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[test]
fn writes_images_labels_and_a_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let out = phantom(
        dir.path(),
        &[
            "--count", "2", "--size", "48", "--seed", "5", "--bits", "16",
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for n in 1..=2 {
        let img =
            interslice_io::read_volume(&dir.path().join(format!("cell_{n:03}.nii.gz"))).unwrap();
        let lab =
            interslice_io::read_labels(&dir.path().join(format!("cell_{n:03}_labels.nii.gz")))
                .unwrap();
        assert!(matches!(img, AnyVolume::U16(_)));
        let g = img.geometry();
        assert_eq!(g.dims, [48; 3]);
        assert!(g.spacing.iter().all(|s| (s - 0.35).abs() < 1e-6));
        assert_eq!(g.unit, LengthUnit::Micrometre);
        assert!(g.same_grid(lab.geometry()));
        let max = *lab.data().iter().max().unwrap();
        assert!(
            (3..=5).contains(&max),
            "labels 1, 2 and 1-3 nucleoli: max {max}"
        );
        for l in 1..=max {
            assert!(lab.data().contains(&l), "label {l} missing");
        }
    }
    let manifest: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("phantom.json")).unwrap())
            .unwrap();
    assert_eq!(manifest["cells"].as_array().unwrap().len(), 2);
    assert_eq!(manifest["cells"][0]["structures"][1]["name"], "Nucleus");
    // Different cells of one series differ.
    assert_ne!(
        digest(&dir.path().join("cell_001_labels.nii.gz")),
        digest(&dir.path().join("cell_002_labels.nii.gz"))
    );
}

#[test]
fn same_seed_same_bytes_on_one_or_two_threads() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let args = ["--count", "1", "--size", "40", "--seed", "9"];
    assert!(phantom(a.path(), &args, Some(1)).status.success());
    assert!(phantom(b.path(), &args, Some(2)).status.success());
    for f in ["cell_001.nii.gz", "cell_001_labels.nii.gz", "phantom.json"] {
        assert_eq!(digest(&a.path().join(f)), digest(&b.path().join(f)), "{f}");
    }
}

#[test]
fn bad_parameters_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        &["--bits", "12"][..],
        &["--size", "8"],
        &["--noise", "2"],
        &["--count", "0"],
    ] {
        let out = phantom(&dir.path().join("x"), args, None);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.starts_with("error: ") && err.trim_end().lines().count() == 1,
            "{args:?}: {err}"
        );
        assert!(
            !dir.path().join("x").exists(),
            "nothing written on bad input"
        );
    }
}
