//! `interslice bench` through the binary on a small stand-in for the
//! development data: the generated phantom and a folder `stardist/` holding
//! two labelled balls and their image, run as one mask and as a label volume.
use crate::common::bin;
use interslice_core::{Geometry, LabelVolume, LengthUnit, Volume};

/// Two balls of radius 5 (labels 1 and 2) in a 40 × 24 × 20 volume, and an
/// image bright inside them.
fn two_balls() -> (LabelVolume, LabelVolume) {
    let g = Geometry::new([40, 24, 20], [1.0; 3], LengthUnit::Micrometre).unwrap();
    let mut labels: LabelVolume = Volume::zeros(g.clone());
    let mut image: LabelVolume = Volume::filled(g, 50);
    for (label, cx) in [(1u16, 10.0), (2, 28.0)] {
        for z in 0..20usize {
            for y in 0..24usize {
                for x in 0..40usize {
                    let d = [x as f64 - cx, y as f64 - 11.5, z as f64 - 9.5];
                    if d.iter().map(|v| v * v).sum::<f64>() <= 30.0 {
                        labels.set(x, y, z, label);
                        image.set(x, y, z, 200);
                    }
                }
            }
        }
    }
    (labels, image)
}

/// A data folder holding the stardist stand-in (`two_balls`).
fn data_with_balls() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("stardist")).unwrap();
    let (labels, image) = two_balls();
    interslice_io::write_labels(&dir.path().join("stardist/mask3d.tif"), &labels).unwrap();
    interslice_io::write_labels(&dir.path().join("stardist/img3d.tif"), &image).unwrap();
    dir
}

/// `interslice bench ARGS --json DIR/rows.json --data DIR`: the run, and
/// its JSON rows (none where it wrote none).
fn bench(dir: &std::path::Path, args: &[&str]) -> (std::process::Output, Vec<serde_json::Value>) {
    let json = dir.join("rows.json");
    let _ = std::fs::remove_file(&json);
    let out = bin()
        .arg("bench")
        .args(args)
        .arg("--json")
        .arg(&json)
        .arg("--data")
        .arg(dir)
        .output()
        .unwrap();
    let rows = std::fs::read_to_string(&json)
        .map(|t| serde_json::from_str(&t).unwrap())
        .unwrap_or_default();
    (out, rows)
}

/// The skipped slices' Dice of `method` on `mask` among `rows`.
fn dice(rows: &[serde_json::Value], mask: &str, method: &str) -> Option<f64> {
    rows.iter()
        .find(|r| r["mask"] == mask && r["method"] == method)
        .map(|r| r["dice_skipped"].as_f64().unwrap())
}

/// The run succeeded (its stderr shown where not).
fn assert_ran(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn bench_scores_the_masks_and_the_label_volume_it_finds() {
    let dir = data_with_balls();
    let (out, rows) = bench(
        dir.path(),
        &["--skips", "2", "--methods", "nearest,shape-auto"],
    );
    assert_ran(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("| stardist nuclei, labelled (1) | shape-auto |"),
        "{stdout}"
    );
    // The families without data are named, not fatal.
    assert!(String::from_utf8_lossy(&out.stderr).contains("pyradiomics"));
    let dice = |mask: &str, method: &str| {
        dice(&rows, mask, method).unwrap_or_else(|| panic!("no row {mask} {method}"))
    };
    // Four phantom masks, the balls as one mask and as labels, two methods.
    assert_eq!(rows.len(), 6 * 2);
    for mask in ["stardist-all", "stardist-labels"] {
        // Balls drawn every third slice: every method is close, and the
        // shape methods are closer than the copy.
        assert!(dice(mask, "nearest") > 0.85, "{mask}");
        assert!(dice(mask, "shape-auto") > dice(mask, "nearest"), "{mask}");
        assert!(dice(mask, "shape-auto") > 0.9, "{mask}");
    }
    // Apart and labelled alike, the two scores agree.
    let (all, each) = (
        dice("stardist-all", "shape-auto"),
        dice("stardist-labels", "shape-auto"),
    );
    assert!((all - each).abs() < 0.02, "{all} {each}");
}

#[test]
fn bench_runs_only_the_masks_named_and_lists_them_for_a_name_it_lacks() {
    let dir = tempfile::tempdir().unwrap();
    let run = |masks: &str| {
        bench(
            dir.path(),
            &["--skips", "3", "--methods", "nearest", "--masks", masks],
        )
    };
    let (out, rows) = run("phantom2-nucleus");
    assert_ran(&out);
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["mask"], "phantom2-nucleus");
    assert!(rows[0]["dice_skipped"].as_f64().unwrap() > 0.8);
    // A mask the data lacks: one line naming those there are, no rows.
    let (out, rows) = run("phantom1-cell,brain1");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no mask brain1"), "{err}");
    assert!(err.contains("phantom1-cell, phantom1-nucleus"), "{err}");
    assert!(rows.is_empty());
    assert!(!dir.path().join("rows.json").exists());
}

#[test]
fn bench_prints_the_area_ceiling_on_masks_of_one_structure_only() {
    let dir = data_with_balls();
    let (out, rows) = bench(
        dir.path(),
        &["--skips", "3", "--methods", "area-ceiling,shape-area"],
    );
    assert_ran(&out);
    // The label volume has no truth of one structure to read the area from.
    assert_eq!(dice(&rows, "stardist-labels", "area-ceiling"), None);
    assert!(dice(&rows, "stardist-labels", "shape-area").is_some());
    for mask in ["stardist-all", "phantom1-cell", "phantom1-nucleus"] {
        let (ceiling, method) = (
            dice(&rows, mask, "area-ceiling").unwrap(),
            dice(&rows, mask, "shape-area").unwrap(),
        );
        // The same blend at the true area: at least the predicted area's
        // cut, up to the ties at the cut level.
        assert!(
            ceiling > 0.85 && ceiling >= method - 0.002,
            "{mask}: {ceiling} {method}"
        );
    }
}
