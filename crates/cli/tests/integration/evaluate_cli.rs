//! `interslice evaluate` as a user runs it: the binary on reference cases, its
//! JSON keys and values, the table, and one-line errors on bad input.
use crate::common;
use common::{assert_one_line_error, bin, refs, stdout_json};
use serde_json::Value;
use std::path::PathBuf;

fn case(name: &str, which: &str) -> PathBuf {
    refs().join(format!("cases/{name}_{which}.nii.gz"))
}

fn expected(name: &str) -> Value {
    let text = std::fs::read_to_string(refs().join("metrics_expected.json")).unwrap();
    let json: Value = serde_json::from_str(&text).unwrap();
    json["cases"][name]["results"].clone()
}

fn close(got: &Value, want: &Value, rel: f64) -> bool {
    match (got.as_f64(), want.as_f64()) {
        (Some(g), Some(w)) => (g - w).abs() <= rel * w.abs().max(1e-12),
        _ => false,
    }
}

#[test]
fn label_json_has_the_contract_keys_and_reference_values() {
    let name = "blob64_mm";
    let (gt, pred) = (case(name, "gt"), case(name, "pred"));
    let mut c = bin();
    c.arg("evaluate").args([&gt, &pred]);
    c.args(["--label", "1", "--json"]);
    let out = c.output().unwrap();
    let j = stdout_json(&out);
    let r = expected(name);
    let (np, bd) = (&r["numpy_ref"], &r["ref_border6_kdtree"]);

    for (key, want) in [
        ("tp", &np["TP"]),
        ("fp", &np["FP"]),
        ("fn", &np["FN"]),
        ("tn", &np["TN"]),
        ("dice", &np["dice"]),
        ("jaccard", &np["jaccard"]),
        ("sensitivity", &np["sensitivity"]),
        ("specificity", &np["specificity"]),
        ("precision", &np["precision"]),
        ("volume_similarity", &np["volume_similarity_taha"]),
    ] {
        assert_eq!(&j[key], want, "{key}");
    }
    for (key, want) in [
        ("volume_gt", &np["volume_gt_phys"]),
        ("volume_seg", &np["volume_pred_phys"]),
        ("hd", &bd["hd"]),
        ("hd95", &bd["hd95_max_of_directed"]),
        ("hd95_pooled", &bd["hd95_pooled"]),
        ("assd", &bd["msd_pooled"]),
        ("masd", &bd["assd_mean_of_directed_means"]),
        ("nsd", &bd["nsd_count_le_tol"]),
    ] {
        assert!(close(&j[key], want, 1e-6), "{key}: {} vs {want}", j[key]);
    }
    assert_eq!(j["label"], 1);
    assert_eq!(j["unit"], "mm");
    assert_eq!(j["tolerance"], 1.0);
}

#[test]
fn all_labels_json_and_null_rules() {
    let name = "gt_empty_mm";
    let (gt, pred) = (case(name, "gt"), case(name, "pred"));
    let mut c = bin();
    c.arg("evaluate").args([&gt, &pred]).arg("--json");
    let j = stdout_json(&c.output().unwrap());
    let m = &j["labels"]["1"];
    assert_eq!(j["labels"].as_object().unwrap().len(), 1);
    // Empty ground truth: Dice 0, sensitivity 0/0, distances undefined.
    assert_eq!(m["dice"], 0.0);
    assert!(m["sensitivity"].is_null());
    for key in ["hd", "hd95", "hd95_pooled", "assd", "masd", "nsd"] {
        assert!(m[key].is_null(), "{key} = {}", m[key]);
    }
    // For a 0/1 mask the union of labels is label 1.
    assert_eq!(&j["foreground"], m);
}

#[test]
fn tolerance_changes_nsd_only() {
    let name = "sphere_shift_mm";
    let (gt, pred) = (case(name, "gt"), case(name, "pred"));
    let get = |tol: &str| {
        let mut c = bin();
        c.arg("evaluate").args([&gt, &pred]);
        c.args(["--label", "1", "--json", "--tolerance", tol]);
        stdout_json(&c.output().unwrap())
    };
    let (a, b) = (get("1"), get("10"));
    assert_eq!(b["nsd"], 1.0);
    assert!(a["nsd"].as_f64().unwrap() < 1.0);
    assert_eq!(a["hd95"], b["hd95"]);
    assert_eq!(b["tolerance"], 10.0);
}

#[test]
fn table_without_json() {
    let name = "blob64_mm";
    let mut c = bin();
    c.arg("evaluate")
        .args([case(name, "gt"), case(name, "pred")])
        .args(["--label", "1"]);
    let out = c.output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("Dice") && text.contains("0.822656"), "{text}");
    assert!(text.contains("HD95, pooled (mm)"), "{text}");
}

#[test]
fn different_geometry_is_a_one_line_error() {
    let mut c = bin();
    c.arg("evaluate")
        .arg(case("blob64_mm", "gt"))
        .arg(case("blob256_um", "pred"));
    assert_one_line_error(&c.output().unwrap(), "differ");
    // Same dims, different spacing.
    let mut c = bin();
    c.arg("evaluate")
        .arg(case("blob64_mm", "gt"))
        .arg(case("blob64_iso", "pred"));
    assert_one_line_error(&c.output().unwrap(), "spacing");
}

#[test]
fn missing_file_and_bad_tolerance_are_one_line_errors() {
    let mut c = bin();
    c.arg("evaluate")
        .arg(case("blob64_mm", "gt"))
        .arg("/nonexistent/seg.nii.gz");
    assert_one_line_error(&c.output().unwrap(), "segmentation");
    let mut c = bin();
    c.arg("evaluate")
        .arg(case("blob64_mm", "gt"))
        .arg(case("blob64_mm", "pred"))
        .args(["--tolerance", "-1"]);
    assert_one_line_error(&c.output().unwrap(), "tolerance");
}

#[test]
fn a_label_in_neither_volume_is_answered_with_a_warning() {
    let name = "gt_empty_mm";
    let (gt, pred) = (case(name, "gt"), case(name, "pred"));
    let out = bin()
        .arg("evaluate")
        .args([&gt, &pred])
        .args(["--label", "7", "--json"])
        .output()
        .unwrap();
    let j = stdout_json(&out);
    assert_eq!((j["label"].as_u64(), j["tp"].as_u64()), (Some(7), Some(0)));
    assert!(j["dice"].is_null() && j["hd"].is_null());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("label 7 is in neither volume"), "{err}");
}
