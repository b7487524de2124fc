//! The change log and the audit log: their cost per write, exact undo/redo,
//! a complete audit trail, the conversion of version-1 history and the WAL
//! bound.
use super::fixtures::*;
use super::*;
use crate::model::*;
use std::collections::{BTreeMap, BTreeSet};

fn snapshot(s: &Store, u: &User) -> (Vec<StoredContour>, Vec<Vec<DrawnSlice>>) {
    let q = ContourQuery {
        cell: "cell1".into(),
        user_id: u.id,
        ..Default::default()
    };
    let drawn = (1..=2)
        .map(|l| s.drawn("cell1", u.id, l, Axis::Z).unwrap())
        .collect();
    (s.contours(&q).unwrap(), drawn)
}

/// A deterministic sequence of numbers (a 64-bit LCG): the tests need
/// varied operations, not statistical quality.
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) % n
    }
}

/// One random write of alice on labels 1–2, slices 0–2.
fn random_write(s: &Store, u: &User, rng: &mut Lcg, step: usize) {
    let k = key(u, 1 + rng.below(2) as u16, rng.below(3) as usize);
    let x = step as f64;
    match rng.below(10) {
        0..=4 => {
            s.add_contour(&k, square(x), None).unwrap();
        }
        5 | 6 => {
            let on_slice = s
                .contours(&ContourQuery {
                    cell: "cell1".into(),
                    user_id: u.id,
                    axis: Some(Axis::Z),
                    index: Some(k.index),
                    label: Some(k.label),
                })
                .unwrap();
            match on_slice.first() {
                Some(c) => s.delete_contour("cell1", u.id, c.id).unwrap(),
                None => s.mark_empty(&k).unwrap(),
            }
        }
        7 | 8 => {
            let n = rng.below(3) as usize;
            s.replace_slice(&k, (0..n).map(|i| square(x + i as f64)).collect())
                .unwrap();
        }
        _ => s.mark_empty(&k).unwrap(),
    }
}

#[test]
fn bytes_per_write_do_not_grow_with_the_slice_or_its_history() {
    let (s, u) = store_with_cell();
    let bytes = |s: &Store| s.space().unwrap().database_bytes;
    // Writes of one stroke each: add a contour, then delete it again.
    let per_write = |k: &SliceKey, writes: usize| -> u64 {
        let before = bytes(&s);
        for i in 0..writes / 2 {
            let (c, _) = s.add_contour(k, square(i as f64), None).unwrap();
            s.delete_contour("cell1", u.id, c.id).unwrap();
        }
        (bytes(&s) - before) / writes as u64
    };
    s.add_contour(&key(&u, 1, 0), square(0.0), None).unwrap();
    let small = per_write(&key(&u, 1, 0), 60);
    // A slice of 1000 contours with a history of its own.
    let big = key(&u, 2, 0);
    s.replace_slice(&big, (0..1000).map(|i| square(i as f64)).collect())
        .unwrap();
    for _ in 0..2 {
        s.replace_slice(&big, (0..1000).map(|i| square(i as f64)).collect())
            .unwrap();
    }
    per_write(&big, 20);
    let large = per_write(&big, 60);
    eprintln!("bytes per write: {small} on a slice of 1 contour, {large} on one of 1000");
    assert!(
        small < 2048 && large <= small + small / 2 + 128,
        "a write on a slice of 1 contour took {small} bytes, on one of 1000 {large}"
    );
}

#[test]
fn undo_and_redo_replay_every_change_exactly() {
    let (s, u) = store_with_cell();
    let mut rng = Lcg(7);
    let mut states = vec![snapshot(&s, &u)];
    for step in 0..80 {
        random_write(&s, &u, &mut rng, step);
        states.push(snapshot(&s, &u));
    }
    // Back to the start, one change at a time, then forward again.
    for want in states.iter().rev().skip(1) {
        assert!(s.undo("cell1", u.id).unwrap().changed);
        assert_eq!(&snapshot(&s, &u), want);
    }
    assert!(!s.undo("cell1", u.id).unwrap().changed);
    for want in states.iter().skip(1) {
        assert!(s.redo("cell1", u.id).unwrap().changed);
        assert_eq!(&snapshot(&s, &u), want);
    }
    assert!(!s.redo("cell1", u.id).unwrap().changed);
    // Half-way back, a new write drops the rest of the redo stack.
    for _ in 0..40 {
        s.undo("cell1", u.id).unwrap();
    }
    assert_eq!(snapshot(&s, &u), states[40]);
    random_write(&s, &u, &mut rng, 1000);
    assert!(!s.redo("cell1", u.id).unwrap().changed);
    assert!(s.undo("cell1", u.id).unwrap().changed);
    assert_eq!(snapshot(&s, &u), states[40]);
}

#[test]
fn the_audit_log_replays_to_the_tracing() {
    let (s, u) = store_with_cell();
    let mut rng = Lcg(11);
    for step in 0..60 {
        random_write(&s, &u, &mut rng, step);
        if rng.below(4) == 0 {
            s.undo("cell1", u.id).unwrap();
        }
        if rng.below(6) == 0 {
            s.redo("cell1", u.id).unwrap();
        }
    }
    // Fold every logged change, oldest first, into live contour ids and
    // drawn-empty marks per slice.
    let mut log = s.audit_log(10_000).unwrap();
    log.reverse();
    let mut live: BTreeSet<i64> = BTreeSet::new();
    let mut empty: BTreeMap<(u64, String, u64), bool> = BTreeMap::new();
    let ids = |v: &serde_json::Value| -> Vec<i64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|i| i.as_i64().unwrap())
            .collect()
    };
    let mut changes = 0;
    for e in log.iter().filter(|e| e.detail.get("added").is_some()) {
        changes += 1;
        assert_eq!(
            (e.user.as_deref(), e.cell.as_deref()),
            (Some("alice"), Some("cell1"))
        );
        let d = &e.detail;
        let slice = (
            d["label"].as_u64().unwrap(),
            d["axis"].as_str().unwrap().to_string(),
            d["index"].as_u64().unwrap(),
        );
        assert_eq!(
            empty.get(&slice).copied().unwrap_or(false),
            d["empty_before"].as_bool().unwrap(),
            "{e:?}"
        );
        empty.insert(slice.clone(), d["empty_after"].as_bool().unwrap());
        for id in ids(&d["removed"]) {
            assert!(live.remove(&id), "{e:?} removes {id}, which is not there");
        }
        for id in ids(&d["added"]) {
            let c = s.archived_contour(id).unwrap().unwrap();
            assert_eq!(
                (c.contour.label as u64, c.contour.slice.index as u64),
                (slice.0, slice.2)
            );
            assert!(live.insert(id), "{e:?} adds {id} twice");
        }
    }
    assert!(changes > 60);
    let (contours, drawn) = snapshot(&s, &u);
    assert_eq!(live, contours.iter().map(|c| c.id).collect());
    for c in &contours {
        assert_eq!(&s.archived_contour(c.id).unwrap().unwrap(), c);
    }
    let logged_empty: BTreeSet<(u64, u64)> = empty
        .iter()
        .filter(|(_, e)| **e)
        .map(|((l, _, i), _)| (*l, *i))
        .collect();
    let stored_empty: BTreeSet<(u64, u64)> = drawn
        .iter()
        .enumerate()
        .flat_map(|(l, d)| {
            d.iter()
                .filter(|d| d.empty)
                .map(move |d| (l as u64 + 1, d.index as u64))
        })
        .collect();
    assert_eq!(logged_empty, stored_empty);
    // The archive is as append-only as the log.
    let conn = s.lock();
    assert!(conn.execute("DELETE FROM contour_archive", []).is_err());
    assert!(
        conn.execute("UPDATE contour_archive SET points = '[]'", [])
            .is_err()
    );
    // ... and a contour id names one content: rows are replaced, not updated.
    assert!(
        conn.execute("UPDATE contours SET points = '[]'", [])
            .is_err()
    );
}

/// A contour as version 1 serialised it in its change and audit logs.
fn v1_contour(id: i64, user: i64, x: f64, client_id: Option<&str>) -> StoredContour {
    StoredContour {
        id,
        cell: "cell1".into(),
        contour: interslice_core::Contour {
            slice: interslice_core::SliceRef {
                axis: Axis::Z,
                index: 0,
            },
            label: 1,
            points: vec![[x, x], [x + 4.5, x], [x + 4.5, x + 4.25]],
            author: "alice".into(),
            created: format!("2026-01-0{id}T00:00:00.000Z"),
            pressure: Some(vec![0.5, 0.25, 1.0]),
            times_ms: Some(vec![0.0, 10.5, 35.0]),
            tool: Some("pen".into()),
        },
        duration_ms: Some(35.0),
        user_id: user,
        client_id: client_id.map(str::to_string),
        updated: format!("2026-01-0{id}T00:00:00.000Z"),
    }
}

#[test]
fn version_1_history_is_converted_to_deltas() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("v1.sqlite");
    let (c1, c2);
    {
        // A version-1 database: alice added contours 1 and 2 on z=0, then
        // deleted 1; the change log and audit log hold whole slice states.
        let mut conn = Connection::open(&path).unwrap();
        let tx = conn.transaction().unwrap();
        tx.execute_batch(migrations::MIGRATIONS[0]).unwrap();
        tx.pragma_update(None, "user_version", 1).unwrap();
        tx.execute_batch(
            "INSERT INTO users (id, name, role, created) VALUES (1, 'alice', 'tracer', 'x'); \
             INSERT INTO cells (id, path, updated) VALUES ('cell1', 'cell1.nii', 'x');",
        )
        .unwrap();
        c1 = v1_contour(1, 1, 1.0, Some("stroke-1"));
        c2 = v1_contour(2, 1, 2.0, None);
        let j = |v: &serde_json::Value, k: &str| v.get(k).map(|x| x.to_string());
        let row = serde_json::to_value(&c2).unwrap();
        tx.execute(
            "INSERT INTO contours (id, cell, user_id, label, axis, slice, points, pressure, \
             times_ms, duration_ms, tool, client_id, created, updated) \
             VALUES (2, 'cell1', 1, 1, 'z', 0, ?1, ?2, ?3, 35.0, 'pen', NULL, ?4, ?4)",
            rusqlite::params![
                j(&row, "points"),
                j(&row, "pressure"),
                j(&row, "times_ms"),
                c2.contour.created
            ],
        )
        .unwrap();
        let state = |cs: &[&StoredContour]| serde_json::json!({"empty": false, "contours": cs});
        let history = [
            ("contour.add", state(&[]), state(&[&c1])),
            ("contour.add", state(&[&c1]), state(&[&c1, &c2])),
            ("contour.delete", state(&[&c1, &c2]), state(&[&c2])),
        ];
        for (n, (action, before, after)) in history.iter().enumerate() {
            tx.execute(
                "INSERT INTO changes (id, cell, user_id, label, axis, slice, before, after) \
                 VALUES (?1, 'cell1', 1, 1, 'z', 0, ?2, ?3)",
                rusqlite::params![n as i64 + 1, before.to_string(), after.to_string()],
            )
            .unwrap();
            let detail = serde_json::json!({"label": 1, "axis": "z", "index": 0,
                "before": before, "after": after});
            tx.execute(
                "INSERT INTO audit (at, user_id, cell, action, detail) \
                 VALUES ('t', 1, 'cell1', ?1, ?2)",
                rusqlite::params![action, detail.to_string()],
            )
            .unwrap();
        }
        tx.commit().unwrap();
    }
    let s = Store::open(&path).unwrap();
    assert_eq!(s.schema_version().unwrap(), migrations::latest_version());
    assert_eq!(s.integrity_check().unwrap(), "ok");
    let u = s.user("alice").unwrap().unwrap();
    let contours = |s: &Store| snapshot(s, &u).0;
    assert_eq!(contours(&s), vec![c2.clone()]);
    // Contour 1 lived only in the history; its content is archived.
    assert_eq!(s.archived_contour(1).unwrap().unwrap(), c1);
    // The audit entries name what changed instead of copying the slice.
    let log = s.audit_log(10).unwrap();
    let delta = |e: &AuditEntry| (e.detail["added"].clone(), e.detail["removed"].clone());
    assert_eq!(
        log.iter().map(delta).collect::<Vec<_>>(),
        [
            (serde_json::json!([]), serde_json::json!([1])),
            (serde_json::json!([2]), serde_json::json!([])),
            (serde_json::json!([1]), serde_json::json!([])),
        ]
    );
    assert!(log.iter().all(|e| e.detail.get("before").is_none()));
    // Undo walks the old history back exactly, redo forward again.
    s.undo("cell1", u.id).unwrap();
    assert_eq!(contours(&s), vec![c1.clone(), c2.clone()]);
    s.undo("cell1", u.id).unwrap();
    assert_eq!(contours(&s), vec![c1.clone()]);
    s.undo("cell1", u.id).unwrap();
    assert!(contours(&s).is_empty());
    assert!(!s.undo("cell1", u.id).unwrap().changed);
    for _ in 0..3 {
        s.redo("cell1", u.id).unwrap();
    }
    assert_eq!(contours(&s), vec![c2]);
    // New writes continue the ids.
    let (c3, _) = s.add_contour(&key(&u, 1, 0), square(3.0), None).unwrap();
    assert_eq!(c3.id, 3);
}

#[test]
fn the_wal_is_emptied_once_past_its_limit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("db.sqlite");
    let wal = dir.path().join("db.sqlite-wal");
    let limit = 256 << 10;
    let s = Store::open_with_wal_limit(&path, limit).unwrap();
    s.upsert_cell("cell1", "cell1.nii").unwrap();
    let u = s.ensure_user("alice").unwrap();
    // One transaction of a few MB: the WAL has to grow past the limit.
    let long = |x: f64| NewContour {
        points: (0..2000).map(|i| [x + i as f64 * 0.125, x]).collect(),
        pressure: None,
        times_ms: None,
        tool: None,
        duration_ms: None,
    };
    s.replace_slice(&key(&u, 1, 0), (0..40).map(|i| long(i as f64)).collect())
        .unwrap();
    let size = || std::fs::metadata(&wal).map_or(0, |m| m.len());
    let deadline = std::time::Instant::now() + Duration::from_secs(10);
    while size() > limit && std::time::Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(size() <= limit, "the WAL is {} bytes", size());
    assert!(s.space().unwrap().wal_bytes <= limit);
    assert_eq!(
        s.contours(&ContourQuery {
            cell: "cell1".into(),
            user_id: u.id,
            ..Default::default()
        })
        .unwrap()
        .len(),
        40
    );
}
