-- 2: the change log and the audit log record what changed, not the slice.
--
-- Version 1 stored the whole state of a slice (every contour with its points)
-- before and after each change, in both `changes` and `audit`: a write on a
-- slice of n contours cost 4n contours of storage, so the database grew with
-- the square of the tracing. From version 2 on:
--
-- * an id names one contour content forever: ids are AUTOINCREMENT (never
--   reused) and a trigger now refuses to update a contour row.
-- * `contour_archive` holds, once, the content of every contour taken off
--   its slice (deleted, replaced, cleared, undone); live contours are only in
--   `contours`. Triggers make the archive append-only like the audit log.
-- * `changes` keeps one row per change (slice, drawn-empty mark before and
--   after, undone flag) and `change_contours` the ids it added and removed;
--   undo and redo replay these deltas.
-- * an audit entry of a contour change names the change, the slice and the
--   ids added and removed (their content is in `contours` or `contour_archive`).
--
-- Existing data is converted, not dropped: every contour that the old change
-- log or the old audit details hold and that is no longer live is archived;
-- old changes become deltas (undo/redo keep working across the upgrade); old
-- audit details are rewritten to the new, lossless form (the content they
-- carried is in `contours` or the archive). The append-only triggers of the
-- audit log are lifted for this rewrite only. The program runs VACUUM
-- afterwards to return the freed space to the file system.

CREATE TABLE contour_archive (
    id INTEGER PRIMARY KEY,
    cell TEXT NOT NULL,
    user_id INTEGER NOT NULL,
    label INTEGER NOT NULL,
    axis TEXT NOT NULL,
    slice INTEGER NOT NULL,
    points TEXT NOT NULL,
    pressure TEXT,
    times_ms TEXT,
    duration_ms REAL,
    tool TEXT NOT NULL,
    client_id TEXT,
    created TEXT NOT NULL,
    updated TEXT NOT NULL
);
CREATE TRIGGER contour_archive_no_update BEFORE UPDATE ON contour_archive
    BEGIN SELECT RAISE(ABORT, 'archived contours are immutable'); END;
CREATE TRIGGER contour_archive_no_delete BEFORE DELETE ON contour_archive
    BEGIN SELECT RAISE(ABORT, 'archived contours are immutable'); END;
CREATE TRIGGER contours_no_update BEFORE UPDATE ON contours
    BEGIN SELECT RAISE(ABORT, 'a contour is replaced, never updated in place'); END;

-- Every contour of every slice state held by the old change log and audit log,
-- with the slice it was on (version 1 serialised a contour as JSON, without
-- its user id, which is the row's).
CREATE TEMP TABLE v1_states AS
SELECT 'change' AS src, c.id AS row_id, c.cell AS cell, c.user_id AS user_id,
       c.label AS label, c.axis AS axis, c.slice AS slice, 0 AS side, j.value AS contour
FROM changes c, json_each(c.before, '$.contours') j
UNION ALL
SELECT 'change', c.id, c.cell, c.user_id, c.label, c.axis, c.slice, 1, j.value
FROM changes c, json_each(c.after, '$.contours') j
UNION ALL
SELECT 'audit', a.id, a.cell, a.user_id, json_extract(a.detail, '$.label'),
       json_extract(a.detail, '$.axis'), json_extract(a.detail, '$.index'), 0, j.value
FROM audit a, json_each(a.detail, '$.before.contours') j
WHERE json_type(a.detail, '$.before') = 'object'
UNION ALL
SELECT 'audit', a.id, a.cell, a.user_id, json_extract(a.detail, '$.label'),
       json_extract(a.detail, '$.axis'), json_extract(a.detail, '$.index'), 1, j.value
FROM audit a, json_each(a.detail, '$.after.contours') j
WHERE json_type(a.detail, '$.after') = 'object';

INSERT OR IGNORE INTO contour_archive
SELECT json_extract(contour, '$.id'), cell, user_id, label, axis, slice,
       json_extract(contour, '$.points'), json_extract(contour, '$.pressure'),
       json_extract(contour, '$.times_ms'), json_extract(contour, '$.duration_ms'),
       json_extract(contour, '$.tool'), json_extract(contour, '$.client_id'),
       json_extract(contour, '$.created'), json_extract(contour, '$.updated')
FROM v1_states
WHERE json_extract(contour, '$.id') NOT IN (SELECT id FROM contours);

-- What each old change or audit entry did: a contour in only one of the two
-- states was added (after) or removed (before).
CREATE TEMP TABLE v1_deltas AS
SELECT src, row_id, json_extract(contour, '$.id') AS contour_id, MAX(side) AS added
FROM v1_states
GROUP BY src, row_id, json_extract(contour, '$.id')
HAVING COUNT(*) = 1;
CREATE INDEX temp.v1_deltas_by_row ON v1_deltas (src, row_id, added, contour_id);
DROP TABLE v1_states;

DROP INDEX changes_by_user;
ALTER TABLE changes RENAME TO changes_v1;
CREATE TABLE changes (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    cell TEXT NOT NULL REFERENCES cells(id),
    user_id INTEGER NOT NULL REFERENCES users(id),
    label INTEGER NOT NULL,
    axis TEXT NOT NULL,
    slice INTEGER NOT NULL,
    empty_before INTEGER NOT NULL CHECK (empty_before IN (0, 1)),
    empty_after INTEGER NOT NULL CHECK (empty_after IN (0, 1)),
    undone INTEGER NOT NULL DEFAULT 0
);
CREATE INDEX changes_by_user ON changes (cell, user_id, undone, id);
CREATE TABLE change_contours (
    change_id INTEGER NOT NULL REFERENCES changes(id) ON DELETE CASCADE,
    contour_id INTEGER NOT NULL,
    added INTEGER NOT NULL CHECK (added IN (0, 1)),
    PRIMARY KEY (change_id, contour_id)
) WITHOUT ROWID;

INSERT INTO changes (id, cell, user_id, label, axis, slice, empty_before, empty_after, undone)
SELECT id, cell, user_id, label, axis, slice,
       COALESCE(json_extract(before, '$.empty'), 0), COALESCE(json_extract(after, '$.empty'), 0),
       undone
FROM changes_v1;
INSERT INTO change_contours (change_id, contour_id, added)
SELECT row_id, contour_id, added FROM v1_deltas WHERE src = 'change';
DROP TABLE changes_v1;

DROP TRIGGER audit_no_update;
UPDATE audit SET detail = json_object(
    'change', json_extract(detail, '$.change'),
    'label', json_extract(detail, '$.label'),
    'axis', json_extract(detail, '$.axis'),
    'index', json_extract(detail, '$.index'),
    'added', (SELECT json_group_array(contour_id) FROM (
        SELECT contour_id FROM v1_deltas d
        WHERE d.src = 'audit' AND d.row_id = audit.id AND d.added = 1 ORDER BY contour_id)),
    'removed', (SELECT json_group_array(contour_id) FROM (
        SELECT contour_id FROM v1_deltas d
        WHERE d.src = 'audit' AND d.row_id = audit.id AND d.added = 0 ORDER BY contour_id)),
    'empty_before', json(CASE WHEN json_extract(detail, '$.before.empty') THEN 'true' ELSE 'false' END),
    'empty_after', json(CASE WHEN json_extract(detail, '$.after.empty') THEN 'true' ELSE 'false' END)
)
WHERE json_type(detail, '$.before') = 'object' AND json_type(detail, '$.after') = 'object';
CREATE TRIGGER audit_no_update BEFORE UPDATE ON audit
    BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
DROP TABLE v1_deltas;
