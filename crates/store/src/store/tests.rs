use super::fixtures::*;
use super::*;
use crate::model::*;
use interslice_core::{Geometry, LengthUnit, Volume};

#[test]
fn migrations_reach_the_latest_version_and_reopen() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sub").join("db.sqlite");
    {
        let s = Store::open(&path).unwrap();
        assert_eq!(s.schema_version().unwrap(), migrations::latest_version());
        s.upsert_cell("c", "c.nrrd").unwrap();
    }
    let s = Store::open(&path).unwrap();
    assert!(s.cell("c").unwrap().is_some());
    assert_eq!(s.integrity_check().unwrap(), "ok");
    let mode: String = s
        .lock()
        .query_row("PRAGMA journal_mode", [], |r| r.get(0))
        .unwrap();
    assert_eq!(mode, "wal");
}

#[test]
fn newer_schema_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("db.sqlite");
    {
        let c = Connection::open(&path).unwrap();
        c.pragma_update(None, "user_version", 99).unwrap();
    }
    assert!(matches!(
        Store::open(&path),
        Err(StoreError::TooNew { found: 99, .. })
    ));
}

#[test]
fn default_labels_and_adding_one() {
    let s = Store::open_in_memory().unwrap();
    let names = label_names(&s);
    assert_eq!(
        names,
        vec![
            (1, "Cell".to_string()),
            (2, "Nucleus".to_string()),
            (3, "Nucleolus 1".to_string()),
            (4, "Nucleolus 2".to_string())
        ]
    );
    let l = s.add_label("Vacuole", Some("#A0B0C0"), None).unwrap();
    assert_eq!((l.id, l.color.as_str()), (5, "#a0b0c0"));
    assert!(s.add_label("Vacuole", None, None).is_err());
    assert!(s.add_label("Other", Some("red"), None).is_err());
}

#[test]
fn passwords_sessions_and_roles() {
    let s = Store::open_in_memory().unwrap();
    let u = s
        .upsert_user("bob", Role::Reviewer, Some("s3cret"))
        .unwrap();
    assert_eq!(u.role, Role::Reviewer);
    assert!(u.has_password);
    assert_eq!(s.verify_password("bob", "s3cret").unwrap().id, u.id);
    assert!(matches!(
        s.verify_password("bob", "wrong"),
        Err(StoreError::BadCredentials)
    ));
    assert!(matches!(
        s.verify_password("nobody", "x"),
        Err(StoreError::BadCredentials)
    ));
    let t = s.create_session(u.id, true).unwrap();
    assert_eq!(t.len(), 64);
    let (who, with_password) = s.session_user(&t).unwrap().unwrap();
    assert_eq!((who.name.as_str(), with_password), ("bob", true));
    // A session remembers that it was opened by name alone.
    let by_name = s.create_session(u.id, false).unwrap();
    assert!(!s.session_user(&by_name).unwrap().unwrap().1);
    s.delete_session(&t).unwrap();
    assert!(s.session_user(&t).unwrap().is_none());
    // Updating the role keeps the password.
    s.upsert_user("bob", Role::Tracer, None).unwrap();
    assert!(s.verify_password("bob", "s3cret").is_ok());
    assert!(s.upsert_user("../x", Role::Tracer, None).is_err());
    assert!(s.upsert_user("", Role::Tracer, None).is_err());
}

#[test]
fn contours_round_trip_with_provenance() {
    let (s, u) = store_with_cell();
    let (c, created) = s
        .add_contour(&key(&u, 2, 7), square(1.0), Some("abc".into()))
        .unwrap();
    assert!(created);
    assert_eq!(c.contour.author, "alice");
    assert_eq!(c.duration_ms, Some(35.0));
    assert_eq!(c.contour.points, square(1.0).points);
    // Idempotent retry.
    let (again, created) = s
        .add_contour(&key(&u, 2, 7), square(9.0), Some("abc".into()))
        .unwrap();
    assert!(!created);
    assert_eq!(again.id, c.id);
    assert_eq!(again.contour.points, square(1.0).points);
    let all = s
        .contours(&ContourQuery {
            cell: "cell1".into(),
            user_id: u.id,
            ..Default::default()
        })
        .unwrap();
    assert_eq!(all.len(), 1);
    assert_eq!(s.contour(c.id).unwrap().unwrap(), c);
    assert_eq!(s.statuses(u.id).unwrap()["cell1"], CellStatus::InProgress);
}

#[test]
fn invalid_contours_are_refused() {
    let (s, u) = store_with_cell();
    let mut c = square(0.0);
    c.points.truncate(2);
    assert!(matches!(
        s.add_contour(&key(&u, 1, 0), c, None),
        Err(StoreError::Invalid(_))
    ));
    let mut c = square(0.0);
    c.points[0][0] = f64::NAN;
    assert!(s.add_contour(&key(&u, 1, 0), c, None).is_err());
    let mut c = square(0.0);
    c.pressure = Some(vec![1.0]);
    assert!(s.add_contour(&key(&u, 1, 0), c, None).is_err());
    assert!(matches!(
        s.add_contour(&key(&u, 99, 0), square(0.0), None),
        Err(StoreError::Invalid(_))
    ));
    let mut k = key(&u, 1, 0);
    k.cell = "nope".into();
    assert!(matches!(
        s.add_contour(&k, square(0.0), None),
        Err(StoreError::NotFound(_))
    ));
}

/// Drawn slices `(index, empty)`.
fn drawn_at(slices: &[(usize, bool)]) -> Vec<DrawnSlice> {
    slices
        .iter()
        .map(|&(index, empty)| DrawnSlice { index, empty })
        .collect()
}

#[test]
fn drawn_slices_replace_empty_and_delete() {
    let (s, u) = store_with_cell();
    s.add_contour(&key(&u, 1, 3), square(0.0), None).unwrap();
    s.add_contour(&key(&u, 1, 3), square(5.0), None).unwrap();
    s.mark_empty(&key(&u, 1, 8)).unwrap();
    s.add_contour(&key(&u, 2, 5), square(0.0), None).unwrap();
    let d = s.drawn("cell1", u.id, 1, Axis::Z).unwrap();
    assert_eq!(d, drawn_at(&[(3, false), (8, true)]));
    // Replace with one contour.
    let r = s.replace_slice(&key(&u, 1, 3), vec![square(2.0)]).unwrap();
    assert_eq!(r.len(), 1);
    // Adding a contour to an empty slice unmarks it.
    s.add_contour(&key(&u, 1, 8), square(1.0), None).unwrap();
    assert_eq!(
        s.drawn("cell1", u.id, 1, Axis::Z).unwrap(),
        drawn_at(&[(3, false), (8, false)])
    );
    // Clearing removes the slice from the drawn set.
    s.replace_slice(&key(&u, 1, 8), vec![]).unwrap();
    assert_eq!(s.drawn("cell1", u.id, 1, Axis::Z).unwrap().len(), 1);
    assert_eq!(
        s.drawn_labels("cell1", u.id).unwrap(),
        vec![(1, Axis::Z, 1), (2, Axis::Z, 1)]
    );
    // Delete: someone else's is forbidden, unknown is not found.
    let other = s.ensure_user("eve").unwrap();
    assert!(matches!(
        s.delete_contour("cell1", other.id, r[0].id),
        Err(StoreError::Forbidden(_))
    ));
    assert!(matches!(
        s.delete_contour("cell1", u.id, 9999),
        Err(StoreError::NotFound(_))
    ));
    s.delete_contour("cell1", u.id, r[0].id).unwrap();
    assert!(s.contour(r[0].id).unwrap().is_none());
    assert_eq!(s.tracers_of("cell1").unwrap().len(), 1);
}

#[test]
fn undo_and_redo_restore_exact_states() {
    let (s, u) = store_with_cell();
    let q = ContourQuery {
        cell: "cell1".into(),
        user_id: u.id,
        ..Default::default()
    };
    let (a, _) = s.add_contour(&key(&u, 1, 0), square(0.0), None).unwrap();
    let (b, _) = s.add_contour(&key(&u, 1, 1), square(1.0), None).unwrap();
    s.mark_empty(&key(&u, 1, 0)).unwrap();
    assert_eq!(s.contours(&q).unwrap(), vec![b.clone()]);
    assert!(s.undo("cell1", u.id).unwrap().changed); // un-mark empty: a is back with its id
    assert_eq!(s.contours(&q).unwrap(), vec![a.clone(), b.clone()]);
    assert!(s.undo("cell1", u.id).unwrap().changed); // remove b
    assert_eq!(s.contours(&q).unwrap(), vec![a.clone()]);
    assert!(s.redo("cell1", u.id).unwrap().changed); // b again
    assert_eq!(s.contours(&q).unwrap(), vec![a.clone(), b.clone()]);
    // A new change drops the redo stack.
    s.undo("cell1", u.id).unwrap();
    s.add_contour(&key(&u, 1, 2), square(2.0), None).unwrap();
    assert!(!s.redo("cell1", u.id).unwrap().changed);
    // Another user's undo does not touch alice's work.
    let eve = s.ensure_user("eve").unwrap();
    assert!(!s.undo("cell1", eve.id).unwrap().changed);
    for _ in 0..3 {
        s.undo("cell1", u.id).unwrap();
    }
    assert!(s.contours(&q).unwrap().is_empty());
    assert!(!s.undo("cell1", u.id).unwrap().changed);
    assert!(s.drawn("cell1", u.id, 1, Axis::Z).unwrap().is_empty());
}

#[test]
fn audit_log_is_append_only() {
    let (s, u) = store_with_cell();
    s.add_contour(&key(&u, 1, 0), square(0.0), None).unwrap();
    let log = s.audit_log(10).unwrap();
    assert_eq!(log[0].action, "contour.add");
    assert_eq!(log[0].user.as_deref(), Some("alice"));
    let conn = s.lock();
    assert!(conn.execute("DELETE FROM audit", []).is_err());
    assert!(conn.execute("UPDATE audit SET action = 'x'", []).is_err());
}

#[test]
fn time_status_results_segmentations_ratings() {
    let (s, u) = store_with_cell();
    assert_eq!(s.add_time("cell1", u.id, 12.5).unwrap(), 12.5);
    assert_eq!(s.add_time("cell1", u.id, 2.5).unwrap(), 15.0);
    assert!(s.add_time("cell1", u.id, -1.0).is_err());
    assert_eq!(s.time_spent("cell1", u.id).unwrap(), 15.0);
    s.set_status("cell1", u.id, CellStatus::Done).unwrap();
    assert_eq!(s.statuses(u.id).unwrap()["cell1"], CellStatus::Done);

    let g = Geometry::new([5, 4, 3], [0.35, 0.35, 0.7], LengthUnit::Micrometre).unwrap();
    let data: Vec<bool> = (0..60).map(|i| i % 5 == 1).collect();
    let mask = Volume::from_vec(g.clone(), data).unwrap();
    let id = s
        .save_result("cell1", u.id, 2, Axis::Y, "shape-based", &mask)
        .unwrap();
    let (meta, back) = s.result(id).unwrap().unwrap();
    assert_eq!(back, mask);
    assert_eq!((meta.voxels, meta.label, meta.axis), (12, 2, Axis::Y));
    assert!(s.result(id + 1).unwrap().is_none());
    assert_eq!(s.results("cell1", u.id).unwrap(), vec![meta]);
    assert!(s.results("cell1", u.id + 1).unwrap().is_empty());

    let labels = Volume::from_vec(g, (0..60).map(|i| (i % 3) as u16).collect()).unwrap();
    let seg = s
        .save_segmentation(
            "cell1",
            "otsu",
            "otsu",
            &serde_json::json!({"smooth": 1.0}),
            &labels,
            Some(u.id),
        )
        .unwrap();
    assert_eq!(s.segmentations("cell1").unwrap(), vec![seg.clone()]);
    assert_eq!(
        s.segmentation_volume("cell1", seg.id).unwrap().unwrap(),
        labels
    );
    assert!(s.segmentation_volume("other", seg.id).unwrap().is_none());
    let r = s
        .add_rating("cell1", u.id, &seg.id.to_string(), 4, "good")
        .unwrap();
    assert_eq!(s.ratings(Some("cell1")).unwrap(), vec![r]);
    assert!(s.add_rating("cell1", u.id, "1", 6, "").is_err());
}

#[test]
fn cell_content_hash_change_is_reported() {
    let (s, _) = store_with_cell();
    let g = Geometry::new([2, 2, 2], [1.0; 3], LengthUnit::Micrometre).unwrap();
    assert_eq!(s.set_cell_content("cell1", "h1", &g, "u8").unwrap(), None);
    assert_eq!(s.set_cell_content("cell1", "h1", &g, "u8").unwrap(), None);
    assert_eq!(
        s.set_cell_content("cell1", "h2", &g, "u8").unwrap(),
        Some("h1".into())
    );
    assert_eq!(
        s.cell("cell1").unwrap().unwrap().content_hash.as_deref(),
        Some("h2")
    );
}

#[test]
fn progress_lists_who_did_what() {
    let (s, alice) = store_with_cell();
    s.upsert_cell("cell2", "cell2.nii").unwrap();
    let bob = s.ensure_user("bob").unwrap();
    s.add_contour(&key(&alice, 1, 3), square(1.0), None)
        .unwrap();
    s.add_contour(&key(&alice, 1, 4), square(1.0), None)
        .unwrap();
    s.set_status("cell1", alice.id, CellStatus::Done).unwrap();
    s.add_time("cell2", bob.id, 30.0).unwrap();
    let all = s.progress(None).unwrap();
    assert_eq!(
        all.iter()
            .map(|p| (
                p.cell.as_str(),
                p.user.as_str(),
                p.status,
                p.seconds,
                p.contours
            ))
            .collect::<Vec<_>>(),
        [
            ("cell1", "alice", CellStatus::Done, 0.0, 2),
            ("cell2", "bob", CellStatus::NotStarted, 30.0, 0),
        ]
    );
    assert_eq!(s.progress(Some(bob.id)).unwrap().len(), 1);
}

#[test]
fn foreign_keys_hold_and_checkpoints_run_in_the_background() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("db.sqlite");
    let s = Store::open(&path).unwrap();
    s.upsert_cell("cell1", "cell1.nii").unwrap();
    let u = s.ensure_user("alice").unwrap();
    {
        let conn = s.lock();
        let fk: i64 = conn
            .query_row("PRAGMA foreign_keys", [], |r| r.get(0))
            .unwrap();
        assert_eq!(fk, 1);
        let orphan = conn.execute(
            "INSERT INTO contours (cell, user_id, label, axis, slice, points, tool, created, updated) \
             VALUES ('no such cell', ?1, 1, 'z', 0, '[]', 'pen', '', '')",
            [u.id],
        );
        assert!(orphan.is_err());
    }
    let size = || std::fs::metadata(&path).unwrap().len();
    let before = size();
    for k in 0..200 {
        s.add_contour(&key(&u, 1, k), square(1.0), None).unwrap();
    }
    // Commits only append to the WAL; the checkpoint thread copies them into
    // the database file within a period or two.
    let deadline = std::time::Instant::now() + Duration::from_secs(10);
    while size() == before && std::time::Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(size() > before, "no checkpoint within 10 s");
    drop(s);
    assert!(
        !dir.path().join("db.sqlite-wal").exists()
            || std::fs::metadata(dir.path().join("db.sqlite-wal"))
                .unwrap()
                .len()
                == 0
    );
}
