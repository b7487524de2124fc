//! MetaImage (`.mha` with the data attached, `.mhd` with a `.raw`/`.zraw` file).
//!
//! The text header is parsed here (no well-kept Rust crate reads MetaImage).
//! Read: `ElementType` MET_UCHAR/CHAR/USHORT/SHORT/UINT/INT/FLOAT/DOUBLE, one
//! channel, raw or zlib (`CompressedData = True`) data, big or little endian,
//! `HeaderSize` (including -1: data at the end of the file). Geometry as ITK
//! reads it: `ElementSpacing`, `Offset` (or `Origin`/`Position`) and
//! `TransformMatrix` (or `Rotation`/`Orientation`), whose consecutive triples
//! are the direction vectors of the x, y and z axes (ITK's direction columns).
//! MetaImage has no unit field: interslice writes and reads its own
//! `ElementSpacingUnits` line, which ITK ignores; without it the unit is mm.
//! Write: `.mha` with zlib-compressed data, `.mhd` with an uncompressed `.raw`
//! file of the same stem (data written first, then the header, both atomic).
use crate::header::{self, num};
use crate::limits::{Loaded, ReadLimits, VolumeHeader, Want};
use crate::raw::{self, Endian, RawType};
use crate::source::Source;
use crate::{Format, IoError};
use interslice_core::{AnyVolume, LengthUnit};
use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

fn raw_type(path: &Path, s: &str) -> Result<RawType, IoError> {
    Ok(match s.trim() {
        "MET_UCHAR" => RawType::U8,
        "MET_CHAR" => RawType::I8,
        "MET_USHORT" => RawType::U16,
        "MET_SHORT" => RawType::I16,
        "MET_UINT" | "MET_ULONG" => RawType::U32,
        "MET_INT" | "MET_LONG" => RawType::I32,
        "MET_FLOAT" => RawType::F32,
        "MET_DOUBLE" => RawType::F64,
        other => {
            return Err(IoError::unsupported(
                path,
                format!("MetaImage ElementType '{other}' is not supported"),
            ));
        }
    })
}

fn type_name(t: RawType) -> &'static str {
    match t {
        RawType::U8 => "MET_UCHAR",
        RawType::I8 => "MET_CHAR",
        RawType::U16 => "MET_USHORT",
        RawType::I16 => "MET_SHORT",
        RawType::U32 => "MET_UINT",
        RawType::I32 => "MET_INT",
        RawType::F32 => "MET_FLOAT",
        RawType::F64 => "MET_DOUBLE",
    }
}

fn is_true(s: &str) -> bool {
    matches!(s.trim().to_ascii_lowercase().as_str(), "true" | "1" | "yes")
}

/// Read a `.mha` or `.mhd` file or bytes; a separate data file must be
/// inside the header's folder (see [`Source::data_file`]).
pub(crate) fn read(src: Source<'_>, limits: &ReadLimits, want: Want) -> Result<Loaded, IoError> {
    let path = src.name;
    let (mut r, total_len) = src.open()?;
    let mut consumed = 0usize;
    let mut fields: HashMap<String, String> = HashMap::new();
    let mut data_file = None;
    while let Some(line) = header::read_line(path, &mut r, &mut consumed)? {
        if line.trim().is_empty() {
            continue;
        }
        let Some((k, v)) = line.split_once('=') else {
            return Err(IoError::invalid(
                path,
                "not a MetaImage file (header line without '=')",
            ));
        };
        let k = k.trim().to_string();
        if fields.is_empty()
            && data_file.is_none()
            && !matches!(
                k.as_str(),
                "ObjectType" | "NDims" | "Comment" | "ObjectSubType"
            )
        {
            return Err(IoError::invalid(
                path,
                "not a MetaImage file (does not start with ObjectType or NDims)",
            ));
        }
        if k == "ElementDataFile" {
            data_file = Some(v.trim().to_string());
            break;
        }
        fields.insert(k, v.trim().to_string());
    }
    let data_file = data_file
        .ok_or_else(|| IoError::invalid(path, "MetaImage header has no ElementDataFile"))?;
    let get = |k: &str| fields.get(k).map(String::as_str);
    let need = |k: &str| {
        get(k).ok_or_else(|| IoError::invalid(path, format!("MetaImage header has no {k}")))
    };

    if let Some(o) = get("ObjectType")
        && o != "Image"
    {
        return Err(IoError::unsupported(
            path,
            format!("MetaImage ObjectType '{o}' is not an image"),
        ));
    }
    let ndims: usize = need("NDims")?
        .parse()
        .map_err(|_| IoError::invalid(path, "bad NDims"))?;
    if !(2..=3).contains(&ndims) {
        return Err(IoError::unsupported(
            path,
            format!("{ndims}D MetaImage files are not supported (2D and 3D only)"),
        ));
    }
    if let Some(c) = get("ElementNumberOfChannels")
        && c.trim() != "1"
    {
        return Err(IoError::unsupported(
            path,
            format!("MetaImage with {c} channels per voxel is not supported"),
        ));
    }
    let sizes: Vec<usize> = need("DimSize")?
        .split_whitespace()
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| IoError::invalid(path, "bad DimSize"))?;
    if sizes.len() != ndims {
        return Err(IoError::invalid(
            path,
            format!("DimSize has {} values for NDims {ndims}", sizes.len()),
        ));
    }
    let mut dims = [1usize; 3];
    dims[..ndims].copy_from_slice(&sizes);
    let t = raw_type(path, need("ElementType")?)?;
    let nbytes = limits.array_bytes(path, dims, t)?;

    let vals = |k: &str| -> Result<Option<Vec<f64>>, IoError> {
        match get(k) {
            None => Ok(None),
            Some(s) => s
                .split_whitespace()
                .map(|x| x.parse::<f64>())
                .collect::<Result<Vec<_>, _>>()
                .map(Some)
                .map_err(|_| IoError::invalid(path, format!("bad {k} '{s}'"))),
        }
    };
    // Without ElementSpacing the file has no spacing (1); a spacing it
    // gives must be a positive number.
    let spacing = vals("ElementSpacing")?
        .or(vals("ElementSize")?)
        .unwrap_or_else(|| vec![1.0; ndims]);
    if let Some(s) = spacing.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
        return Err(IoError::invalid(
            path,
            format!("ElementSpacing {s} is not a positive number"),
        ));
    }
    let origin = vals("Offset")?
        .or(vals("Origin")?)
        .or(vals("Position")?)
        .unwrap_or_else(|| vec![0.0; ndims]);
    let matrix = vals("TransformMatrix")?
        .or(vals("Rotation")?)
        .or(vals("Orientation")?);
    if spacing.len() != ndims
        || origin.len() != ndims
        || matrix.as_ref().is_some_and(|m| m.len() != ndims * ndims)
    {
        return Err(IoError::invalid(
            path,
            "ElementSpacing, Offset or TransformMatrix has the wrong number of values",
        ));
    }
    let mut axes = [[0.0; 3]; 3];
    let mut org = [0.0; 3];
    for a in 0..3 {
        if a < ndims {
            for r in 0..ndims {
                let d = match &matrix {
                    Some(m) => m[a * ndims + r],
                    None => f64::from(u8::from(a == r)),
                };
                axes[a][r] = d * spacing[a];
            }
            org[a] = origin[a];
        } else {
            axes[a][a] = 1.0;
        }
    }
    let unit = match get("ElementSpacingUnits") {
        Some(u) => LengthUnit::parse(u).unwrap_or(LengthUnit::Unknown),
        None => LengthUnit::Millimetre,
    };
    let geometry = header::geometry_from_axes(path, dims, axes, org, unit)?;

    if get("BinaryData").is_some_and(|b| !is_true(b)) {
        return Err(IoError::unsupported(
            path,
            "MetaImage with ASCII data (BinaryData = False) is not supported",
        ));
    }
    let endian = if get("BinaryDataByteOrderMSB")
        .or(get("ElementByteOrderMSB"))
        .is_some_and(is_true)
    {
        Endian::Big
    } else {
        Endian::Little
    };
    let compressed = get("CompressedData").is_some_and(is_true);
    let header_size: i64 = match get("HeaderSize") {
        None => 0,
        Some(h) => match h.trim().parse::<i64>() {
            Ok(n) if n >= -1 => n,
            _ => {
                return Err(IoError::invalid(
                    path,
                    format!("bad HeaderSize '{h}' (a count of bytes, or -1)"),
                ));
            }
        },
    };
    if data_file != "LOCAL"
        && (data_file.starts_with("LIST")
            || data_file.contains('%')
            || data_file.split_whitespace().count() > 1)
    {
        return Err(IoError::unsupported(
            path,
            "MetaImage with one data file per slice is not supported",
        ));
    }
    if want == Want::Header {
        return Ok(Loaded::Header(VolumeHeader {
            format: if data_file == "LOCAL" {
                Format::Mha
            } else {
                Format::Mhd
            },
            geometry,
            stored_type: t,
            data_bytes: nbytes as u64,
        }));
    }

    let (mut reader, len, name): (Box<dyn std::io::BufRead>, u64, PathBuf) = if data_file == "LOCAL"
    {
        (
            r,
            total_len.saturating_sub(consumed as u64),
            path.to_path_buf(),
        )
    } else {
        let (p, reader, len) = src.data_file(&data_file)?;
        (reader, len, p)
    };
    let bytes = if compressed {
        let mut dec = flate2::read::ZlibDecoder::new(reader);
        raw::read_data(&name, &mut dec, nbytes)?
    } else {
        let skip = if header_size == -1 {
            len.checked_sub(nbytes as u64).ok_or_else(|| {
                IoError::invalid(
                    &name,
                    format!("file is truncated: dims {dims:?} need {nbytes} bytes of data"),
                )
            })?
        } else {
            header_size.max(0) as u64
        };
        if len < skip + nbytes as u64 {
            return Err(IoError::invalid(
                &name,
                format!(
                    "file is truncated: dims {dims:?} need {nbytes} bytes of data, {} are there",
                    len.saturating_sub(skip)
                ),
            ));
        }
        std::io::copy(&mut (&mut reader).take(skip), &mut std::io::sink())
            .map_err(|e| IoError::read(&name, e))?;
        raw::read_data(&name, &mut reader, nbytes)?
    };
    raw::decode_volume(&name, geometry, t, endian, &bytes).map(Loaded::Volume)
}

fn header_text(v: &AnyVolume, compressed: Option<usize>, data_file: &str) -> String {
    let g = v.geometry();
    let d = g.direction;
    let mut s = String::from(
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n",
    );
    match compressed {
        Some(n) => s.push_str(&format!(
            "CompressedData = True\nCompressedDataSize = {n}\n"
        )),
        None => s.push_str("CompressedData = False\n"),
    }
    let m: Vec<String> = (0..3)
        .flat_map(|c| (0..3).map(move |r| num(d[r][c])))
        .collect();
    s.push_str(&format!("TransformMatrix = {}\n", m.join(" ")));
    s.push_str(&format!(
        "Offset = {} {} {}\n",
        num(g.origin[0]),
        num(g.origin[1]),
        num(g.origin[2])
    ));
    s.push_str("CenterOfRotation = 0 0 0\n");
    s.push_str(&format!(
        "ElementSpacing = {} {} {}\n",
        num(g.spacing[0]),
        num(g.spacing[1]),
        num(g.spacing[2])
    ));
    s.push_str(&format!("ElementSpacingUnits = {}\n", g.unit.ascii()));
    s.push_str(&format!(
        "DimSize = {} {} {}\n",
        g.dims[0], g.dims[1], g.dims[2]
    ));
    s.push_str(&format!("ElementType = {}\n", type_name(RawType::of(v))));
    s.push_str(&format!("ElementDataFile = {data_file}\n"));
    s
}

/// The bytes of a `.mha` file (zlib data attached) into `w`; `path` names it
/// in errors.
pub(crate) fn encode_mha(w: &mut impl Write, path: &Path, v: &AnyVolume) -> Result<(), IoError> {
    let data = v.to_le_bytes();
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    z.write_all(&data).map_err(|e| IoError::write(path, e))?;
    let zdata = z.finish().map_err(|e| IoError::write(path, e))?;
    drop(data);
    let head = header_text(v, Some(zdata.len()), "LOCAL");
    w.write_all(head.as_bytes())
        .and_then(|()| w.write_all(&zdata))
        .map_err(|e| IoError::write(path, e))
}

/// Write a `.mha` (zlib data attached) or `.mhd` (+ uncompressed `.raw`) file.
pub fn write(path: &Path, v: &AnyVolume, attached: bool) -> Result<(), IoError> {
    if attached {
        raw::write_atomic_with(path, |w| encode_mha(w, path, v))
    } else {
        let data = v.to_le_bytes();
        let raw_path = path.with_extension("raw");
        let raw_name = raw_path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        raw::write_atomic(&raw_path, |w| w.write_all(&data))?;
        let head = header_text(v, None, &raw_name);
        raw::write_atomic(path, |w| w.write_all(head.as_bytes()))
    }
}
