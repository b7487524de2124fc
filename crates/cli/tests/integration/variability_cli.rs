//! `interslice campaign simulate` then `interslice variability` on a small
//! phantom project: the report's files, its numbers against the exact
//! labels, the ratings, the same consensus from the server's export, and
//! one-line errors.
use interslice_store::{Role, Store};
use std::path::Path;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_interslice"))
}

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// Rows of a CSV file as maps from header to field (no quoted commas here).
fn csv(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

fn num(row: &std::collections::HashMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?}", row[key]))
}

#[test]
fn simulated_campaign_report() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("project");
    let o = bin()
        .args(["campaign", "simulate"])
        .arg(&dir)
        .args(["--cells", "2", "--size", "64"])
        .output()
        .unwrap();
    ok(&o);
    let out = tmp.path().join("report");
    let o = bin()
        .arg("variability")
        .arg(&dir)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = ok(&o);
    assert!(stdout.contains("4 structure(s) of 2 cell(s)"), "{stdout}");
    for f in [
        "volumes.csv",
        "summary.csv",
        "pairwise_dice.csv",
        "ratings.csv",
        "report.md",
        "volumes_label1.svg",
        "volumes_label2.svg",
        "consensus/cell_001_consensus.nii.gz",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Per user: three tracers, volumes in µm³ = voxels × 0.35³.
    let vols = csv(&out.join("volumes.csv"));
    assert_eq!(vols.len(), 2 * 2 * 3);
    for r in &vols {
        let v = num(r, "volume_um3");
        let n = num(r, "voxels");
        assert!((v - n * 0.35f64.powi(3)).abs() < 1e-3 * v.max(1.0), "{r:?}");
        // Every simulated tracer is close to the truth and to the consensus.
        assert!(num(r, "dice_vs_truth") > 0.85, "{r:?}");
        assert!(num(r, "dice_vs_consensus") > 0.85, "{r:?}");
        assert!(num(r, "staple_sensitivity") > 0.8, "{r:?}");
        assert!(num(r, "staple_specificity") > 0.98, "{r:?}");
    }
    // The summary: mean and sample SD of the three users' volumes.
    let sum = csv(&out.join("summary.csv"));
    assert_eq!(sum.len(), 4);
    for s in &sum {
        let users: Vec<f64> = vols
            .iter()
            .filter(|r| r["cell"] == s["cell"] && r["label"] == s["label"])
            .map(|r| num(r, "volume_um3"))
            .collect();
        let mean = users.iter().sum::<f64>() / 3.0;
        let sd = (users.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
        assert!((num(s, "mean_um3") - mean).abs() < 0.01, "{s:?}");
        assert!((num(s, "sd_um3") - sd).abs() < 0.01, "{s:?}");
        assert!(num(s, "sd_um3") > 0.0, "tracers differ: {s:?}");
        // The consensus is at least as good as the average tracer.
        let mean_truth_dice: f64 = vols
            .iter()
            .filter(|r| r["cell"] == s["cell"] && r["label"] == s["label"])
            .map(|r| num(r, "dice_vs_truth"))
            .sum::<f64>()
            / 3.0;
        assert!(
            num(s, "consensus_dice_vs_truth") >= mean_truth_dice,
            "{s:?}"
        );
        let truth = num(s, "truth_um3");
        assert!(
            (num(s, "consensus_um3") - truth).abs() < 0.1 * truth,
            "{s:?}"
        );
    }
    assert_eq!(csv(&out.join("pairwise_dice.csv")).len(), 2 * 2 * 3);
    // Two simulated ratings per cell, and the report lists them.
    let ratings = csv(&out.join("ratings.csv"));
    assert_eq!(ratings.len(), 4);
    assert!(
        ratings
            .iter()
            .all(|r| (1..=5).contains(&(num(r, "score") as u8)))
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## Cell (label 1): volume per user, µm³"));
    assert!(md.contains("## Ratings of automated segmentations"));
    assert!(md.contains("| tracer-a | tracer-b | tracer-c | mean | SD |"));
    let svg = std::fs::read_to_string(out.join("volumes_label2.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("STAPLE consensus"));

    // The server's export of user=consensus is the same volume (reviewers only).
    let store = Store::open(&interslice_store::default_db_path(&dir)).unwrap();
    let g = interslice_io::read_volume(&dir.join("cell_001.nii.gz"))
        .unwrap()
        .geometry()
        .clone();
    let method = interslice_project::methods::method_by_name(None).unwrap();
    let reviewer = store.upsert_user("rev", Role::Reviewer, None).unwrap();
    let (bytes, name) = interslice_project::consensus::export_bytes(
        &store,
        &reviewer,
        "cell_001",
        &g,
        "nii.gz",
        method.as_ref(),
        None,
        &interslice_core::Cancel::new(),
    )
    .unwrap();
    assert_eq!(name, "cell_001-consensus.nii.gz");
    let exported = tmp.path().join(&name);
    std::fs::write(&exported, bytes).unwrap();
    assert_eq!(
        interslice_io::read_labels(&exported).unwrap(),
        interslice_io::read_labels(&out.join("consensus/cell_001_consensus.nii.gz")).unwrap()
    );
    // The effort columns against the database: slices with contours, and
    // minutes from the 45 s of drawing time each simulated contour records.
    for r in &vols {
        let u = store.user(&r["user"]).unwrap().unwrap();
        let contours = store
            .contours(&interslice_store::ContourQuery {
                cell: r["cell"].clone(),
                user_id: u.id,
                axis: None,
                index: None,
                label: Some(r["label"].parse().unwrap()),
            })
            .unwrap();
        let slices: std::collections::BTreeSet<usize> =
            contours.iter().map(|c| c.contour.slice.index).collect();
        assert_eq!(num(r, "traced_slices") as usize, slices.len(), "{r:?}");
        let minutes = contours.len() as f64 * 45.0 / 60.0;
        assert!((num(r, "minutes") - minutes).abs() < 1e-3, "{r:?}");
        let predicted = num(r, "predicted_dice");
        eprintln!(
            "{} {} label {}: predicted {predicted:.4}, vs truth {:.4}",
            r["cell"],
            r["user"],
            r["label"],
            num(r, "dice_vs_truth")
        );
        assert!(predicted > 0.5 && predicted <= 1.0, "{r:?}");
    }
    assert!(
        md.contains("## Time to ground truth")
            && md.contains("Minutes per cell at predicted Dice ≥ 0.95: "),
        "{md}"
    );
    let tracer = store.user("tracer-a").unwrap().unwrap();
    let e = interslice_project::consensus::export_bytes(
        &store,
        &tracer,
        "cell_001",
        &g,
        "nii.gz",
        method.as_ref(),
        None,
        &interslice_core::Cancel::new(),
    )
    .unwrap_err();
    assert_eq!(
        interslice_server::error::ApiError::from(e).status.as_u16(),
        403
    );

    // Through the HTTP API: the nucleus of tracer-a evaluated against the
    // consensus (whole structures on both sides) has the report's Dice, and
    // the overlay of a segmentation against the consensus is served.
    drop(store);
    let mut config = interslice_server::Config::new(&dir);
    config.bind = "127.0.0.1:0".parse().unwrap();
    let server = interslice_server::spawn(config).unwrap();
    let mut rev = interslice_test_support::client::Client::new(&server.url());
    assert_eq!(rev.login("rev", None).unwrap().status, 200);
    let ev = rev
        .json(
            "POST",
            "/api/cells/cell_001/evaluate",
            &serde_json::json!({"label": 2, "reference": {"user": "consensus"},
                                "test": {"user": "tracer-a"}}),
        )
        .unwrap();
    assert_eq!(ev.status, 200, "{:?}", ev.error());
    let want = vols
        .iter()
        .find(|r| r["cell"] == "cell_001" && r["label"] == "2" && r["user"] == "tracer-a")
        .unwrap();
    let got = ev.json()["dice"].as_f64().unwrap();
    assert!(
        (got - num(want, "dice_vs_consensus")).abs() < 1e-6,
        "{got} vs {want:?}"
    );
    let ov = rev
        .get("/api/cells/cell_001/overlay/z/32?label=1&segmentation=1&reference_user=consensus")
        .unwrap();
    assert_eq!(ov.status, 200, "{:?}", ov.error());
    assert_eq!(ov.body.len(), 64 * 64);
    assert!(ov.body.contains(&1), "the cell is on slice 32");
    drop(server);

    // --label narrows the report to one structure.
    let o = bin()
        .arg("variability")
        .arg(&dir)
        .args(["--label", "2", "--out"])
        .arg(tmp.path().join("nucleus"))
        .output()
        .unwrap();
    assert!(ok(&o).contains("2 structure(s) of 2 cell(s)"));
}

#[test]
fn errors_are_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let o = bin().arg("variability").arg(tmp.path()).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("no annotation database"), "{err}");
    let o = bin()
        .args(["campaign", "simulate"])
        .arg(tmp.path())
        .args(["--tracers", "9"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--tracers must be 1 to 6"));
}
