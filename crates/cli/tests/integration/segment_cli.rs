//! `interslice segment` and `interslice staple` as a user runs them: the
//! thresholds and class sizes of the reference volumes, the clean-up options
//! (largest component with 6 or 26 neighbours, hole filling), STAPLE's
//! estimates on synthetic raters, and one-line errors on bad input.
use crate::common;
use common::{assert_one_line_error, bin, refs, stdout_json};
use interslice_core::{AnyVolume, Geometry, LabelVolume, LengthUnit, Volume};
use rand::{Rng, SeedableRng};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn reference(volume: &str, key: &str) -> Value {
    let text = std::fs::read_to_string(refs().join("thresholds_expected.json")).unwrap();
    let json: Value = serde_json::from_str(&text).unwrap();
    json["volumes"][volume]["methods"][key].clone()
}

fn segment(input: &Path, out: &Path, args: &[&str]) -> Value {
    let o = bin()
        .arg("segment")
        .arg(input)
        .arg("--out")
        .arg(out)
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    stdout_json(&o)
}

fn voxels(v: &Value) -> Vec<u64> {
    v["labels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["voxels"].as_u64().unwrap())
        .collect()
}

#[test]
fn reference_volumes_every_method() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("seg.nii.gz");
    let gaps = refs().join("cases/thresholds/u8_exact_gaps.nii.gz");
    // {10: 20000, 11: 10000, 12: 5000, 100: 3000, 101: 2000, 200: 1000}
    let v = segment(&gaps, &out, &["--method", "otsu"]);
    assert_eq!(v["thresholds"], serde_json::json!([12.0]));
    assert_eq!(voxels(&v), vec![6000]);
    let v = segment(&gaps, &out, &["--method", "rosin"]);
    assert_eq!(v["thresholds"], serde_json::json!([13.0]));
    assert_eq!(voxels(&v), vec![6000]);
    let v = segment(&gaps, &out, &["--method", "kmeans"]);
    let t = v["thresholds"][0].as_f64().unwrap();
    assert!((t - 63.785714285714285).abs() < 1e-9, "{t}");
    let v = segment(&gaps, &out, &["--method", "multi-otsu"]);
    assert_eq!(v["thresholds"], serde_json::json!([12.0, 101.0]));
    assert_eq!(voxels(&v), vec![5000, 1000]);
    let v = segment(&gaps, &out, &["--method", "kmeans", "--classes", "3"]);
    assert_eq!(voxels(&v), vec![5000, 1000]);
    // The written labels are what the JSON says.
    let labels = interslice_io::read_labels(&out).unwrap();
    assert_eq!(labels.label_counts(), vec![(1, 5000), (2, 1000)]);

    // 16-bit: native bins, one per grey level (not 256 bins).
    let u16v = refs().join("cases/thresholds/u16_12bit_bimodal.nii.gz");
    let want = reference("u16_12bit_bimodal", "otsu_float64_exact_native");
    let v = segment(&u16v, &out, &["--method", "otsu"]);
    assert_eq!(v["thresholds"][0], want["threshold"]);
    assert_eq!(v["binning"], "native");
    assert_eq!(
        voxels(&v)[0],
        want["counts"]["n_gt"].as_u64().unwrap(),
        "foreground is v > t"
    );
    let want = reference("u16_12bit_bimodal", "rosin_first_empty_after_last_native");
    let v = segment(&u16v, &out, &["--method", "rosin"]);
    assert_eq!(v["thresholds"][0], want["threshold"]);
    assert_eq!(voxels(&v)[0], want["counts"]["n_gt"].as_u64().unwrap());
}

/// A bright hollow ball with a stray bright voxel in a corner and a small
/// bright cube touching the ball's bounding corner only diagonally.
fn hollow_ball(dir: &Path) -> (PathBuf, u64, u64) {
    let n = 24;
    let g = Geometry::new([n, n, n], [0.5; 3], LengthUnit::Micrometre).unwrap();
    let mut v = Volume::<u8>::zeros(g);
    let (mut shell, mut cavity) = (0u64, 0u64);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let d = [i, j, k]
                    .iter()
                    .map(|&c| (c as f64 - 11.5).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let x = if d < 4.0 {
                    cavity += 1;
                    30
                } else if d < 8.0 {
                    shell += 1;
                    200
                } else {
                    20
                };
                v.set(i, j, k, x);
            }
        }
    }
    v.set(0, 0, 0, 210);
    let path = dir.join("ball.nii.gz");
    interslice_io::write_volume(&path, &AnyVolume::U8(v)).unwrap();
    (path, shell, cavity)
}

#[test]
fn largest_component_connectivity_and_hole_filling() {
    let tmp = tempfile::tempdir().unwrap();
    let (ball, shell, cavity) = hollow_ball(tmp.path());
    let out = tmp.path().join("seg.nii");
    let plain = segment(&ball, &out, &["--method", "otsu"]);
    assert_eq!(voxels(&plain), vec![shell + 1]);
    let clean = segment(
        &ball,
        &out,
        &["--method", "otsu", "--largest-component", "--fill-holes"],
    );
    assert_eq!(voxels(&clean), vec![shell + cavity]);
    let l = interslice_io::read_labels(&out).unwrap();
    assert_eq!(l.get(0, 0, 0), 0);
    assert_eq!(l.get(12, 12, 12), 1);

    // Two cubes touching at one corner: one component with 26 neighbours.
    let g = Geometry::new([8, 8, 8], [1.0; 3], LengthUnit::Micrometre).unwrap();
    let mut v = Volume::<u8>::filled(g, 10);
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                v.set(i, j, k, 100); // 27 voxels
                if i < 2 && j < 2 && k < 2 {
                    v.set(3 + i, 3 + j, 3 + k, 100); // 8 voxels, corner-adjacent
                }
            }
        }
    }
    let cubes = tmp.path().join("cubes.nii.gz");
    interslice_io::write_volume(&cubes, &AnyVolume::U8(v)).unwrap();
    let six = segment(&cubes, &out, &["--method", "otsu", "--largest-component"]);
    assert_eq!(voxels(&six), vec![27]);
    let full = segment(
        &cubes,
        &out,
        &[
            "--method",
            "otsu",
            "--largest-component",
            "--connectivity",
            "26",
        ],
    );
    assert_eq!(voxels(&full), vec![35]);
}

#[test]
fn bad_input_is_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("seg.nii.gz");
    let run = |args: &[&str]| bin().arg("segment").args(args).output().unwrap();
    let gaps = refs().join("cases/thresholds/u8_exact_gaps.nii.gz");
    let gaps = gaps.to_str().unwrap();
    let o = run(&[
        gaps,
        "--method",
        "otsu",
        "--classes",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_one_line_error(&o, "use kmeans or multi-otsu");
    let constant = refs().join("cases/thresholds/u8_constant.nii.gz");
    let o = run(&[
        constant.to_str().unwrap(),
        "--method",
        "multi-otsu",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_one_line_error(&o, "only 1 distinct value");
    let o = run(&[
        "/nonexistent.nii.gz",
        "--method",
        "otsu",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_one_line_error(&o, "nonexistent");
    let o = run(&[
        gaps,
        "--method",
        "otsu",
        "--smooth",
        "-1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_one_line_error(&o, "sigma");
    // An unknown method is a usage error (exit 2) naming the choices.
    let o = run(&[
        gaps,
        "--method",
        "watershed",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("otsu, rosin, kmeans or multi-otsu"));
    assert!(!out.exists(), "nothing is written on error");
}

/// Three raters of an ellipsoid with known sensitivity and specificity.
#[test]
fn staple_recovers_raters() {
    let tmp = tempfile::tempdir().unwrap();
    let n = 40;
    let g = Geometry::new([n, n, n], [0.35; 3], LengthUnit::Micrometre).unwrap();
    let c = (n as f64 - 1.0) / 2.0;
    let truth: Vec<bool> = (0..n * n * n)
        .map(|p| {
            let (i, j, k) = (p % n, (p / n) % n, p / (n * n));
            ((i as f64 - c) / 15.0).powi(2)
                + ((j as f64 - c) / 12.0).powi(2)
                + ((k as f64 - c) / 9.0).powi(2)
                <= 1.0
        })
        .collect();
    let pq = [(0.95, 0.99), (0.85, 0.98), (0.80, 0.995)];
    let mut paths = Vec::new();
    for (s, &(p, q)) in pq.iter().enumerate() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(s as u64 + 5);
        let data: Vec<u16> = truth
            .iter()
            .map(|&t| u16::from(if t { rng.gen_bool(p) } else { !rng.gen_bool(q) }))
            .collect();
        let path = tmp.path().join(format!("rater{s}.nii.gz"));
        interslice_io::write_labels(&path, &LabelVolume::from_vec(g.clone(), data).unwrap())
            .unwrap();
        paths.push(path);
    }
    let out = tmp.path().join("consensus.nii.gz");
    let prob = tmp.path().join("probability.nii.gz");
    let o = bin()
        .arg("staple")
        .args(&paths)
        .arg("--out")
        .arg(&out)
        .args(["--label", "1", "--json", "--probability"])
        .arg(&prob)
        .output()
        .unwrap();
    let v = stdout_json(&o);
    let est = &v["labels"][0];
    assert_eq!(est["converged"], true);
    for (j, &(p, q)) in pq.iter().enumerate() {
        let r = &est["raters"][j];
        let (sp, sq) = (
            r["sensitivity"].as_f64().unwrap(),
            r["specificity"].as_f64().unwrap(),
        );
        assert!(
            (sp - p).abs() < 0.02 && (sq - q).abs() < 0.02,
            "rater {j}: {sp} {sq} vs {p} {q}"
        );
    }
    let consensus = interslice_io::read_labels(&out).unwrap();
    let agree = consensus
        .data()
        .iter()
        .zip(&truth)
        .filter(|(a, t)| (**a == 1) == **t)
        .count();
    assert!(agree as f64 / truth.len() as f64 > 0.99);
    let AnyVolume::F32(pv) = interslice_io::read_volume(&prob).unwrap() else {
        panic!("the probability map is f32");
    };
    // The consensus is exactly the voxels with posterior above one half.
    assert!(
        pv.data()
            .iter()
            .zip(consensus.data())
            .all(|(&w, &l)| (w > 0.5) == (l == 1))
    );
    // Without --label: every label, painted.
    let o = bin()
        .arg("staple")
        .args(&paths)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("label 1:"));
    // One rater is not enough; --probability needs --label.
    let o = bin()
        .arg("staple")
        .arg(&paths[0])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = bin()
        .arg("staple")
        .args(&paths)
        .arg("--out")
        .arg(&out)
        .arg("--probability")
        .arg(&prob)
        .output()
        .unwrap();
    assert_one_line_error(&o, "--probability needs --label");
}
