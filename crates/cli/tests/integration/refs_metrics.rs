//! The metrics of `interslice evaluate` against the reference values of
//! established libraries, on every case in `tests/fixtures/refs/cases/`.
//!
//! Overlap metrics and voxel counts must match numpy (`numpy_ref`) exactly;
//! border-voxel distances must match the exact border-voxel reference
//! (`ref_border6_kdtree`, which equals medpy and MONAI) to 1e-6 relative.
//! Physical volumes are compared to 1e-6 relative as well: the NIfTI files store
//! the spacing as f32 (0.35 is 0.3499999940…), the reference used the nominal
//! spacing.
use interslice_core::metrics::{Metrics, evaluate_label};
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

fn refs_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/refs");
    assert!(
        dir.join("metrics_expected.json").is_file(),
        "reference data not found at {} (tests/fixtures/refs in the repository)",
        dir.display()
    );
    dir
}

/// A reference number; NaN and ±inf (stored as strings) are our `None`.
fn num(v: &Value) -> Option<f64> {
    match v {
        Value::Number(n) => n.as_f64().filter(|x| x.is_finite()),
        Value::String(s) if ["NaN", "Infinity", "-Infinity"].contains(&s.as_str()) => None,
        other => panic!("unexpected reference value {other}"),
    }
}

fn count(v: &Value) -> u64 {
    v.as_u64()
        .unwrap_or_else(|| panic!("expected a count, got {v}"))
}

fn sha256_u8(data: &[u16]) -> String {
    let bytes: Vec<u8> = data
        .iter()
        .map(|&x| u8::try_from(x).expect("reference masks hold 0/1"))
        .collect();
    Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn check_exact(errs: &mut Vec<String>, case: &str, key: &str, got: Option<f64>, want: Option<f64>) {
    if got != want {
        errs.push(format!("{case}: {key} = {got:?}, reference {want:?}"));
    }
}

fn check_rel(errs: &mut Vec<String>, case: &str, key: &str, got: Option<f64>, want: Option<f64>) {
    let ok = match (got, want) {
        (Some(g), Some(w)) => (g - w).abs() <= 1e-6 * w.abs().max(1e-12),
        (None, None) => true,
        _ => false,
    };
    if !ok {
        errs.push(format!("{case}: {key} = {got:?}, reference {want:?}"));
    }
}

fn compare(case: &str, m: &Metrics, num_ref: &Value, dist_ref: &Value, errs: &mut Vec<String>) {
    for (key, got) in [("TP", m.tp), ("FP", m.fp), ("FN", m.fn_), ("TN", m.tn)] {
        if got != count(&num_ref[key]) {
            errs.push(format!("{case}: {key} = {got}, reference {}", num_ref[key]));
        }
    }
    for (key, got) in [
        ("dice", m.dice),
        ("jaccard", m.jaccard),
        ("sensitivity", m.sensitivity),
        ("specificity", m.specificity),
        ("precision", m.precision),
        ("volume_similarity_taha", m.volume_similarity),
    ] {
        check_exact(errs, case, key, got, num(&num_ref[key]));
    }
    check_rel(
        errs,
        case,
        "volume_gt_phys",
        Some(m.volume_gt),
        num(&num_ref["volume_gt_phys"]),
    );
    check_rel(
        errs,
        case,
        "volume_pred_phys",
        Some(m.volume_seg),
        num(&num_ref["volume_pred_phys"]),
    );

    if dist_ref.get("error").is_some() {
        // One border set is empty: the reference gives no distances, we give nulls.
        if m.border_gt != count(&dist_ref["n_border_gt"])
            || m.border_seg != count(&dist_ref["n_border_pred"])
        {
            errs.push(format!(
                "{case}: border counts {}/{} vs {dist_ref}",
                m.border_gt, m.border_seg
            ));
        }
        for (key, got) in [
            ("hd", m.hd),
            ("hd95", m.hd95),
            ("hd95_pooled", m.hd95_pooled),
            ("assd", m.assd),
            ("masd", m.masd),
            ("nsd", m.nsd),
        ] {
            check_exact(errs, case, key, got, None);
        }
        return;
    }
    assert_eq!(
        dist_ref["_a"], "pred",
        "{case}: reference direction changed"
    );
    if m.border_seg != count(&dist_ref["n_surface_a"])
        || m.border_gt != count(&dist_ref["n_surface_b"])
    {
        errs.push(format!(
            "{case}: border counts {}/{} vs {dist_ref}",
            m.border_seg, m.border_gt
        ));
    }
    for (key, got) in [
        ("hd", m.hd),
        ("hd95_max_of_directed", m.hd95),
        ("hd95_pooled", m.hd95_pooled),
        ("msd_pooled", m.assd),
        ("assd_mean_of_directed_means", m.masd),
        ("nsd_count_le_tol", m.nsd),
        ("mean_a_to_b", m.mean_seg_to_gt),
        ("mean_b_to_a", m.mean_gt_to_seg),
    ] {
        check_rel(errs, case, key, got, num(&dist_ref[key]));
    }
}

#[test]
fn every_reference_case_matches() {
    let dir = refs_dir();
    let text = std::fs::read_to_string(dir.join("metrics_expected.json"))
        .expect("read metrics_expected.json");
    let json: Value = serde_json::from_str(&text).expect("parse metrics_expected.json");
    let tol = json["meta"]["nsd_tolerance"]
        .as_f64()
        .expect("nsd_tolerance");
    let cases = json["cases"].as_object().expect("cases");

    // Every pair on disk has an entry, so a new case cannot be skipped silently.
    let on_disk: Vec<String> = std::fs::read_dir(dir.join("cases"))
        .expect("list cases")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| n.strip_suffix("_gt.nii.gz").map(str::to_string))
        .collect();
    assert!(
        on_disk.len() >= 24,
        "expected at least 24 cases, found {}",
        on_disk.len()
    );
    for c in &on_disk {
        assert!(cases.contains_key(c), "case {c} has no reference values");
    }

    let mut errs = Vec::new();
    for (case, c) in cases {
        let gt_path = dir.join(c["files"]["gt"].as_str().expect("gt path"));
        let pred_path = dir.join(c["files"]["pred"].as_str().expect("pred path"));
        let gt = interslice_io::read_labels(&gt_path).unwrap_or_else(|e| panic!("{case}: {e}"));
        let pred = interslice_io::read_labels(&pred_path).unwrap_or_else(|e| panic!("{case}: {e}"));

        // The reader produced the array the references were computed on.
        let shape: Vec<usize> = c["shape_zyx"]
            .as_array()
            .expect("shape")
            .iter()
            .map(|v| v.as_u64().expect("dim") as usize)
            .collect();
        assert_eq!(gt.dims(), [shape[2], shape[1], shape[0]], "{case}: dims");
        assert_eq!(
            sha256_u8(gt.data()),
            c["sha256_u8_zyx"]["gt"],
            "{case}: gt array hash"
        );
        assert_eq!(
            sha256_u8(pred.data()),
            c["sha256_u8_zyx"]["pred"],
            "{case}: pred array hash"
        );
        for (a, want) in gt
            .geometry()
            .spacing
            .iter()
            .zip(c["spacing_xyz"].as_array().expect("spacing"))
        {
            let want = want.as_f64().expect("spacing value");
            assert!(
                (a - want).abs() <= 1e-6 * want,
                "{case}: spacing {a} vs {want}"
            );
        }

        let m = evaluate_label(&gt, &pred, 1, tol).unwrap_or_else(|e| panic!("{case}: {e}"));
        compare(
            case,
            &m,
            &c["results"]["numpy_ref"],
            &c["results"]["ref_border6_kdtree"],
            &mut errs,
        );
    }
    assert!(
        errs.is_empty(),
        "{} mismatches:\n{}",
        errs.len(),
        errs.join("\n")
    );
}
