//! `interslice contours extract|rasterize` through the binary: a label volume
//! traced into contours and painted back is the same volume, and a sparse
//! extraction lists exactly the slices it traced.
use interslice_core::{Geometry, LabelVolume, LengthUnit, Volume};
use std::path::Path;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_interslice"))
}

/// A nucleus-like blob (label 2) inside a cell (label 1), with a nucleolus
/// (label 3) that has a hole on some slices: hole-free labels must round-trip
/// exactly.
fn labels() -> LabelVolume {
    let mut g = Geometry::new([30, 26, 12], [0.35, 0.35, 0.5], LengthUnit::Micrometre).unwrap();
    g.origin = [1.0, -2.0, 3.5];
    let mut v: LabelVolume = Volume::zeros(g);
    for k in 1..11 {
        for j in 0..26 {
            for i in 0..30 {
                let (x, y) = (i as f64 - 14.5, j as f64 - 12.5);
                let r2 = x * x / 144.0 + y * y / 100.0;
                let l = if r2 < 0.25 {
                    2
                } else if r2 < 1.0 && !(k == 5 && i == 3) {
                    1
                } else {
                    0
                };
                v.set(i, j, k, l);
            }
        }
    }
    v
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().expect("run interslice");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn read(path: &Path) -> LabelVolume {
    interslice_io::read_labels(path).expect("read labels")
}

#[test]
fn extract_then_rasterize_gives_the_volume_back() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("labels.nii.gz");
    let v = labels();
    interslice_io::write_labels(&src, &v).unwrap();
    let json = dir.path().join("contours.json");
    run(bin()
        .args(["contours", "extract"])
        .arg(&src)
        .arg("--out")
        .arg(&json));
    let back = dir.path().join("back.nrrd");
    let drawn = dir.path().join("drawn.txt");
    run(bin()
        .args(["contours", "rasterize"])
        .arg(&json)
        .arg("--out")
        .arg(&back)
        .arg("--drawn-out")
        .arg(&drawn));
    let b = read(&back);
    assert_eq!(b.geometry().dims, v.geometry().dims);
    assert_eq!(b.geometry().spacing, v.geometry().spacing);
    assert_eq!(b.geometry().origin, v.geometry().origin);
    assert_eq!(b.data(), v.data());
    let listed = std::fs::read_to_string(&drawn).unwrap();
    let want: String = (1..11).map(|k| format!("{k}\n")).collect();
    assert_eq!(listed, want);
}

#[test]
fn sparse_extraction_keeps_first_last_and_every_nth_slice() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("labels.mha");
    let v = labels();
    interslice_io::write_labels(&src, &v).unwrap();
    let json = dir.path().join("contours.json");
    run(bin()
        .args(["contours", "extract", "--every", "4"])
        .arg(&src)
        .arg("--out")
        .arg(&json));
    let back = dir.path().join("back.nii");
    let drawn = dir.path().join("drawn.txt");
    run(bin()
        .args(["contours", "rasterize"])
        .arg(&json)
        .arg("--out")
        .arg(&back)
        .arg("--drawn-out")
        .arg(&drawn));
    assert_eq!(std::fs::read_to_string(&drawn).unwrap(), "1\n5\n9\n10\n");
    let b = read(&back);
    for k in 0..12 {
        let want = if [1, 5, 9, 10].contains(&k) {
            v.slice(interslice_core::Axis::Z, k).unwrap()
        } else {
            vec![0; 30 * 26]
        };
        assert_eq!(
            b.slice(interslice_core::Axis::Z, k).unwrap(),
            want,
            "slice {k}"
        );
    }
}

#[test]
fn bad_contours_files_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.nii.gz");
    let bad = dir.path().join("bad.json");
    for (text, want) in [
        ("{\"format\": ", "malformed JSON"),
        (
            "{\"format\": \"interslice-contours\", \"version\": 9}",
            "unsupported version 9",
        ),
    ] {
        std::fs::write(&bad, text).unwrap();
        let o = bin()
            .args(["contours", "rasterize"])
            .arg(&bad)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(err.contains(want), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!out.exists(), "no output on error");
    }
    let o = bin()
        .args(["contours", "rasterize", "/no/such/file.json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot read"));
}
