//! NRRD (`.nrrd` with attached data, `.nhdr` with a detached data file).
//!
//! The header is parsed here (no well-kept Rust crate reads NRRD). Read:
//! encodings `raw`, `gzip`/`gz` and `ascii`/`text`; anything else is refused
//! by name. Geometry: `space directions` give spacing (vector lengths) and
//! direction (unit vectors), `space origin` the origin; an RAS or LAS `space`
//! is turned into LPS (ITK's convention, like SimpleITK). Without `space`,
//! `spacings` (and optional `axis mins`) are used with identity direction.
//!
//! 3D Slicer segmentations (`.seg.nrrd`) are read as their labelmap: a 3D
//! file as is; a 4D file (first axis of kind `list`: one layer per entry)
//! has its layers merged using each segment's `SegmentN_LabelValue` and
//! `SegmentN_Layer` (see `merge_layers`). Other 4D files are refused.
//!
//! Write: `NRRD0004`, gzip, `space: left-posterior-superior`,
//! `space directions`, `space origin`, `space units`.
use crate::header::{self, num};
use crate::limits::{Loaded, ReadLimits, VolumeHeader, Want, try_vec};
use crate::raw::{self, Endian, RawType};
use crate::source::Source;
use crate::{Format, IoError};
use interslice_core::{AnyVolume, LengthUnit};
use std::collections::HashMap;
use std::io::{BufRead, Read, Write};
use std::path::{Path, PathBuf};

fn raw_type(path: &Path, s: &str) -> Result<RawType, IoError> {
    Ok(match s.trim() {
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => RawType::U8,
        "signed char" | "int8" | "int8_t" => RawType::I8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            RawType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => RawType::U16,
        "int" | "signed int" | "int32" | "int32_t" => RawType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => RawType::U32,
        "float" => RawType::F32,
        "double" => RawType::F64,
        other => {
            return Err(IoError::unsupported(
                path,
                format!("NRRD type '{other}' is not supported"),
            ));
        }
    })
}

fn type_name(t: RawType) -> &'static str {
    match t {
        RawType::U8 => "unsigned char",
        RawType::I8 => "signed char",
        RawType::U16 => "unsigned short",
        RawType::I16 => "short",
        RawType::U32 => "unsigned int",
        RawType::I32 => "int",
        RawType::F32 => "float",
        RawType::F64 => "double",
    }
}

/// Parse "(a,b,c)" into a vector, or None for "none".
fn vector(path: &Path, s: &str) -> Result<Option<[f64; 3]>, IoError> {
    let s = s.trim();
    if s == "none" {
        return Ok(None);
    }
    let inner = s
        .strip_prefix('(')
        .and_then(|x| x.strip_suffix(')'))
        .ok_or_else(|| IoError::invalid(path, format!("bad NRRD vector '{s}'")))?;
    let parts: Vec<f64> = inner
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| IoError::invalid(path, format!("bad NRRD vector '{s}'")))?;
    match parts.as_slice() {
        [a, b, c] => Ok(Some([*a, *b, *c])),
        _ => Err(IoError::unsupported(
            path,
            format!("NRRD vector '{s}' is not 3D"),
        )),
    }
}

/// Split "(a,b,c) none (d,e,f)" into its items.
fn vector_items(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut depth = 0;
    for ch in s.chars() {
        match ch {
            '(' => {
                depth += 1;
                cur.push(ch);
            }
            ')' => {
                depth -= 1;
                cur.push(ch);
            }
            c if c.is_whitespace() && depth == 0 => {
                if !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
            }
            c => cur.push(c),
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Strip the quotes of `"mm" "mm" "mm"`.
fn quoted_items(s: &str) -> Vec<String> {
    let items: Vec<String> = s
        .split('"')
        .map(str::trim)
        .filter(|x| !x.is_empty())
        .map(String::from)
        .collect();
    if items.is_empty() {
        s.split_whitespace().map(String::from).collect()
    } else {
        items
    }
}

/// Most layers a 3D Slicer segmentation may have (Slicer makes one per set
/// of overlapping segments: a handful).
const MAX_LAYERS: usize = 256;

/// The header fields (`name: value`, names lower-cased) and key/value pairs
/// (`key:=value`) after the magic line, up to the blank line that ends an
/// attached header (or the end of a detached one).
type HeaderFields = (HashMap<String, String>, HashMap<String, String>);

/// The magic line, then the fields and keys of the header.
fn read_header<R: BufRead + ?Sized>(
    path: &Path,
    r: &mut R,
    consumed: &mut usize,
) -> Result<HeaderFields, IoError> {
    let first = header::read_line(path, r, consumed)?.unwrap_or_default();
    if !first.starts_with("NRRD000") {
        return Err(IoError::invalid(
            path,
            "not a NRRD file (no NRRD000x magic line)",
        ));
    }
    read_fields(path, r, consumed)
}

fn read_fields<R: BufRead + ?Sized>(
    path: &Path,
    r: &mut R,
    consumed: &mut usize,
) -> Result<HeaderFields, IoError> {
    let mut fields: HashMap<String, String> = HashMap::new();
    let mut keys: HashMap<String, String> = HashMap::new();
    // A detached header may end at the end of the file, without a blank line.
    while let Some(line) = header::read_line(path, r, consumed)? {
        if line.is_empty() {
            break;
        }
        if line.starts_with('#') {
            continue;
        }
        if let Some((k, v)) = line.split_once(":=") {
            keys.insert(k.trim().to_string(), v.trim().to_string());
        } else if let Some((k, v)) = line.split_once(": ") {
            fields.insert(k.trim().to_ascii_lowercase(), v.trim().to_string());
        } else if let Some(k) = line.strip_suffix(':') {
            fields.insert(k.trim().to_ascii_lowercase(), String::new());
        } else {
            return Err(IoError::invalid(
                path,
                format!("bad NRRD header line '{line}'"),
            ));
        }
    }
    Ok((fields, keys))
}

/// The `key:=value` pairs of a NRRD header (3D Slicer keeps its segment
/// table there), without reading the data.
pub fn read_keys(path: &Path) -> Result<HashMap<String, String>, IoError> {
    let (mut r, _) = Source::file(path).open()?;
    let mut consumed = 0usize;
    Ok(read_header(path, &mut r, &mut consumed)?.1)
}

/// Read a NRRD file or bytes; a detached data file must be inside the
/// header's folder (see [`Source::data_file`]).
pub(crate) fn read(src: Source<'_>, limits: &ReadLimits, want: Want) -> Result<Loaded, IoError> {
    let path = src.name;
    let (mut r, total_len) = src.open()?;
    let mut consumed = 0usize;
    let (fields, keys) = read_header(path, &mut r, &mut consumed)?;
    let get = |k: &str| fields.get(k).map(String::as_str);
    let need = |k: &str| {
        get(k).ok_or_else(|| IoError::invalid(path, format!("NRRD header has no '{k}' field")))
    };

    let t = raw_type(path, need("type")?)?;
    let dimension: usize = need("dimension")?
        .parse()
        .map_err(|_| IoError::invalid(path, "bad NRRD 'dimension'"))?;
    let sizes: Vec<usize> = need("sizes")?
        .split_whitespace()
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| IoError::invalid(path, "bad NRRD 'sizes'"))?;
    if sizes.len() != dimension {
        return Err(IoError::invalid(
            path,
            format!(
                "NRRD 'sizes' has {} values for dimension {dimension}",
                sizes.len()
            ),
        ));
    }
    let kinds: Vec<String> = get("kinds")
        .map(|k| k.split_whitespace().map(str::to_ascii_lowercase).collect())
        .unwrap_or_default();
    // Which axes are spatial: a leading non-spatial axis of size 1 (a
    // single-layer Slicer segmentation, a 1-component list) is squeezed.
    let dir_items: Vec<String> = get("space directions")
        .map(vector_items)
        .unwrap_or_default();
    let first_is_list = dimension == 4
        && (kinds
            .first()
            .is_some_and(|k| !matches!(k.as_str(), "domain" | "space"))
            || dir_items.first().is_some_and(|d| d == "none"));
    let is_segmentation = keys.contains_key("Segment0_LabelValue")
        || keys.contains_key("Segment0_Layer")
        || keys.keys().any(|k| k.starts_with("Segmentation_"));
    let (skip, spatial, layers) = match dimension {
        1..=3 => (0usize, dimension, 1usize),
        4 if first_is_list => {
            if sizes[0] != 1 && !is_segmentation {
                return Err(IoError::unsupported(
                    path,
                    format!(
                        "a 4D NRRD with {} components per voxel is not supported",
                        sizes[0]
                    ),
                ));
            }
            if sizes[0] > MAX_LAYERS {
                return Err(IoError::unsupported(
                    path,
                    format!(
                        "a segmentation with {} layers is not supported (at most {MAX_LAYERS})",
                        sizes[0]
                    ),
                ));
            }
            (1, 3, sizes[0])
        }
        _ => {
            return Err(IoError::unsupported(
                path,
                format!("{dimension}D NRRD files are not supported (3D only)"),
            ));
        }
    };
    let mut dims = [1usize; 3];
    dims[..spatial].copy_from_slice(&sizes[skip..skip + spatial]);
    // All layers of a multi-layer segmentation are read at once, as if the
    // layer axis (the fastest) were part of x.
    let nbytes = dims
        .iter()
        .try_fold((layers * t.size()) as u64, |a, &d| a.checked_mul(d as u64))
        .unwrap_or(u64::MAX);
    limits.check(path, dims, nbytes)?;
    let nbytes = usize::try_from(nbytes)
        .map_err(|_| IoError::unsupported(path, format!("NRRD sizes {sizes:?} are too large")))?;

    let endian = match get("endian") {
        Some("big") => Endian::Big,
        Some("little") | None => Endian::Little,
        Some(other) => return Err(IoError::invalid(path, format!("bad NRRD endian '{other}'"))),
    };

    // Geometry.
    let space = get("space").map(str::to_ascii_lowercase);
    let units: Vec<String> = get("space units").map(quoted_items).unwrap_or_default();
    let unit = match units.first() {
        Some(u) => LengthUnit::parse(u).unwrap_or(LengthUnit::Unknown),
        None => LengthUnit::Millimetre,
    };
    let geometry = if let Some(space) = space.as_deref().or(get("space dimension").map(|_| "")) {
        let flips: [f64; 3] = match space {
            "right-anterior-superior" | "ras" => [-1.0, -1.0, 1.0],
            "left-anterior-superior" | "las" => [1.0, -1.0, 1.0],
            _ => [1.0; 3],
        };
        let items = &dir_items;
        if items.len() != dimension {
            return Err(IoError::invalid(
                path,
                format!(
                    "NRRD 'space directions' has {} items for dimension {dimension}",
                    items.len()
                ),
            ));
        }
        let mut axes = [[0.0; 3]; 3];
        for a in 0..3 {
            if a < spatial {
                let v = vector(path, &items[skip + a])?.ok_or_else(|| {
                    IoError::invalid(
                        path,
                        format!("space direction of axis {} is 'none'", skip + a),
                    )
                })?;
                axes[a] = [v[0] * flips[0], v[1] * flips[1], v[2] * flips[2]];
            } else {
                axes[a][a] = 1.0;
            }
        }
        let origin = match get("space origin") {
            Some(o) => {
                let v = vector(path, o)?.unwrap_or([0.0; 3]);
                [
                    v[0] * flips[0] + 0.0,
                    v[1] * flips[1] + 0.0,
                    v[2] * flips[2] + 0.0,
                ]
            }
            None => [0.0; 3],
        };
        header::geometry_from_axes(path, dims, axes, origin, unit)?
    } else {
        // No space: per-axis spacings (NaN for non-spatial axes).
        let mut axes = [[0.0; 3]; 3];
        // A per-axis number list; a missing or unreadable entry is NaN.
        let numbers = |key: &str| -> Vec<f64> {
            get(key).map_or_else(Vec::new, |s| {
                s.split_whitespace()
                    .map(|x| x.parse::<f64>().unwrap_or(f64::NAN))
                    .collect()
            })
        };
        let sp = numbers("spacings");
        let mins = numbers("axis mins");
        let mut origin = [0.0; 3];
        for a in 0..3 {
            // An axis the file has must have a positive spacing when
            // `spacings` is given; without `spacings` there is none (1).
            let s = match sp.get(skip + a) {
                Some(&s) if s.is_finite() && s > 0.0 => s,
                Some(&s) if a < spatial => {
                    return Err(IoError::invalid(
                        path,
                        format!(
                            "NRRD spacing of axis {} is {s}, not a positive number",
                            skip + a
                        ),
                    ));
                }
                _ => 1.0,
            };
            axes[a][a] = s;
            if let Some(m) = mins.get(skip + a).filter(|m| m.is_finite()) {
                origin[a] = *m;
            }
        }
        let unit = if units.is_empty() {
            LengthUnit::Unknown
        } else {
            unit
        };
        header::geometry_from_axes(path, dims, axes, origin, unit)?
    };

    let encoding_name = need("encoding")?.to_ascii_lowercase();
    let encoding = Encoding::parse(&encoding_name).ok_or_else(|| {
        IoError::unsupported(
            path,
            format!("NRRD encoding '{encoding_name}' is not supported (use raw, gzip or ascii)"),
        )
    })?;
    let byte_skip: i64 = match get("byte skip") {
        None => 0,
        Some(s) => match s.trim().parse::<i64>() {
            Ok(-1) if encoding == Encoding::Raw => -1,
            Ok(n) if n >= 0 => n,
            _ => Err(IoError::invalid(
                path,
                format!("bad NRRD 'byte skip' '{s}' (a count of bytes, or -1 for raw data)"),
            ))?,
        },
    };
    let line_skip: usize = match get("line skip") {
        None => 0,
        Some(s) => s
            .trim()
            .parse()
            .map_err(|_| IoError::invalid(path, format!("bad NRRD 'line skip' '{s}'")))?,
    };
    if encoding == Encoding::Gzip
        && (byte_skip as u64).saturating_add(nbytes as u64) > limits.max_bytes
    {
        return Err(IoError::unsupported(
            path,
            format!(
                "byte skip {byte_skip} and the voxel data are more than the {} bytes a read may decompress",
                limits.max_bytes
            ),
        ));
    }
    let data_file = get("data file").or(get("datafile")).map(str::trim);
    if let Some(f) = data_file
        && (f.starts_with("LIST") || f.split_whitespace().count() > 1)
    {
        return Err(IoError::unsupported(
            path,
            "NRRD with several data files is not supported",
        ));
    }
    if want == Want::Header {
        return Ok(Loaded::Header(VolumeHeader {
            format: if data_file.is_some() {
                Format::Nhdr
            } else {
                Format::Nrrd
            },
            geometry,
            stored_type: t,
            data_bytes: nbytes as u64,
        }));
    }

    // The data stream: attached (rest of this file) or detached.
    let (data_path, mut reader, data_len): (Option<PathBuf>, Box<dyn BufRead>, u64) =
        match data_file {
            Some(f) => {
                let (p, reader, len) = src.data_file(f)?;
                (Some(p), reader, len)
            }
            None => (None, r, total_len.saturating_sub(consumed as u64)),
        };
    let data_name: &Path = data_path.as_deref().unwrap_or(path);
    let mut skipped = 0usize;
    for _ in 0..line_skip {
        if header::read_line(data_name, &mut reader, &mut skipped)?.is_none() {
            return Err(IoError::invalid(
                data_name,
                "file is truncated (line skip past the end)",
            ));
        }
    }
    let bytes = match encoding {
        Encoding::Raw => {
            let skip_bytes = if byte_skip == -1 {
                data_len
                    .saturating_sub(skipped as u64)
                    .checked_sub(nbytes as u64)
                    .ok_or_else(|| {
                        IoError::invalid(
                            data_name,
                            format!("file is truncated: dims {dims:?} need {nbytes} bytes of data"),
                        )
                    })?
            } else {
                byte_skip.max(0) as u64
            };
            if data_len < skipped as u64 + skip_bytes + nbytes as u64 {
                return Err(IoError::invalid(
                    data_name,
                    format!(
                        "file is truncated: dims {dims:?} need {nbytes} bytes of data, {} are there",
                        data_len.saturating_sub(skipped as u64 + skip_bytes)
                    ),
                ));
            }
            std::io::copy(&mut (&mut reader).take(skip_bytes), &mut std::io::sink())
                .map_err(|e| IoError::read(data_name, e))?;
            raw::read_data(data_name, &mut reader, nbytes)?
        }
        Encoding::Gzip => {
            let mut dec = flate2::read::MultiGzDecoder::new(reader);
            if byte_skip > 0 {
                std::io::copy(&mut (&mut dec).take(byte_skip as u64), &mut std::io::sink())
                    .map_err(|e| IoError::read(data_name, e))?;
            }
            raw::read_data(data_name, &mut dec, nbytes)?
        }
        Encoding::Ascii => {
            // Each value takes at least two characters: bound the text read.
            let limit = ((geometry.len() * layers) as u64).saturating_mul(64);
            let mut text = String::new();
            reader
                .take(limit)
                .read_to_string(&mut text)
                .map_err(|e| IoError::read(data_name, e))?;
            ascii_to_bytes(data_name, &text, t, geometry.len() * layers)?
        }
    };
    let endian = if encoding == Encoding::Ascii {
        Endian::Little
    } else {
        endian
    };
    if layers == 1 {
        return raw::decode_volume(data_name, geometry, t, endian, &bytes).map(Loaded::Volume);
    }
    let mut wide = geometry.clone();
    wide.dims[0] *= layers;
    let stacked = raw::decode_volume(data_name, wide, t, endian, &bytes)?
        .to_labels()
        .map_err(|e| IoError::invalid(path, format!("segmentation layers: {e}")))?;
    merge_layers(path, &keys, layers, stacked.data(), geometry).map(Loaded::Volume)
}

/// The NRRD encodings read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Raw,
    Gzip,
    Ascii,
}

impl Encoding {
    /// The encoding of a (lower-case) `encoding:` field, if supported.
    fn parse(name: &str) -> Option<Encoding> {
        match name {
            "raw" => Some(Encoding::Raw),
            "gzip" | "gz" => Some(Encoding::Gzip),
            "ascii" | "text" | "txt" => Some(Encoding::Ascii),
            _ => None,
        }
    }
}

/// One segment of a 3D Slicer segmentation: the layer it lives in and its
/// value there.
struct Segment {
    layer: usize,
    value: u16,
}

/// The `SegmentN_LabelValue` / `SegmentN_Layer` keys of a 3D Slicer
/// segmentation, in segment order.
fn segments(path: &Path, keys: &HashMap<String, String>) -> Result<Vec<Segment>, IoError> {
    let mut out = Vec::new();
    for n in 0.. {
        let Some(value) = keys.get(&format!("Segment{n}_LabelValue")) else {
            break;
        };
        let value: u16 = value
            .trim()
            .parse()
            .map_err(|_| IoError::invalid(path, format!("bad Segment{n}_LabelValue '{value}'")))?;
        let layer: usize = match keys.get(&format!("Segment{n}_Layer")) {
            Some(l) => l
                .trim()
                .parse()
                .map_err(|_| IoError::invalid(path, format!("bad Segment{n}_Layer '{l}'")))?,
            None => 0,
        };
        out.push(Segment { layer, value });
    }
    Ok(out)
}

/// Merge the layers of a multi-layer 3D Slicer segmentation into one label
/// volume. A segment keeps its `LabelValue` when the label values of all
/// segments are distinct, otherwise segment N becomes label N + 1. Where
/// segments overlap, the one listed last wins (as in Slicer's export to a
/// labelmap).
fn merge_layers(
    path: &Path,
    keys: &HashMap<String, String>,
    layers: usize,
    stacked: &[u16],
    geometry: interslice_core::Geometry,
) -> Result<AnyVolume, IoError> {
    use rayon::prelude::*;
    let segs = segments(path, keys)?;
    if segs.is_empty() {
        return Err(IoError::invalid(
            path,
            format!("segmentation with {layers} layers has no Segment0_LabelValue key"),
        ));
    }
    if let Some(s) = segs.iter().find(|s| s.layer >= layers) {
        return Err(IoError::invalid(
            path,
            format!(
                "a segment is in layer {} but the file has {layers} layers",
                s.layer
            ),
        ));
    }
    let mut values: Vec<u16> = segs.iter().map(|s| s.value).collect();
    values.sort_unstable();
    let distinct = values.windows(2).all(|w| w[0] != w[1]);
    let out_label: Vec<u16> = segs
        .iter()
        .enumerate()
        .map(|(n, s)| if distinct { s.value } else { (n + 1) as u16 })
        .collect();
    // table[layer][value] = segment index + 1 (0: no segment).
    let mut table = vec![vec![0u32; 65536]; layers];
    for (n, s) in segs.iter().enumerate() {
        if s.value != 0 {
            table[s.layer][usize::from(s.value)] = n as u32 + 1;
        }
    }
    let merged: Result<Vec<u16>, (usize, u16)> = stacked
        .par_chunks_exact(layers)
        .map(|voxel| {
            let mut best = 0u32;
            for (l, &x) in voxel.iter().enumerate() {
                if x != 0 {
                    match table[l][usize::from(x)] {
                        0 => return Err((l, x)),
                        n => best = best.max(n),
                    }
                }
            }
            Ok(if best == 0 {
                0
            } else {
                out_label[best as usize - 1]
            })
        })
        .collect();
    let merged = merged.map_err(|(l, x)| {
        IoError::invalid(
            path,
            format!("layer {l} has value {x}, which no segment names"),
        )
    })?;
    let max = merged.par_iter().copied().max().unwrap_or(0);
    let bad = |e: interslice_core::CoreError| IoError::invalid(path, e.to_string());
    Ok(if max <= u16::from(u8::MAX) {
        AnyVolume::U8(
            interslice_core::Volume::from_vec(geometry, merged.iter().map(|&x| x as u8).collect())
                .map_err(bad)?,
        )
    } else {
        AnyVolume::U16(interslice_core::Volume::from_vec(geometry, merged).map_err(bad)?)
    })
}

fn ascii_to_bytes(path: &Path, text: &str, t: RawType, n: usize) -> Result<Vec<u8>, IoError> {
    // A value takes at least two characters (a digit and a separator): a
    // header that claims more values than the text can hold is refused
    // before the output is allocated.
    if n > text.len() / 2 + 1 {
        return Err(IoError::invalid(
            path,
            format!(
                "file is truncated: ASCII data of {} bytes cannot hold {n} values",
                text.len()
            ),
        ));
    }
    let mut out = try_vec(path, n * t.size())?;
    let mut count = 0usize;
    for tok in text.split_whitespace().take(n) {
        let x: f64 = tok
            .parse()
            .map_err(|_| IoError::invalid(path, format!("bad number '{tok}' in ASCII data")))?;
        let ok_int = |lo: f64, hi: f64| x.fract() == 0.0 && x >= lo && x <= hi;
        let bad = || IoError::invalid(path, format!("value {tok} does not fit the NRRD type"));
        match t {
            RawType::U8 if ok_int(0.0, 255.0) => out.push(x as u8),
            RawType::I8 if ok_int(-128.0, 127.0) => out.push(x as i8 as u8),
            RawType::U16 if ok_int(0.0, 65535.0) => {
                out.extend_from_slice(&(x as u16).to_le_bytes())
            }
            RawType::I16 if ok_int(-32768.0, 32767.0) => {
                out.extend_from_slice(&(x as i16).to_le_bytes())
            }
            RawType::U32 if ok_int(0.0, 4294967295.0) => {
                out.extend_from_slice(&(x as u32).to_le_bytes())
            }
            RawType::I32 if ok_int(-2147483648.0, 2147483647.0) => {
                out.extend_from_slice(&(x as i32).to_le_bytes())
            }
            RawType::F32 => out.extend_from_slice(&(x as f32).to_le_bytes()),
            RawType::F64 => out.extend_from_slice(&x.to_le_bytes()),
            _ => return Err(bad()),
        }
        count += 1;
    }
    if count < n {
        return Err(IoError::invalid(
            path,
            format!("file is truncated: ASCII data has {count} of {n} values"),
        ));
    }
    Ok(out)
}

/// Write a `.nrrd` file (attached gzip data) atomically.
pub fn write(path: &Path, v: &AnyVolume) -> Result<(), IoError> {
    write_with_keys(path, v, &[])
}

/// Write a `.nrrd` file with extra `key:=value` lines (3D Slicer's segment
/// table); keys and values must not hold line breaks.
pub fn write_with_keys(
    path: &Path,
    v: &AnyVolume,
    keys: &[(String, String)],
) -> Result<(), IoError> {
    raw::write_atomic_with(path, |w| encode(w, path, v, keys))
}

/// The bytes of a `.nrrd` file with extra `key:=value` lines into `w`;
/// `path` names it in errors.
pub(crate) fn encode(
    w: &mut impl Write,
    path: &Path,
    v: &AnyVolume,
    keys: &[(String, String)],
) -> Result<(), IoError> {
    let g = v.geometry();
    let t = RawType::of(v);
    let vec3 = |x: [f64; 3]| format!("({},{},{})", num(x[0]), num(x[1]), num(x[2]));
    let axis = |c: usize| [0, 1, 2].map(|r| g.direction[r][c] * g.spacing[c]);
    let u = g.unit.ascii();
    let head = format!(
        "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\n\
         type: {}\ndimension: 3\nspace: left-posterior-superior\nsizes: {} {} {}\n\
         space directions: {} {} {}\nkinds: domain domain domain\nendian: little\nencoding: gzip\n\
         space origin: {}\nspace units: \"{u}\" \"{u}\" \"{u}\"\n",
        type_name(t),
        g.dims[0],
        g.dims[1],
        g.dims[2],
        vec3(axis(0)),
        vec3(axis(1)),
        vec3(axis(2)),
        vec3(g.origin),
    );
    let mut head = head;
    for (k, val) in keys {
        if k.contains(['\n', '\r']) || val.contains(['\n', '\r']) || k.contains(":=") {
            return Err(IoError::invalid(
                path,
                format!("NRRD key '{k}' holds a line break"),
            ));
        }
        head.push_str(&format!("{k}:={val}\n"));
    }
    head.push('\n');
    let data = v.to_le_bytes();
    let mut write = || -> std::io::Result<()> {
        w.write_all(head.as_bytes())?;
        let mut e = flate2::write::GzEncoder::new(&mut *w, flate2::Compression::fast());
        e.write_all(&data)?;
        e.finish()?;
        Ok(())
    };
    write().map_err(|e| IoError::write(path, e))
}
