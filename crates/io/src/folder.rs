//! A folder of 2D slices: one PNG or TIFF file per z slice.
//!
//! Read: every `.png`, `.tif` or `.tiff` file of the folder (hidden files
//! and other files are ignored), sorted naturally by name (`slice_2` before
//! `slice_10`). All slices must have one size and one gray type; a folder
//! that mixes PNG and TIFF files is refused. PNG slices may be 8- or 16-bit
//! gray (1-, 2- and 4-bit gray are unpacked to their stored values, never
//! stretched); TIFF slices are read like a page of a multi-page TIFF.
//! Geometry comes from the first slice: the `interslice` text chunk that
//! interslice writes into PNG slices, or the ImageJ metadata of a TIFF slice.
//! Without either, spacing is 1 and the unit unknown.
//!
//! Write: `slice_0000.png`, `slice_0001.png`, ... (more digits when there are
//! more than 10 000 slices), 8- or 16-bit gray. Every slice carries an
//! `interslice` tEXt chunk with spacing, unit, origin and direction, and a
//! `pHYs` chunk (pixels per metre) for other viewers. The folder is written
//! next to the target under a temporary name and swapped in when complete;
//! an existing folder is replaced only when it holds nothing but
//! `slice_*.png` files.
use crate::header::num;
use crate::limits::{Loaded, ReadLimits, VolumeHeader, Want, try_vec};
use crate::planes::{Plane, Stack, parse_list, unknown_geometry};
use crate::raw::{self, RawType};
use crate::{Format, IoError};
use crate::{source, tiff_stack};
use interslice_core::{AnyVolume, Geometry, LengthUnit};
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Keyword of the PNG text chunk that holds the geometry.
const TEXT_KEY: &str = "interslice";

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Png,
    Tiff,
}

fn kind_of(name: &str) -> Option<Kind> {
    if name.starts_with('.') {
        return None;
    }
    let lower = name.to_ascii_lowercase();
    if lower.ends_with(".png") {
        Some(Kind::Png)
    } else if lower.ends_with(".tif") || lower.ends_with(".tiff") {
        Some(Kind::Tiff)
    } else {
        None
    }
}

/// The slice files of a folder, sorted naturally, and their kind.
fn list(path: &Path) -> Result<(Vec<PathBuf>, Kind), IoError> {
    let entries = std::fs::read_dir(path).map_err(|e| IoError::read(path, e))?;
    let mut files: Vec<(String, Kind)> = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| IoError::read(path, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(kind) = kind_of(&name) else {
            continue;
        };
        let Ok(ft) = entry.file_type() else {
            continue;
        };
        // A link is followed only to a file inside the folder; a link that
        // leads out is refused whether or not its target exists.
        if ft.is_symlink() && !source::stays_inside(path, &name) {
            return Err(IoError::unsupported(
                path,
                format!("slice '{name}' is a link that leads out of the folder"),
            ));
        }
        let is_file = ft.is_file()
            || (ft.is_symlink() && std::fs::metadata(entry.path()).is_ok_and(|m| m.is_file()));
        if is_file {
            files.push((name, kind));
        }
    }
    let Some(&(_, kind)) = files.first() else {
        return Err(IoError::invalid(
            path,
            "folder has no PNG or TIFF slices (.png, .tif, .tiff)",
        ));
    };
    if files.iter().any(|&(_, k)| k != kind) {
        return Err(IoError::invalid(
            path,
            "folder mixes PNG and TIFF slices (keep one kind per folder)",
        ));
    }
    files.sort_by(|a, b| natord::compare(&a.0, &b.0));
    Ok((files.into_iter().map(|(n, _)| path.join(n)).collect(), kind))
}

fn png_err(path: &Path, e: png::DecodingError) -> IoError {
    match e {
        png::DecodingError::IoError(e) => IoError::read(path, e),
        png::DecodingError::LimitsExceeded => IoError::unsupported(path, "PNG image is too large"),
        other => IoError::invalid(path, format!("bad PNG: {other}")),
    }
}

/// Most a PNG's deflate stream expands (deflate's largest ratio is about
/// 1032:1): a header that claims more pixels than its file could hold is
/// refused before the image buffer is allocated.
const MAX_EXPANSION: u64 = 1100;

/// Memory the PNG decoder may use besides the image (text chunks, ICC
/// profiles, its own buffers).
const PNG_DECODER_BYTES: usize = 64 << 20;

/// A PNG slice whose header has been read.
struct PngSlice {
    reader: png::Reader<std::io::BufReader<std::fs::File>>,
    header: SliceHeader,
    text: Option<String>,
}

/// Size and stored type of a slice, from its header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct SliceHeader {
    w: usize,
    h: usize,
    t: RawType,
}

/// Open a PNG slice and read its header (nothing of the image is decoded).
fn png_header(path: &Path) -> Result<PngSlice, IoError> {
    let file = raw::open(path)?;
    let file_len = file
        .get_ref()
        .metadata()
        .map_err(|e| IoError::read(path, e))?
        .len();
    let mut dec = png::Decoder::new(file);
    dec.set_transformations(png::Transformations::IDENTITY);
    dec.set_limits(png::Limits {
        bytes: PNG_DECODER_BYTES,
    });
    let reader = dec.read_info().map_err(|e| png_err(path, e))?;
    let info = reader.info();
    let (w, h) = (info.width as usize, info.height as usize);
    if info.color_type != png::ColorType::Grayscale {
        return Err(IoError::unsupported(
            path,
            format!(
                "PNG colour type {:?} is not supported (gray slices only)",
                info.color_type
            ),
        ));
    }
    let t = match info.bit_depth {
        png::BitDepth::Sixteen => RawType::U16,
        _ => RawType::U8,
    };
    // The decoded rows (with their filter bytes) must fit what the file can expand to.
    let depth = info.bit_depth as u64;
    let row = (w as u64)
        .saturating_mul(depth)
        .div_ceil(8)
        .saturating_add(1);
    let need = row.saturating_mul(h as u64);
    if need
        > file_len
            .saturating_mul(MAX_EXPANSION)
            .saturating_add(1 << 16)
    {
        return Err(IoError::invalid(
            path,
            format!("PNG of {w} x {h} needs {need} bytes, more than the file can hold"),
        ));
    }
    let text = info
        .uncompressed_latin1_text
        .iter()
        .find(|t| t.keyword == TEXT_KEY)
        .map(|t| t.text.clone());
    Ok(PngSlice {
        reader,
        header: SliceHeader { w, h, t },
        text,
    })
}

/// Decode the pixels of a PNG slice whose header was checked.
fn png_pixels(path: &Path, slice: PngSlice) -> Result<Plane, IoError> {
    let PngSlice {
        mut reader,
        header: SliceHeader { w, h, .. },
        ..
    } = slice;
    let depth = reader.info().bit_depth as usize;
    let size = reader.output_buffer_size();
    let mut buf: Vec<u8> = try_vec(path, size)?;
    buf.resize(size, 0);
    let out = reader.next_frame(&mut buf).map_err(|e| png_err(path, e))?;
    let line = out.line_size;
    let plane = match depth {
        8 => Plane::U8(
            buf.chunks(line)
                .take(h)
                .flat_map(|r| &r[..w])
                .copied()
                .collect(),
        ),
        16 => Plane::U16(
            buf.chunks(line)
                .take(h)
                .flat_map(|r| r[..2 * w].chunks_exact(2))
                .map(|b| u16::from_be_bytes([b[0], b[1]]))
                .collect(),
        ),
        1 | 2 | 4 => {
            let per = 8 / depth;
            let mask = (1u16 << depth) as u8 - 1;
            let mut px = try_vec(path, w * h)?;
            for row in buf.chunks(line).take(h) {
                for x in 0..w {
                    let byte = row[x / per];
                    let shift = 8 - depth * (x % per + 1);
                    px.push((byte >> shift) & mask);
                }
            }
            Plane::U8(px)
        }
        other => {
            return Err(IoError::unsupported(
                path,
                format!("PNG bit depth {other} is not supported"),
            ));
        }
    };
    Ok(plane)
}

/// One TIFF slice (exactly one page): its decoder at the page, header and
/// the geometry its ImageJ metadata gives.
type TiffSlice = (
    tiff::decoder::Decoder<std::io::BufReader<std::fs::File>>,
    SliceHeader,
    Geometry,
    u64,
);

fn tiff_header(path: &Path, first: bool) -> Result<TiffSlice, IoError> {
    let f = raw::open(path)?;
    let len = f
        .get_ref()
        .metadata()
        .map_err(|e| IoError::read(path, e))?
        .len();
    let mut d = tiff_stack::decoder(path, f)?;
    let g = if first {
        tiff_stack::geometry_of(path, &mut d)?
    } else {
        Geometry::new([1; 3], [1.0; 3], LengthUnit::Unknown)
            .map_err(|e| IoError::invalid(path, e.to_string()))?
    };
    let (w, h, t) = tiff_stack::page_header(path, &mut d)?;
    if d.more_images() {
        return Err(IoError::unsupported(
            path,
            "TIFF slice has several pages (a slice folder needs one image per file; read the file itself as a stack)",
        ));
    }
    Ok((d, SliceHeader { w, h, t }, g, len))
}

/// Geometry (dims left 1) from the `interslice` text chunk.
fn geometry_from_text(path: &Path, text: Option<&str>) -> Result<Geometry, IoError> {
    let mut g = unknown_geometry();
    let Some(text) = text else {
        return Ok(g);
    };
    let keys: HashMap<&str, &str> = text
        .lines()
        .filter_map(|l| l.split_once('='))
        .map(|(k, v)| (k.trim(), v.trim()))
        .collect();
    let bad = |k: &str| IoError::invalid(path, format!("bad '{k}' in the interslice text chunk"));
    if let Some(s) = keys.get("spacing") {
        g.spacing = parse_list::<3>(s).ok_or_else(|| bad("spacing"))?;
    }
    if let Some(u) = keys.get("unit") {
        g.unit = LengthUnit::parse(u).unwrap_or(LengthUnit::Unknown);
    }
    if let Some(s) = keys.get("origin") {
        g.origin = parse_list::<3>(s).ok_or_else(|| bad("origin"))?;
    }
    if let Some(s) = keys.get("direction") {
        let d = parse_list::<9>(s).ok_or_else(|| bad("direction"))?;
        g.direction = [[d[0], d[1], d[2]], [d[3], d[4], d[5]], [d[6], d[7], d[8]]];
    }
    crate::header::checked(path, g)
}

/// Read a folder of slices as a volume. The first slice's header gives the
/// size and type, checked against the limits before any slice is decoded;
/// every other slice's header must match it before its pixels are decoded.
pub(crate) fn read(path: &Path, limits: &ReadLimits, want: Want) -> Result<Loaded, IoError> {
    let (files, kind) = list(path)?;
    let (first, g) = match kind {
        Kind::Png => {
            let s = png_header(&files[0])?;
            let g = geometry_from_text(&files[0], s.text.as_deref())?;
            (s.header, g)
        }
        Kind::Tiff => {
            let (_, h, g, _) = tiff_header(&files[0], true)?;
            (h, g)
        }
    };
    let SliceHeader { w, h, t } = first;
    let dims = [w, h, files.len()];
    let data_bytes = (w as u64)
        .saturating_mul(h as u64)
        .saturating_mul(files.len() as u64)
        .saturating_mul(t.size() as u64);
    limits.check(path, dims, data_bytes)?;
    if want == Want::Header {
        let mut g = g;
        g.dims = dims;
        return Ok(Loaded::Header(VolumeHeader {
            format: Format::SliceFolder,
            geometry: g,
            stored_type: t,
            data_bytes,
        }));
    }
    let same = |f: &Path, k: usize, s: SliceHeader| {
        if s == first {
            Ok(())
        } else {
            Err(IoError::invalid(
                f,
                format!(
                    "slice {k} is {} x {} {:?} but the first is {w} x {h} {t:?} (all slices must have one size and type)",
                    s.w, s.h, s.t
                ),
            ))
        }
    };
    let planes: Vec<Plane> = files
        .par_iter()
        .enumerate()
        .map(|(k, f)| -> Result<Plane, IoError> {
            match kind {
                Kind::Png => {
                    let s = png_header(f)?;
                    same(f, k, s.header)?;
                    png_pixels(f, s)
                }
                Kind::Tiff => {
                    let (d, s, _, len) = tiff_header(f, false)?;
                    same(f, k, s)?;
                    let (_, plane) = tiff_stack::read_page(f, d, (s.w, s.h, s.t), len)?;
                    Ok(plane)
                }
            }
        })
        .collect::<Result<_, _>>()?;
    let mut stack = Stack::default();
    for (plane, f) in planes.into_iter().zip(&files) {
        stack.push(f, w, h, plane)?;
    }
    stack.finish(path, g).map(Loaded::Volume)
}

fn metres_per_unit(u: LengthUnit) -> Option<f64> {
    match u {
        LengthUnit::Micrometre => Some(1e-6),
        LengthUnit::Millimetre => Some(1e-3),
        LengthUnit::Metre => Some(1.0),
        LengthUnit::Unknown => None,
    }
}

fn text_of(g: &Geometry) -> String {
    let d: Vec<String> = g.direction.iter().flatten().map(|&x| num(x)).collect();
    format!(
        "spacing={},{},{}\nunit={}\norigin={},{},{}\ndirection={}\n",
        num(g.spacing[0]),
        num(g.spacing[1]),
        num(g.spacing[2]),
        g.unit.ascii(),
        num(g.origin[0]),
        num(g.origin[1]),
        num(g.origin[2]),
        d.join(",")
    )
}

/// Pixels per metre of a spacing, when it fits a PNG `pHYs` chunk.
fn per_metre(spacing: f64, unit: LengthUnit) -> Option<u32> {
    let m = spacing * metres_per_unit(unit)?;
    let ppm = (1.0 / m).round();
    (ppm >= 1.0 && ppm <= f64::from(u32::MAX)).then_some(ppm as u32)
}

fn write_png(
    file: &Path,
    g: &Geometry,
    text: &str,
    depth: png::BitDepth,
    bytes: &[u8],
) -> Result<(), IoError> {
    raw::write_atomic(file, |w| {
        let to_io = |e: png::EncodingError| match e {
            png::EncodingError::IoError(e) => e,
            other => std::io::Error::other(other.to_string()),
        };
        let mut enc = png::Encoder::new(w, g.dims[0] as u32, g.dims[1] as u32);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(depth);
        enc.set_compression(png::Compression::Fast);
        if let (Some(x), Some(y)) = (
            per_metre(g.spacing[0], g.unit),
            per_metre(g.spacing[1], g.unit),
        ) {
            enc.set_pixel_dims(Some(png::PixelDimensions {
                xppu: x,
                yppu: y,
                unit: png::Unit::Meter,
            }));
        }
        enc.add_text_chunk(TEXT_KEY.to_string(), text.to_string())
            .map_err(to_io)?;
        let mut wr = enc.write_header().map_err(to_io)?;
        wr.write_image_data(bytes).map_err(to_io)?;
        wr.finish().map_err(to_io)
    })
}

/// True for a name interslice gives a slice (`slice_` digits `.png`).
fn is_our_slice(name: &str) -> bool {
    name.strip_prefix("slice_")
        .and_then(|r| r.strip_suffix(".png"))
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

/// Write a volume as a folder of PNG slices (u8 or u16 only).
pub fn write(path: &Path, v: &AnyVolume) -> Result<(), IoError> {
    let g = v.geometry();
    let (depth, bytes_per) = match v {
        AnyVolume::U8(_) => (png::BitDepth::Eight, 1),
        AnyVolume::U16(_) => (png::BitDepth::Sixteen, 2),
        other => {
            return Err(IoError::unsupported(
                path,
                format!(
                    "PNG slices hold 8- or 16-bit unsigned values; a {} volume cannot be written without loss (use .tif, .nii.gz, .nrrd or .mha)",
                    other.type_name()
                ),
            ));
        }
    };
    let [nx, ny, nz] = g.dims;
    if nx > u32::MAX as usize || ny > u32::MAX as usize {
        return Err(IoError::unsupported(
            path,
            "PNG slices are at most 2^32-1 pixels wide",
        ));
    }
    // An existing target must be a folder of our own slices (or empty).
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.is_dir() => {
            return Err(IoError::unsupported(
                path,
                "exists and is not a folder (a slice folder is written as a directory)",
            ));
        }
        Ok(_) => {
            let entries = std::fs::read_dir(path).map_err(|e| IoError::write(path, e))?;
            for e in entries {
                let e = e.map_err(|e| IoError::write(path, e))?;
                let name = e.file_name().to_string_lossy().into_owned();
                if !is_our_slice(&name) {
                    return Err(IoError::unsupported(
                        path,
                        format!(
                            "folder holds '{name}', which is not a slice_N.png file; refusing to replace it"
                        ),
                    ));
                }
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(IoError::write(path, e)),
    }
    let trimmed = path.components().as_path();
    let parent = match trimmed.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = trimmed
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "slices".into());
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .tempdir_in(parent)
        .map_err(|e| IoError::write(path, e))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = 0o777 & !raw::umask();
        std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(mode))
            .map_err(|e| IoError::write(path, e))?;
    }
    let digits = nz.saturating_sub(1).to_string().len().max(4);
    let text = text_of(g);
    let page = nx * ny;
    (0..nz).into_par_iter().try_for_each(|k| {
        let file = tmp.path().join(format!("slice_{k:0digits$}.png"));
        let bytes: Vec<u8> = match v {
            AnyVolume::U8(x) => x.data()[k * page..(k + 1) * page].to_vec(),
            AnyVolume::U16(x) => x.data()[k * page..(k + 1) * page]
                .iter()
                .flat_map(|p| p.to_be_bytes())
                .collect(),
            _ => Vec::new(),
        };
        debug_assert_eq!(bytes.len(), page * bytes_per);
        write_png(&file, g, &text, depth, &bytes)
    })?;
    // Swap the finished folder in; the old one is removed only afterwards.
    let old = if path.exists() {
        let trash = tempfile::Builder::new()
            .prefix(&format!(".{name}."))
            .suffix(".old")
            .tempdir_in(parent)
            .map_err(|e| IoError::write(path, e))?;
        let moved = trash.path().join("old");
        std::fs::rename(path, &moved).map_err(|e| IoError::write(path, e))?;
        Some((trash, moved))
    } else {
        None
    };
    if let Err(e) = std::fs::rename(tmp.path(), path) {
        if let Some((_, moved)) = &old {
            let _ = std::fs::rename(moved, path);
        }
        return Err(IoError::write(path, e));
    }
    let _ = tmp.keep();
    drop(old); // removes the replaced slices
    Ok(())
}
