//! The contours file: every contour of one volume, as versioned JSON.
//!
//! `{"format": "interslice-contours", "version": 1, "geometry": {...},
//! "labels": [...], "contours": [...], "drawn_empty": [...]}`; the full
//! specification with an example is `docs/contours-format.md`. The file is
//! what a tracing session exports and what `interpolate`/`evaluate` pipelines
//! can re-import, so [`read`] validates everything a later step relies on
//! (known labels, slices in range, finite points) and fails with one line.
//!
//! [`write()`] lays the JSON out one label, contour or empty slice per line:
//! readable, diff-friendly, and byte-identical on a read/write round trip.
use crate::{Axis, Contour, CoreError, Geometry, LengthUnit, SliceRef};
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};

/// The value of the `"format"` key.
pub const FORMAT: &str = "interslice-contours";
/// The version this code reads and writes.
pub const VERSION: u32 = 1;

/// Longest contours file [`read`] accepts, in bytes (512 MiB): the parser
/// holds the whole file, so a bound on it bounds the memory of a read.
pub const MAX_FILE_BYTES: usize = 512 << 20;
/// Most contours a file may hold.
pub const MAX_CONTOURS: usize = 1_000_000;
/// Most points one contour may have.
pub const MAX_POINTS_PER_CONTOUR: usize = 1_000_000;
/// Most points all contours of a file may have together.
pub const MAX_POINTS: usize = 50_000_000;
/// Most slices a file may mark drawn-empty.
pub const MAX_DRAWN_EMPTY: usize = 1_000_000;
/// Most voxels the file's grid may have (2^31, what the volume readers
/// accept by default): rasterising the contours allocates the grid.
pub const MAX_VOXELS: u64 = 1 << 31;

/// A structure that can be traced: label id, display name and colour.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct LabelInfo {
    /// Label value (1..=65535) painted into label volumes.
    pub id: u16,
    /// Display name ("Cell", "Nucleus", ...).
    pub name: String,
    /// Display colour `#rrggbb`.
    pub color: String,
}

/// A slice drawn with no contour for a label: a known-empty slice, which
/// interpolation must keep empty (DESIGN.md).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DrawnEmpty {
    /// The slice.
    pub slice: SliceRef,
    /// The label known to be absent there.
    pub label: u16,
    /// Who marked it.
    pub author: String,
}

/// The contents of a contours file.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourFile {
    /// The grid the contours were drawn on. Only dims, spacing and unit are
    /// stored unless origin/direction differ from the defaults.
    pub geometry: Geometry,
    /// Every label a contour or an empty slice may use.
    pub labels: Vec<LabelInfo>,
    /// The contours, in file order.
    pub contours: Vec<Contour>,
    /// Slices drawn empty for a label.
    pub drawn_empty: Vec<DrawnEmpty>,
}

/// The labels of a new project: Cell 1, Nucleus 2, Nucleolus 1 = 3,
/// Nucleolus 2 = 4, Nucleolus 3 = 5 (as in the phantom).
pub fn default_labels() -> Vec<LabelInfo> {
    [
        (1, "Cell", "#2ca02c"),
        (2, "Nucleus", "#1f77b4"),
        (3, "Nucleolus 1", "#d62728"),
        (4, "Nucleolus 2", "#ff7f0e"),
        (5, "Nucleolus 3", "#9467bd"),
    ]
    .into_iter()
    .map(|(id, name, color)| LabelInfo {
        id,
        name: name.into(),
        color: color.into(),
    })
    .collect()
}

impl ContourFile {
    /// An empty file for `geometry` with the [`default_labels`].
    pub fn new(geometry: Geometry) -> ContourFile {
        ContourFile {
            geometry,
            labels: default_labels(),
            contours: Vec::new(),
            drawn_empty: Vec::new(),
        }
    }

    /// Check what [`read`] checks: valid geometry, unique labels 1..=65535
    /// with `#rrggbb` colours, every contour and empty slice on a known label
    /// and a slice in range, finite points, per-point arrays as long as the
    /// points, pressure in 0..=1, and no slice both drawn empty and traced
    /// for the same label by the same author.
    pub fn validate(&self) -> Result<(), CoreError> {
        self.geometry.validate()?;
        let voxels = self
            .geometry
            .dims
            .iter()
            .map(|&d| d as u64)
            .try_fold(1u64, |a, d| a.checked_mul(d))
            .unwrap_or(u64::MAX);
        if voxels > MAX_VOXELS {
            return Err(invalid(format!(
                "grid {:?} has more than {MAX_VOXELS} voxels",
                self.geometry.dims
            )));
        }
        if self.contours.len() > MAX_CONTOURS {
            return Err(invalid(format!(
                "{} contours (at most {MAX_CONTOURS})",
                self.contours.len()
            )));
        }
        if self.drawn_empty.len() > MAX_DRAWN_EMPTY {
            return Err(invalid(format!(
                "{} drawn-empty slices (at most {MAX_DRAWN_EMPTY})",
                self.drawn_empty.len()
            )));
        }
        let mut total = 0usize;
        for (n, c) in self.contours.iter().enumerate() {
            if c.points.len() > MAX_POINTS_PER_CONTOUR {
                return Err(invalid(format!(
                    "contour #{n} has {} points (at most {MAX_POINTS_PER_CONTOUR})",
                    c.points.len()
                )));
            }
            total += c.points.len();
        }
        if total > MAX_POINTS {
            return Err(invalid(format!(
                "{total} points in all (at most {MAX_POINTS})"
            )));
        }
        let d = self.geometry.direction;
        if d.iter().flatten().any(|x| !x.is_finite()) {
            return Err(invalid(format!("direction {d:?} is not finite")));
        }
        let mut ids = HashSet::new();
        for l in &self.labels {
            if l.id == 0 {
                return Err(invalid(format!(
                    "label '{}' has id 0 (0 is background)",
                    l.name
                )));
            }
            if !ids.insert(l.id) {
                return Err(invalid(format!("label id {} is listed twice", l.id)));
            }
            if !is_colour(&l.color) {
                return Err(invalid(format!(
                    "label {} has colour '{}' (expected #rrggbb)",
                    l.id, l.color
                )));
            }
        }
        let in_range = |s: SliceRef| -> Result<(), CoreError> {
            let len = self.geometry.dims[s.axis.dim()];
            if s.index >= len {
                return Err(CoreError::SliceOutOfRange {
                    axis: s.axis,
                    index: s.index,
                    len,
                });
            }
            Ok(())
        };
        // The label of a contour or a drawn-empty mark must be listed.
        let known = |label: u16, at: &dyn Fn() -> String| {
            if ids.contains(&label) {
                Ok(())
            } else {
                Err(invalid(format!(
                    "{}: label {label} is not in \"labels\"",
                    at()
                )))
            }
        };
        let mut traced: HashSet<(SliceRef, u16, &str)> = HashSet::new();
        for (n, c) in self.contours.iter().enumerate() {
            let at = || format!("contour #{n} (label {}, slice {})", c.label, c.slice);
            let per_point = |what: &str, len: usize| {
                if len == c.points.len() {
                    Ok(())
                } else {
                    Err(invalid(format!(
                        "{}: {len} {what} for {} points",
                        at(),
                        c.points.len()
                    )))
                }
            };
            known(c.label, &at)?;
            in_range(c.slice).map_err(|e| invalid(format!("{}: {e}", at())))?;
            if let Some(p) = c
                .points
                .iter()
                .position(|p| !(p[0].is_finite() && p[1].is_finite()))
            {
                return Err(invalid(format!("{}: point #{p} is not finite", at())));
            }
            if let Some(pr) = &c.pressure {
                per_point("pressure values", pr.len())?;
                if pr.iter().any(|p| !(0.0..=1.0).contains(p)) {
                    return Err(invalid(format!("{}: pressure outside 0..=1", at())));
                }
            }
            if let Some(t) = &c.times_ms {
                per_point("times", t.len())?;
                if t.iter().any(|t| !t.is_finite()) {
                    return Err(invalid(format!("{}: a time is not finite", at())));
                }
            }
            traced.insert((c.slice, c.label, c.author.as_str()));
        }
        for (n, e) in self.drawn_empty.iter().enumerate() {
            let at = || format!("drawn_empty #{n} (label {}, slice {})", e.label, e.slice);
            known(e.label, &at)?;
            in_range(e.slice).map_err(|err| invalid(format!("{}: {err}", at())))?;
            if traced.contains(&(e.slice, e.label, e.author.as_str())) {
                return Err(invalid(format!(
                    "{}: the slice also has a contour of this label by '{}'",
                    at(),
                    e.author
                )));
            }
        }
        Ok(())
    }

    /// A map from label id to its [`LabelInfo`].
    pub fn label_map(&self) -> HashMap<u16, &LabelInfo> {
        self.labels.iter().map(|l| (l.id, l)).collect()
    }
}

fn invalid(msg: String) -> CoreError {
    CoreError::Invalid(format!("contours file: {msg}"))
}

fn is_colour(s: &str) -> bool {
    s.len() == 7 && s.starts_with('#') && s[1..].chars().all(|c| c.is_ascii_hexdigit())
}

/// Only the keys that decide how to read the rest.
struct Header {
    format: Option<serde_json::Value>,
    version: Option<serde_json::Value>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WireGeometry {
    dims: [usize; 3],
    spacing: [f64; 3],
    unit: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    origin: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    direction: Option<[[f64; 3]; 3]>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WireContour {
    axis: Axis,
    index: usize,
    label: u16,
    author: String,
    created: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tool: Option<String>,
    points: Vec<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pressure: Option<Vec<f32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    times_ms: Option<Vec<f64>>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WireEmpty {
    axis: Axis,
    index: usize,
    label: u16,
    author: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Wire {
    #[allow(dead_code)]
    format: String,
    #[allow(dead_code)]
    version: u32,
    geometry: WireGeometry,
    labels: Vec<LabelInfo>,
    #[serde(default)]
    contours: Vec<WireContour>,
    #[serde(default)]
    drawn_empty: Vec<WireEmpty>,
}

/// Parse and validate a contours file.
///
/// Errors (one line each): a text longer than [`MAX_FILE_BYTES`], malformed
/// JSON (with line and column), a file of another format, a version other
/// than [`VERSION`], unknown keys, and everything [`ContourFile::validate`]
/// rejects (counts past [`MAX_CONTOURS`], [`MAX_POINTS_PER_CONTOUR`],
/// [`MAX_POINTS`], [`MAX_DRAWN_EMPTY`], a grid past [`MAX_VOXELS`]).
pub fn read(text: &str) -> Result<ContourFile, CoreError> {
    if text.len() > MAX_FILE_BYTES {
        return Err(invalid(format!(
            "file of {} bytes is larger than the {MAX_FILE_BYTES} bytes a contours file may have",
            text.len()
        )));
    }
    // A map first: a JSON array would otherwise fill the header by position.
    let mut header: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(text).map_err(|e| invalid(format!("malformed JSON: {e}")))?;
    let header = Header {
        format: header.remove("format"),
        version: header.remove("version"),
    };
    match header.format {
        Some(serde_json::Value::String(f)) if f == FORMAT => {}
        Some(f) => return Err(invalid(format!("\"format\" is {f}, expected \"{FORMAT}\""))),
        None => {
            return Err(invalid(format!(
                "no \"format\" key (expected \"{FORMAT}\")"
            )));
        }
    }
    match header.version {
        Some(v) if v.as_u64() == Some(VERSION as u64) => {}
        Some(v) => {
            return Err(invalid(format!(
                "unsupported version {v} (this version of interslice reads version {VERSION})"
            )));
        }
        None => return Err(invalid("no \"version\" key".into())),
    }
    let wire: Wire = serde_json::from_str(text).map_err(|e| invalid(e.to_string()))?;
    let g = wire.geometry;
    let unit =
        LengthUnit::parse(&g.unit).ok_or_else(|| invalid(format!("unknown unit '{}'", g.unit)))?;
    let geometry = Geometry {
        dims: g.dims,
        spacing: g.spacing,
        unit,
        origin: g.origin.unwrap_or([0.0; 3]),
        direction: g.direction.unwrap_or(crate::geometry::IDENTITY_DIRECTION),
    };
    geometry.validate().map_err(|e| invalid(e.to_string()))?;
    let file = ContourFile {
        geometry,
        labels: wire.labels,
        contours: wire
            .contours
            .into_iter()
            .map(|c| Contour {
                slice: SliceRef {
                    axis: c.axis,
                    index: c.index,
                },
                label: c.label,
                points: c.points,
                author: c.author,
                created: c.created,
                pressure: c.pressure,
                times_ms: c.times_ms,
                tool: c.tool,
            })
            .collect(),
        drawn_empty: wire
            .drawn_empty
            .into_iter()
            .map(|e| DrawnEmpty {
                slice: SliceRef {
                    axis: e.axis,
                    index: e.index,
                },
                label: e.label,
                author: e.author,
            })
            .collect(),
    };
    file.validate()?;
    Ok(file)
}

/// Validate and serialise a contours file (UTF-8 JSON ending in a newline).
///
/// Layout: top-level keys on their own lines, then one label, one contour,
/// one empty slice per line; numbers in their shortest exact form, so
/// `write(&read(text)?)` returns `text` for any file `write` produced.
pub fn write(file: &ContourFile) -> Result<String, CoreError> {
    file.validate()?;
    let g = &file.geometry;
    let default_origin = g.origin == [0.0; 3];
    let default_dir = g.direction == crate::geometry::IDENTITY_DIRECTION;
    let geometry = WireGeometry {
        dims: g.dims,
        spacing: g.spacing,
        unit: g.unit.ascii().into(),
        origin: (!default_origin).then_some(g.origin),
        direction: (!default_dir).then_some(g.direction),
    };
    let mut out = String::new();
    out.push_str("{\n");
    out.push_str(&format!("  \"format\": \"{FORMAT}\",\n"));
    out.push_str(&format!("  \"version\": {VERSION},\n"));
    out.push_str(&format!("  \"geometry\": {},\n", js(&geometry)?));
    let labels: Result<Vec<String>, CoreError> = file.labels.iter().map(js).collect();
    push_list(&mut out, "labels", &labels?, true);
    let contours = js_all(file.contours.iter().map(|c| WireContour {
        axis: c.slice.axis,
        index: c.slice.index,
        label: c.label,
        author: c.author.clone(),
        created: c.created.clone(),
        tool: c.tool.clone(),
        points: c.points.clone(),
        pressure: c.pressure.clone(),
        times_ms: c.times_ms.clone(),
    }))?;
    push_list(&mut out, "contours", &contours, true);
    let empties = js_all(file.drawn_empty.iter().map(|e| WireEmpty {
        axis: e.slice.axis,
        index: e.slice.index,
        label: e.label,
        author: e.author.clone(),
    }))?;
    push_list(&mut out, "drawn_empty", &empties, false);
    out.push_str("}\n");
    Ok(out)
}

fn push_list(out: &mut String, key: &str, items: &[String], comma: bool) {
    let end = if comma { "," } else { "" };
    if items.is_empty() {
        out.push_str(&format!("  \"{key}\": []{end}\n"));
        return;
    }
    out.push_str(&format!("  \"{key}\": [\n"));
    for (n, it) in items.iter().enumerate() {
        let sep = if n + 1 < items.len() { "," } else { "" };
        out.push_str(&format!("    {it}{sep}\n"));
    }
    out.push_str(&format!("  ]{end}\n"));
}

/// Compact JSON of one item (one line of the file).
fn js<T: Serialize>(v: &T) -> Result<String, CoreError> {
    serde_json::to_string(v).map_err(|e| invalid(e.to_string()))
}

/// [`js`] of every item, in order.
fn js_all<T: Serialize>(items: impl Iterator<Item = T>) -> Result<Vec<String>, CoreError> {
    items.map(|x| js(&x)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOLDEN: &str = include_str!("../tests/data/contours_v1.json");

    #[test]
    fn golden_file_parses_to_exact_values_and_round_trips() {
        let f = read(GOLDEN).unwrap();
        assert_eq!(f.geometry.dims, [40, 32, 24]);
        assert_eq!(f.geometry.spacing, [0.35, 0.35, 0.35]);
        assert_eq!(f.geometry.unit, LengthUnit::Micrometre);
        assert_eq!(f.geometry.origin, [0.0; 3]);
        assert_eq!(f.labels.len(), 3);
        assert_eq!(
            f.labels[1],
            LabelInfo {
                id: 2,
                name: "Nucleus".into(),
                color: "#1f77b4".into()
            }
        );
        assert_eq!(f.contours.len(), 3);
        let c = &f.contours[0];
        assert_eq!(
            c.slice,
            SliceRef {
                axis: Axis::Z,
                index: 10
            }
        );
        assert_eq!(c.label, 1);
        assert_eq!(c.author, "alice");
        assert_eq!(c.created, "2024-05-02T09:14:03Z");
        assert_eq!(c.tool.as_deref(), Some("pen"));
        assert_eq!(
            c.points,
            vec![[10.5, 4.0], [30.25, 6.0], [28.0, 27.5], [8.125, 20.0]]
        );
        assert_eq!(c.pressure, Some(vec![0.5, 0.625, 0.75, 0.5]));
        assert_eq!(c.times_ms, Some(vec![0.0, 410.0, 905.5, 1320.0]));
        let c = &f.contours[2];
        assert_eq!(
            c.slice,
            SliceRef {
                axis: Axis::X,
                index: 20
            }
        );
        assert_eq!(c.label, 3);
        assert_eq!(
            (c.tool.as_ref(), c.pressure.as_ref(), c.times_ms.as_ref()),
            (None, None, None)
        );
        assert_eq!(
            f.drawn_empty,
            vec![DrawnEmpty {
                slice: SliceRef {
                    axis: Axis::Z,
                    index: 2
                },
                label: 2,
                author: "alice".into()
            }]
        );
        assert_eq!(write(&f).unwrap(), GOLDEN);
    }

    #[test]
    fn round_trip_keeps_every_value() {
        let mut g = Geometry::new(
            [5, 6, 7],
            [0.1, 0.2, 0.30000000000000004],
            LengthUnit::Millimetre,
        )
        .unwrap();
        g.origin = [1.5, -2.0, 1e-9];
        let mut f = ContourFile::new(g);
        let mut c = Contour::new(
            SliceRef {
                axis: Axis::Y,
                index: 5,
            },
            5,
            vec![[0.1, 0.2], [1.0 / 3.0, 5.0], [-1.0, 1e300]],
            "bob \"b\"",
            "t",
        );
        c.tool = Some("mouse".into());
        f.contours.push(c);
        f.drawn_empty.push(DrawnEmpty {
            slice: SliceRef {
                axis: Axis::X,
                index: 4,
            },
            label: 1,
            author: "bob".into(),
        });
        let text = write(&f).unwrap();
        let back = read(&text).unwrap();
        assert_eq!(back, f);
        assert_eq!(write(&back).unwrap(), text);
        // An empty file too.
        let e = ContourFile::new(Geometry::new([1, 1, 1], [1.0; 3], LengthUnit::Unknown).unwrap());
        assert_eq!(read(&write(&e).unwrap()).unwrap(), e);
    }

    fn err(text: &str) -> String {
        let e = read(text).unwrap_err().to_string();
        assert!(!e.contains('\n'), "one line: {e}");
        e
    }

    #[test]
    fn bad_files_are_one_line_errors() {
        assert!(err("{\"format\": ").contains("malformed JSON"));
        assert!(err("[1, 2]").contains("malformed JSON"));
        assert!(
            err("{\"format\": \"other\", \"version\": 1}")
                .contains("expected \"interslice-contours\"")
        );
        assert!(err("{\"version\": 1}").contains("no \"format\""));
        // (replace, with, the error names): one edit of the golden file each.
        let cases: [(&str, &str, &str); 15] = [
            ("\"version\": 1", "\"version\": 2", "unsupported version 2"),
            (
                "\"version\": 1",
                "\"version\": \"1\"",
                "unsupported version",
            ),
            // Slice out of range: z has 24 slices.
            (
                "\"axis\":\"z\",\"index\":10",
                "\"axis\":\"z\",\"index\":24",
                "out of range",
            ),
            // Unknown label.
            (
                "\"index\":20,\"label\":3",
                "\"index\":20,\"label\":9",
                "label 9 is not in",
            ),
            (
                "\"index\":2,\"label\":2",
                "\"index\":2,\"label\":7",
                "label 7 is not in",
            ),
            // Non-finite points cannot be written as JSON numbers: overflow and null.
            ("[10.5,4.0]", "[1e999,4.0]", "contours file"),
            ("[10.5,4.0]", "[null,4.0]", "contours file"),
            ("\"axis\":\"x\"", "\"axis\":\"w\"", "unknown variant"),
            ("\"unit\":\"um\"", "\"unit\":\"furlong\"", "unknown unit"),
            ("\"dims\":[40,32,24]", "\"dims\":[40,0,24]", "contain 0"),
            ("\"#1f77b4\"", "\"blue\"", "#rrggbb"),
            (
                "\"tool\":\"pen\"",
                "\"tool\":\"pen\",\"colour\":1",
                "unknown field",
            ),
            (
                "[0.5,0.625,0.75,0.5]",
                "[0.5,0.625,0.75]",
                "3 pressure values for 4 points",
            ),
            (
                "[0.5,0.625,0.75,0.5]",
                "[0.5,0.625,1.75,0.5]",
                "pressure outside",
            ),
            // Drawn empty where the same author traced the same label.
            (
                "\"index\":2,\"label\":2",
                "\"index\":12,\"label\":2",
                "also has a contour",
            ),
        ];
        for (from, to, says) in cases {
            assert!(GOLDEN.contains(from), "{from}");
            let e = err(&GOLDEN.replace(from, to));
            assert!(e.contains(says), "{from} -> {to}: {e}");
        }
    }

    /// A 4³ µm grid with one contour of label 1 on slice z = 0.
    fn one_contour_file(points: Vec<[f64; 2]>) -> ContourFile {
        let mut f =
            ContourFile::new(Geometry::new([4, 4, 4], [1.0; 3], LengthUnit::Micrometre).unwrap());
        f.contours.push(Contour::new(
            SliceRef {
                axis: Axis::Z,
                index: 0,
            },
            1,
            points,
            "a",
            "t",
        ));
        f
    }

    #[test]
    fn write_rejects_what_read_would_reject() {
        let mut f = one_contour_file(vec![[f64::NAN, 0.0]]);
        assert!(write(&f).unwrap_err().to_string().contains("not finite"));
        f.contours[0].points = vec![[0.0, 0.0]];
        f.contours[0].label = 42;
        assert!(write(&f).is_err());
        f.contours[0].label = 1;
        f.labels.push(LabelInfo {
            id: 1,
            name: "again".into(),
            color: "#000000".into(),
        });
        assert!(write(&f).unwrap_err().to_string().contains("twice"));
    }

    #[test]
    fn hostile_sizes_are_refused_before_use() {
        // A grid that rasterising would have to allocate: 2^33 voxels.
        let e = err(&GOLDEN.replace("\"dims\":[40,32,24]", "\"dims\":[2048,2048,2048]"));
        assert!(e.contains("more than 2147483648 voxels"), "{e}");
        // A direction with a non-finite entry.
        let g = GOLDEN.replace(
            "\"unit\":\"um\"",
            "\"unit\":\"um\",\"direction\":[[1,0,0],[0,1,0],[0,0,1e999]]",
        );
        assert!(err(&g).contains("contours file"), "{}", err(&g));
        // Too many points in one contour.
        let f = one_contour_file(vec![[1.0, 1.0]; MAX_POINTS_PER_CONTOUR + 1]);
        let e = f.validate().unwrap_err().to_string();
        assert!(e.contains("points (at most"), "{e}");
        // A text longer than the bound is refused before it is parsed.
        let long = " ".repeat(MAX_FILE_BYTES + 1);
        assert!(err(&long).contains("larger than"));
    }
}
