//! Contours: closed polylines traced on one slice.
//!
//! A contour is a closed polyline of `(u, v)` points in continuous pixel
//! units on slice `(axis, index)`: pixel `(a, b)` covers `[a, a+1) x [b, b+1)`
//! and its centre is `(a + 0.5, b + 0.5)`. The last point connects back to the
//! first (it is not repeated). A pixel is inside when its centre is inside by
//! the even-odd rule; several contours of one label on one slice are united.
use crate::SliceRef;
use serde::{Deserialize, Serialize};

/// One traced contour with its provenance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contour {
    /// The slice it was drawn on.
    pub slice: SliceRef,
    /// Label (1..=65535) of the structure traced.
    pub label: u16,
    /// Vertices `(u, v)` in continuous pixel units; closed implicitly.
    pub points: Vec<[f64; 2]>,
    /// Who traced it.
    pub author: String,
    /// When it was drawn, RFC 3339 (UTC).
    pub created: String,
    /// Pen pressure per point in 0..=1, when the device reported it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure: Option<Vec<f32>>,
    /// Milliseconds since the stroke began, per point, when recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub times_ms: Option<Vec<f64>>,
    /// The drawing tool ("pen", "mouse", "touch", "import", ...), when known:
    /// tracing precision differs between devices, so studies compare them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<String>,
}

impl Contour {
    /// A contour without timing, pressure or tool (e.g. one derived from a mask),
    /// so callers need not list every optional field.
    pub fn new(
        slice: SliceRef,
        label: u16,
        points: Vec<[f64; 2]>,
        author: impl Into<String>,
        created: impl Into<String>,
    ) -> Contour {
        Contour {
            slice,
            label,
            points,
            author: author.into(),
            created: created.into(),
            pressure: None,
            times_ms: None,
            tool: None,
        }
    }
}
