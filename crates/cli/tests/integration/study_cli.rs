//! `interslice study` through the binary on a small phantom: every output is
//! written, rows cover every (method, skip, label), and k = 0 is exact.
use std::path::PathBuf;
use std::process::Command;

/// The exact labels of a `size`³ phantom cell, written to `name` in a
/// temporary folder.
fn phantom_ground_truth_of(size: usize, seed: u64, name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = interslice_core::phantom::generate(&interslice_core::phantom::PhantomParams {
        size,
        seed,
        bits: 8,
        noise: 0.0,
    })
    .unwrap();
    let gt = dir.path().join(name);
    interslice_io::write_labels(&gt, &p.labels).unwrap();
    (dir, gt)
}

/// The exact labels of a 48³ phantom cell, as `.nii.gz`.
fn phantom_ground_truth() -> (tempfile::TempDir, PathBuf) {
    phantom_ground_truth_of(48, 3, "gt.nii.gz")
}

/// `interslice study GT --out OUT ARGS…`.
fn study(gt: &std::path::Path, out: &std::path::Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_interslice"))
        .arg("study")
        .arg(gt)
        .arg("--out")
        .arg(out)
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn study_writes_csv_json_plots_and_summary() {
    let (dir, gt) = phantom_ground_truth();
    let out = dir.path().join("study");
    let r = study(
        &gt,
        &out,
        &[
            "--skips",
            "0..3",
            "--methods",
            "shape-based,linear",
            "--label",
            "2",
            "--quiet",
        ],
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    for f in [
        "results.csv",
        "results.json",
        "summary.md",
        "dice.svg",
        "jaccard.svg",
        "hd95.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 4, "{csv}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 8);
    for r in rows {
        assert_eq!(r["label"], 2);
        if r["skip"] == 0 {
            assert_eq!(r["metrics"]["dice"], 1.0, "{r}");
        }
    }
    let svg = std::fs::read_to_string(out.join("dice.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("shape-based"),
        "{}",
        &svg[..200.min(svg.len())]
    );
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("| shape-based |") && md.contains("k=3"), "{md}");
}

#[test]
fn strategy_study_compares_uniform_and_advised_slices() {
    let (dir, gt) = phantom_ground_truth();
    let out = dir.path().join("strategy");
    let r = study(
        &gt,
        &out,
        &[
            "--strategy",
            "uniform,advised",
            "--budget",
            "2..4",
            "--label",
            "1",
            "--quiet",
        ],
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let csv = std::fs::read_to_string(out.join("strategy.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 6, "{csv}");
    for row in &rows {
        let budget: usize = row[1].parse().unwrap();
        let traced: usize = row[2].parse().unwrap();
        assert_eq!(traced, budget + 2, "{csv}");
        let slices: Vec<usize> = row[5].split(' ').map(|s| s.parse().unwrap()).collect();
        assert_eq!(slices.len(), traced);
        assert!(slices.windows(2).all(|w| w[0] < w[1]), "{csv}");
        // Minutes at the default 45 s per traced slice.
        let minutes: f64 = row[6].parse().unwrap();
        assert!((minutes - traced as f64 * 0.75).abs() < 1e-9, "{csv}");
        for dice in [row[3], row[4]] {
            let d: f64 = dice.parse().unwrap();
            assert!(d > 0.5 && d <= 1.0, "{csv}");
        }
    }
    // The same outermost slices for both strategies.
    let ends = |r: &Vec<&str>| {
        let s: Vec<&str> = r[5].split(' ').collect();
        (s[0].to_string(), s[s.len() - 1].to_string())
    };
    assert!(rows.iter().all(|r| ends(r) == ends(&rows[0])));
    let md = std::fs::read_to_string(out.join("strategy.md")).unwrap();
    assert!(md.contains("| 4 | 6 |"), "{md}");
    // An unknown strategy is a one-line error.
    let r = study(&gt, &out, &["--strategy", "random"]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("unknown strategy 'random'"));
}

#[test]
fn study_prints_minutes_per_cell_for_a_simulated_tracer() {
    let (dir, gt) = phantom_ground_truth();
    let out = dir.path().join("effort");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "--skips",
            "2,4",
            "--methods",
            "shape-based",
            "--label",
            "2",
            "--quiet",
        ];
        args.extend_from_slice(extra);
        study(&gt, &out, &args)
    };
    let r = run(&["--seconds-per-contour", "30"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let stdout = String::from_utf8_lossy(&r.stdout).to_string();
    let results = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let effort = std::fs::read_to_string(out.join("effort.csv")).unwrap();
    let mut lines = effort.lines();
    assert_eq!(
        lines.next().unwrap(),
        "method,skip,traced_slices,seconds_per_contour,minutes,dice_skipped,dice_volume"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2, "{effort}");
    for row in &rows {
        let (skip, traced): (usize, usize) = (row[1].parse().unwrap(), row[2].parse().unwrap());
        assert_eq!(row[3], "30");
        // minutes = traced slices × 30 s / 60.
        let minutes: f64 = row[4].parse().unwrap();
        assert!((minutes - traced as f64 / 2.0).abs() < 1e-9, "{effort}");
        // The same slices and whole-volume Dice as results.csv.
        let res: Vec<&str> = results
            .lines()
            .find(|l| l.starts_with(&format!("shape-based,{skip},2,")))
            .unwrap()
            .split(',')
            .collect();
        assert_eq!(res[3], row[2], "{results}");
        assert_eq!(res[5], row[6], "{results}");
        let skipped: f64 = row[5].parse().unwrap();
        assert!(skipped > 0.5 && skipped < 1.0, "{effort}");
        assert!(
            stdout.contains(&format!(
                "k={skip:<2}: {traced:>3} traced slices, {minutes:>6.1} min at 30 s/slice"
            )),
            "{stdout}"
        );
    }
    // Fewer slices at k = 4 than at k = 2: fewer minutes.
    let m: Vec<f64> = rows.iter().map(|r| r[4].parse().unwrap()).collect();
    assert!(m[1] < m[0], "{effort}");
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("## Time to ground truth") && md.contains("30 s per traced slice"));
    // The time per contour is bounded.
    for bad in ["0", "3601", "x"] {
        let r = run(&["--seconds-per-contour", bad]);
        assert!(!r.status.success(), "{bad}");
        assert!(
            String::from_utf8_lossy(&r.stderr).contains("--seconds-per-contour"),
            "{bad}"
        );
    }
}

#[test]
fn study_rejects_bad_arguments() {
    let (dir, gt) = phantom_ground_truth_of(32, 1, "gt.nrrd");
    let run = |args: &[&str]| {
        let r = Command::new(env!("CARGO_BIN_EXE_interslice"))
            .arg("study")
            .args(args)
            .output()
            .unwrap();
        assert!(!r.status.success());
        String::from_utf8_lossy(&r.stderr).to_string()
    };
    let gt = gt.to_str().unwrap();
    let out = dir.path().join("o");
    let out = out.to_str().unwrap();
    assert!(run(&[gt, "--out", out, "--skips", "9..2"]).contains("--skips"));
    assert!(run(&[gt, "--out", out, "--methods", "nope"]).contains("unknown method"));
    assert!(run(&[gt, "--out", out, "--label", "99"]).contains("label 99"));
}

/// The oracle starts from the better of its greedy picks and uniform spacing
/// and only moves slices where the Dice rises: at every budget it is at least
/// as good as uniform spacing on the whole volume, and it traces the budget.
#[test]
fn the_oracle_strategy_is_never_below_uniform_spacing() {
    let (dir, gt) = phantom_ground_truth();
    let out = dir.path().join("oracle");
    let r = study(
        &gt,
        &out,
        &[
            "--strategy",
            "uniform,oracle",
            "--budget",
            "1..3",
            "--label",
            "2",
            "--quiet",
        ],
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let csv = std::fs::read_to_string(out.join("strategy.csv")).unwrap();
    let row = |strategy: &str, budget: &str| -> (f64, Vec<usize>) {
        let l = csv
            .lines()
            .map(|l| l.split(',').collect::<Vec<_>>())
            .find(|c| c[0] == strategy && c[1] == budget)
            .unwrap_or_else(|| panic!("no {strategy} {budget} in {csv}"));
        (
            l[4].parse().unwrap(),
            l[5].split(' ').map(|s| s.parse().unwrap()).collect(),
        )
    };
    for budget in ["1", "2", "3"] {
        let (uniform, u) = row("uniform", budget);
        let (oracle, o) = row("oracle", budget);
        assert!(
            oracle >= uniform,
            "budget {budget}: {oracle} < {uniform}: {csv}"
        );
        assert_eq!(o.len(), u.len(), "budget {budget}: {csv}");
    }
    let md = std::fs::read_to_string(out.join("strategy.md")).unwrap();
    assert!(md.contains("uniform against oracle"), "{md}");
    assert!(md.contains("| oracle (volume) |"), "{md}");
}

/// `study --image`: the image-guided method is studied beside the shape
/// methods on the cell's intensities, is named the default (what
/// `interpolate` uses with the image), and is at least the shape default
/// on the noisy phantom's nucleus; an image on another grid is refused.
#[test]
fn study_with_the_image_compares_the_image_method_with_the_shape_methods() {
    let dir = tempfile::tempdir().unwrap();
    let p = interslice_core::phantom::generate(&interslice_core::phantom::PhantomParams {
        size: 48,
        seed: 3,
        bits: 8,
        noise: 0.1,
    })
    .unwrap();
    let (gt, image) = (dir.path().join("gt.nii.gz"), dir.path().join("img.nii.gz"));
    interslice_io::write_labels(&gt, &p.labels).unwrap();
    interslice_io::write_volume(&image, &p.intensity).unwrap();
    let out = dir.path().join("study");
    let args = [
        "--image",
        image.to_str().unwrap(),
        "--skips",
        "1,5",
        "--methods",
        "shape-auto,image-guided",
        "--label",
        "2",
        "--quiet",
    ];
    let r = study(&gt, &out, &args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["default_method"], "image-guided");
    let dice = |method: &str, k: u64| {
        json["rows"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["method"] == method && r["skip"] == k)
            .and_then(|r| r["dice_skipped"].as_f64())
            .unwrap_or_else(|| panic!("no row for {method} k={k}"))
    };
    for k in [1, 5] {
        let (g, s) = (dice("image-guided", k), dice("shape-auto", k));
        println!("study --image k={k}: image-guided {g:.4}, shape-auto {s:.4}");
        assert!(g >= s - 0.005 && g > 0.9, "k={k}: {g} vs {s}");
    }
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("the default method is `image-guided`"), "{md}");
    // The image of another cell (another grid) is an error.
    let small = interslice_core::phantom::generate(&interslice_core::phantom::PhantomParams {
        size: 32,
        seed: 3,
        bits: 8,
        noise: 0.1,
    })
    .unwrap();
    interslice_io::write_volume(&image, &small.intensity).unwrap();
    let r = study(&gt, &dir.path().join("bad"), &args);
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}
