//! The records the database stores and returns.
use interslice_core::{Axis, Contour};
use serde::{Deserialize, Serialize};

/// What a user may do: tracers read and write their own tracings, reviewers
/// also read everyone's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// Traces cells; sees only their own tracings.
    Tracer,
    /// Traces cells and reads every user's tracings.
    Reviewer,
}

impl Role {
    /// The name stored in the database and shown in the API.
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Tracer => "tracer",
            Role::Reviewer => "reviewer",
        }
    }

    /// Parse "tracer" or "reviewer".
    pub fn parse(s: &str) -> Option<Role> {
        match s {
            "tracer" => Some(Role::Tracer),
            "reviewer" => Some(Role::Reviewer),
            _ => None,
        }
    }
}

/// A user account.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct User {
    /// Database id.
    pub id: i64,
    /// Unique name, stored with every tracing.
    pub name: String,
    /// Tracer or reviewer.
    pub role: Role,
    /// Whether a password is set (required on non-loopback servers).
    pub has_password: bool,
}

/// A cell registered from the project folder.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CellRecord {
    /// URL-safe id (never a path).
    pub id: String,
    /// Path relative to the project folder.
    pub path: String,
    /// Content hash of the file(s), once computed.
    pub content_hash: Option<String>,
    /// Geometry as JSON, once the volume was read.
    pub geometry: Option<String>,
    /// Voxel type, once the volume was read.
    pub dtype: Option<String>,
}

/// A label of the project (a traced structure).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Label {
    /// The voxel value in label volumes (1..=65535).
    pub id: u16,
    /// Display name.
    pub name: String,
    /// `#rrggbb`.
    pub color: String,
}

/// The tracing status of a cell for one user.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CellStatus {
    /// Nothing traced yet.
    NotStarted,
    /// Tracing has begun.
    InProgress,
    /// The user finished the cell (hidden from their queue).
    Done,
}

impl CellStatus {
    /// The name stored and shown.
    pub fn as_str(self) -> &'static str {
        match self {
            CellStatus::NotStarted => "not_started",
            CellStatus::InProgress => "in_progress",
            CellStatus::Done => "done",
        }
    }

    /// Parse a stored name.
    pub fn parse(s: &str) -> Option<CellStatus> {
        match s {
            "not_started" => Some(CellStatus::NotStarted),
            "in_progress" => Some(CellStatus::InProgress),
            "done" => Some(CellStatus::Done),
            _ => None,
        }
    }
}

/// A contour as the client sends it (no id, author or time stamps yet).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct NewContour {
    /// Closed polyline of `(u, v)` points, at least 3, finite.
    pub points: Vec<[f64; 2]>,
    /// Pen pressure per point (same length as `points`).
    #[serde(default)]
    pub pressure: Option<Vec<f32>>,
    /// Milliseconds since the stroke began, per point (same length as `points`).
    #[serde(default)]
    pub times_ms: Option<Vec<f64>>,
    /// The drawing tool ("pen", "mouse", "polygon", ...).
    #[serde(default)]
    pub tool: Option<String>,
    /// Time spent drawing it, measured by the client (default: the last
    /// per-point time, if any).
    #[serde(default)]
    pub duration_ms: Option<f64>,
}

/// A stored contour: the contour as traced (its slice, label, points,
/// author, creation time, pressure, timing and tool, which is always set
/// here) and what the database keeps beside it.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredContour {
    /// Database id.
    pub id: i64,
    /// Cell id.
    pub cell: String,
    /// The contour.
    pub contour: Contour,
    /// Time spent drawing it (the last per-point time), if recorded.
    pub duration_ms: Option<f64>,
    /// The author's user id.
    pub user_id: i64,
    /// The client's idempotency key, if given.
    pub client_id: Option<String>,
    /// When it last changed (RFC 3339).
    pub updated: String,
}

/// The API's (and the change log's) flat form: `{"id", "cell", "label",
/// "axis", "index", "points", "pressure"?, "times_ms"?, "duration_ms"?,
/// "tool", "author", "client_id"?, "created", "updated"}`. The web client and
/// stored history read this shape, so it is written out here rather than
/// derived from the nested [`Contour`].
impl Serialize for StoredContour {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        fn optional<M: SerializeStruct, T: Serialize>(
            m: &mut M,
            key: &'static str,
            v: &Option<T>,
        ) -> Result<(), M::Error> {
            match v {
                Some(v) => m.serialize_field(key, v),
                None => m.skip_field(key),
            }
        }
        let c = &self.contour;
        let mut m = s.serialize_struct("StoredContour", 14)?;
        m.serialize_field("id", &self.id)?;
        m.serialize_field("cell", &self.cell)?;
        m.serialize_field("label", &c.label)?;
        m.serialize_field("axis", &c.slice.axis)?;
        m.serialize_field("index", &c.slice.index)?;
        m.serialize_field("points", &c.points)?;
        optional(&mut m, "pressure", &c.pressure)?;
        optional(&mut m, "times_ms", &c.times_ms)?;
        optional(&mut m, "duration_ms", &self.duration_ms)?;
        m.serialize_field("tool", c.tool.as_deref().unwrap_or(DEFAULT_TOOL))?;
        m.serialize_field("author", &c.author)?;
        optional(&mut m, "client_id", &self.client_id)?;
        m.serialize_field("created", &c.created)?;
        m.serialize_field("updated", &self.updated)?;
        m.end()
    }
}

/// The tool of a contour whose client named none.
pub const DEFAULT_TOOL: &str = "pen";

/// Which contours to list: one cell and one author, optionally narrowed.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ContourQuery {
    /// Cell id.
    pub cell: String,
    /// Author's user id.
    pub user_id: i64,
    /// Only this axis.
    pub axis: Option<Axis>,
    /// Only this slice index (with or without `axis`).
    pub index: Option<usize>,
    /// Only this label.
    pub label: Option<u16>,
}

/// Where a change happens: one label on one slice of one cell, by one user.
#[derive(Debug, Clone, PartialEq)]
pub struct SliceKey {
    /// Cell id.
    pub cell: String,
    /// Author's user id.
    pub user_id: i64,
    /// Label id.
    pub label: u16,
    /// Slice axis.
    pub axis: Axis,
    /// Slice index.
    pub index: usize,
}

/// A drawn slice of one label: either it has contours or it was marked empty.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct DrawnSlice {
    /// Slice index.
    pub index: usize,
    /// True when drawn with no contour (a known-empty slice).
    pub empty: bool,
}

/// What undo or redo changed, if anything.
#[derive(Debug, Clone, PartialEq)]
pub struct UndoOutcome {
    /// Whether anything was undone/redone.
    pub changed: bool,
    /// The slice it touched.
    pub slice: Option<(u16, Axis, usize)>,
}

/// Metadata of a stored interpolation result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ResultMeta {
    /// Database id.
    pub id: i64,
    /// Cell id.
    pub cell: String,
    /// Author's user id.
    pub user_id: i64,
    /// Label id.
    pub label: u16,
    /// Axis of the drawn slices.
    pub axis: Axis,
    /// Interpolation method.
    pub method: String,
    /// Foreground voxels.
    pub voxels: u64,
    /// When computed.
    pub created: String,
}

/// Metadata of a stored automated segmentation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentationMeta {
    /// Database id.
    pub id: i64,
    /// Cell id.
    pub cell: String,
    /// Display name.
    pub name: String,
    /// Method ("otsu", "rosin", ...).
    pub method: String,
    /// Parameters as JSON.
    pub params: serde_json::Value,
    /// When computed.
    pub created: String,
}

/// A rating of an automated segmentation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rating {
    /// Database id.
    pub id: i64,
    /// Cell id.
    pub cell: String,
    /// Who rated.
    pub user: String,
    /// The segmentation rated (its id in the API).
    pub segmentation: String,
    /// 1..=5.
    pub score: u8,
    /// Free text.
    pub comment: String,
    /// When rated.
    pub created: String,
}

/// One entry of the append-only audit log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AuditEntry {
    /// Sequence number.
    pub id: i64,
    /// When.
    pub at: String,
    /// Who (user name), if a user did it.
    pub user: Option<String>,
    /// Which cell, if any.
    pub cell: Option<String>,
    /// What ("contour.add", "slice.replace", "undo", ...).
    pub action: String,
    /// Details as JSON.
    pub detail: serde_json::Value,
}

/// Progress of one user on one cell in a tracing campaign.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Progress {
    /// Cell id.
    pub cell: String,
    /// User name.
    pub user: String,
    /// The user's status of the cell.
    pub status: CellStatus,
    /// Seconds the user spent tracing it.
    pub seconds: f64,
    /// Contours the user has on it.
    pub contours: u64,
}

/// The space a database takes on disk.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SpaceUsage {
    /// Pages of the database (its file size once the WAL is checkpointed).
    pub database_bytes: u64,
    /// Pages of the `contours` table alone (the live tracing).
    pub contours_bytes: u64,
    /// The write-ahead log file (0 in memory).
    pub wal_bytes: u64,
    /// Every table and index with its pages in bytes, largest first: where
    /// the space goes.
    pub by_object: Vec<(String, u64)>,
}
