//! `interslice interpolate` through the binary: its contract (docs/interpolation.md)
//! (drawn slices, `--drawn`, `--list`, output geometry and format) and one-line
//! errors with a non-zero exit on bad input.
use interslice_core::{Axis, Geometry, LabelVolume, LengthUnit, Volume};
use std::path::Path;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_interslice"))
}

/// A cell (label 1) with a nucleus (label 2) on an anisotropic grid with an
/// origin, fully traced.
fn full() -> LabelVolume {
    let mut g = Geometry::new([32, 28, 24], [0.35, 0.35, 0.7], LengthUnit::Micrometre).unwrap();
    g.origin = [1.0, -2.0, 3.5];
    let mut v: LabelVolume = Volume::zeros(g);
    for k in 0..24 {
        for j in 0..28 {
            for i in 0..32 {
                let (x, y, z) = (i as f64 - 15.5, j as f64 - 13.5, (k as f64 - 11.5) * 2.0);
                let r = (x * x / 169.0 + y * y / 121.0 + z * z / 400.0).sqrt();
                let l = if r < 0.45 {
                    2
                } else if r < 1.0 {
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

/// `full` with only `drawn` slices along `axis` kept.
fn sparse(full: &LabelVolume, axis: Axis, drawn: &[usize]) -> LabelVolume {
    let mut s: LabelVolume = Volume::zeros(full.geometry().clone());
    for &d in drawn {
        s.set_slice(axis, d, &full.slice(axis, d).unwrap()).unwrap();
    }
    s
}

fn ok(out: Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A failed run: non-zero exit and exactly one line on stderr, returned.
fn fails(out: Output) -> String {
    assert!(!out.status.success(), "expected a failure");
    let err = String::from_utf8_lossy(&out.stderr).trim().to_string();
    assert_eq!(err.lines().count(), 1, "one-line error expected: {err}");
    err
}

fn write(path: &Path, v: &LabelVolume) {
    interslice_io::write_labels(path, v).unwrap();
}

fn dice(a: &LabelVolume, b: &LabelVolume, l: u16) -> f64 {
    let (mut tp, mut n) = (0usize, 0usize);
    for (&x, &y) in a.data().iter().zip(b.data()) {
        tp += (x == l && y == l) as usize;
        n += (x == l) as usize + (y == l) as usize;
    }
    2.0 * tp as f64 / n as f64
}

#[test]
fn list_names_every_method_and_marks_the_default() {
    let s = ok(bin().args(["interpolate", "--list"]).output().unwrap());
    for m in interslice_interp::methods() {
        assert!(s.contains(m.name()), "{s}");
    }
    let first = s.lines().next().unwrap();
    assert!(
        first.starts_with(interslice_interp::DEFAULT_METHOD) && first.contains("(default)"),
        "{s}"
    );
}

#[test]
fn interpolates_every_label_keeps_geometry_and_drawn_slices() {
    let dir = tempfile::tempdir().unwrap();
    let gt = full();
    let drawn: Vec<usize> = vec![1, 5, 9, 13, 17, 22];
    let src = dir.path().join("sparse.nii.gz");
    write(&src, &sparse(&gt, Axis::Z, &drawn));
    for (method, ext) in [
        (None, "nrrd"),
        (Some("shape-based"), "nii"),
        (Some("linear"), "mha"),
    ] {
        let out = dir.path().join(format!("out.{ext}"));
        let mut cmd = bin();
        cmd.arg("interpolate").arg(&src).arg("--out").arg(&out);
        if let Some(m) = method {
            cmd.args(["--method", m]);
        }
        ok(cmd.output().unwrap());
        let got = interslice_io::read_labels(&out).unwrap();
        assert_eq!(got.geometry(), gt.geometry());
        for &d in &drawn {
            assert_eq!(
                got.slice(Axis::Z, d).unwrap(),
                gt.slice(Axis::Z, d).unwrap(),
                "{method:?} z={d}"
            );
        }
        for l in [1, 2] {
            let d = dice(&got, &gt, l);
            let floor = if method == Some("linear") { 0.75 } else { 0.85 };
            assert!(d > floor, "{method:?} label {l}: Dice {d}");
        }
    }
}

#[test]
fn along_y_and_with_a_drawn_file_declaring_empty_slices() {
    let dir = tempfile::tempdir().unwrap();
    let gt = full();
    // Along y: slices 0 and 27 are empty and declared drawn, so nothing may
    // appear on them; the default method would otherwise cap past 3 and 24.
    let drawn = [0usize, 3, 8, 13, 18, 24, 27];
    let src = dir.path().join("sparse.nrrd");
    write(&src, &sparse(&gt, Axis::Y, &drawn));
    let list = dir.path().join("drawn.txt");
    std::fs::write(&list, "# drawn slices\n0\n3\n8\n13\n18\n24\n27\n").unwrap();
    let out = dir.path().join("out.nrrd");
    ok(bin()
        .arg("interpolate")
        .arg(&src)
        .arg("--out")
        .arg(&out)
        .args(["--axis", "y", "--drawn"])
        .arg(&list)
        .output()
        .unwrap());
    let got = interslice_io::read_labels(&out).unwrap();
    for &d in &drawn {
        assert_eq!(
            got.slice(Axis::Y, d).unwrap(),
            gt.slice(Axis::Y, d).unwrap(),
            "y={d}"
        );
    }
    assert!(dice(&got, &gt, 1) > 0.85);
}

#[test]
fn fewer_than_two_drawn_slices_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let gt = full();
    let src = dir.path().join("one.nii.gz");
    write(&src, &sparse(&gt, Axis::Z, &[10]));
    let out = dir.path().join("out.nii.gz");
    let e = fails(
        bin()
            .arg("interpolate")
            .arg(&src)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap(),
    );
    assert!(e.contains("at least two drawn slices"), "{e}");
    assert!(!out.exists());
    let empty = dir.path().join("empty.nii.gz");
    write(&empty, &Volume::zeros(gt.geometry().clone()));
    let e = fails(
        bin()
            .arg("interpolate")
            .arg(&empty)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap(),
    );
    assert!(e.contains("found 0"), "{e}");
}

#[test]
fn bad_drawn_files_are_errors_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let gt = full();
    let src = dir.path().join("sparse.nii.gz");
    write(&src, &sparse(&gt, Axis::Z, &[2, 12, 21]));
    let out = dir.path().join("out.nii.gz");
    for (text, want) in [
        ("2\n12\n24\n", "line 3"),
        ("2\ntwelve\n21\n", "'twelve'"),
        ("2\n-1\n", "line 2"),
        ("2\n1.5\n", "line 2"),
    ] {
        let list = dir.path().join("drawn.txt");
        std::fs::write(&list, text).unwrap();
        let e = fails(
            bin()
                .arg("interpolate")
                .arg(&src)
                .arg("--out")
                .arg(&out)
                .arg("--drawn")
                .arg(&list)
                .output()
                .unwrap(),
        );
        assert!(e.contains(want), "{text:?}: {e}");
    }
    let e = fails(
        bin()
            .arg("interpolate")
            .arg(&src)
            .arg("--out")
            .arg(&out)
            .arg("--drawn")
            .arg(dir.path().join("missing.txt"))
            .output()
            .unwrap(),
    );
    assert!(e.contains("missing.txt"), "{e}");
}

#[test]
fn unknown_method_and_missing_input_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let gt = full();
    let src = dir.path().join("sparse.nii.gz");
    write(&src, &sparse(&gt, Axis::Z, &[2, 12, 21]));
    let out = dir.path().join("out.nii.gz");
    let e = fails(
        bin()
            .arg("interpolate")
            .arg(&src)
            .arg("--out")
            .arg(&out)
            .args(["--method", "magic"])
            .output()
            .unwrap(),
    );
    assert!(
        e.contains("unknown method 'magic'") && e.contains("shape-based"),
        "{e}"
    );
    let e = fails(
        bin()
            .arg("interpolate")
            .arg(dir.path().join("nope.nii.gz"))
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap(),
    );
    assert!(e.contains("nope.nii.gz"), "{e}");
    assert!(!out.exists());
}

/// An intensity image read as labels has a label per grey value: more than
/// `--max-labels` (255) is a one-line error that says so, before any work;
/// `--max-labels` raises the bound.
#[test]
fn an_intensity_image_is_refused_unless_max_labels_allows_it() {
    let dir = tempfile::tempdir().unwrap();
    let g = Geometry::new([20, 20, 4], [1.0; 3], LengthUnit::Micrometre).unwrap();
    let mut v: LabelVolume = Volume::zeros(g);
    for k in [0, 3] {
        for j in 0..20 {
            for i in 0..20 {
                v.set(i, j, k, 1 + (i + 20 * j) as u16);
            }
        }
    }
    let (input, out) = (dir.path().join("grey.nrrd"), dir.path().join("out.nrrd"));
    write(&input, &v);
    let run = |extra: &[&str]| {
        let mut c = bin();
        c.arg("interpolate")
            .arg(&input)
            .arg("--out")
            .arg(&out)
            .args(["--method", "linear"])
            .args(extra);
        c.output().unwrap()
    };
    let err = fails(run(&[]));
    assert!(
        err.contains("400 labels") && err.contains("--max-labels"),
        "{err}"
    );
    assert!(!out.exists());
    ok(run(&["--max-labels", "400"]));
    assert!(out.exists());
}
