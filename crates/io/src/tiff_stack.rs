//! Multi-page TIFF (`.tif`, `.tiff`) as written and read by ImageJ/Fiji.
//!
//! Pages are z slices; every page must have the same size and gray type
//! (8/16-bit unsigned, signed 16-bit, 32-bit float). Spacing follows ImageJ:
//! `XResolution`/`YResolution` are pixels per unit, the `ImageDescription`
//! holds `unit=` (micron, µm, mm, ...) and `spacing=` (z). A TIFF without an
//! ImageJ description gets spacing 1 and an unknown unit: its resolution
//! tags usually hold a print resolution (72 dpi), not a voxel size. Origin
//! and direction, which TIFF cannot hold, are kept in two extra description
//! keys (`interslice.origin=`, `interslice.direction=`) that ImageJ ignores.
//! Written uncompressed (what every ImageJ version opens).
use crate::limits::{Loaded, ReadLimits, VolumeHeader, Want};
use crate::planes::{
    Plane, Stack, parse_list, resolution_rational, unit_with_scale, unknown_geometry,
};
use crate::raw::{self, RawType};
use crate::source::Source;
use crate::{Format, IoError};
use interslice_core::geometry::IDENTITY_DIRECTION;
use interslice_core::{AnyVolume, Geometry, LengthUnit};
use std::collections::HashMap;
use std::io::{Cursor, Read, Seek};
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::encoder::{Rational, TiffEncoder, TiffKind};
use tiff::tags::Tag;
use tiff::{ColorType, TiffError};

fn tiff_err(path: &Path, e: TiffError) -> IoError {
    match e {
        TiffError::IoError(e) => IoError::read(path, e),
        TiffError::UnsupportedError(e) => {
            IoError::unsupported(path, format!("unsupported TIFF: {e}"))
        }
        TiffError::LimitsExceeded => IoError::unsupported(path, "TIFF page is too large"),
        other => IoError::invalid(path, format!("bad TIFF: {other}")),
    }
}

/// Most bytes a tag value may hold (an `ImageDescription`, a strip offset
/// table): the decoder's limit while it reads tags, so a tag count of
/// 0xFFFFFFFF is an error, not a 4 GiB allocation.
const TAG_BYTES: usize = 16 << 20;

/// Most a compressed TIFF page is taken to expand (LZW codes of 12 bits
/// give at most 4096 bytes each): a page header that claims more than its
/// file could hold is refused before its buffer is allocated.
const MAX_EXPANSION: u64 = 4096;

fn limits_of(decoding_buffer_size: usize) -> Limits {
    let mut l = Limits::default();
    l.decoding_buffer_size = decoding_buffer_size;
    l.intermediate_buffer_size = decoding_buffer_size.min(1 << 30);
    l
}

/// A decoder whose tag values are bounded by [`TAG_BYTES`].
pub(crate) fn decoder<R: Read + Seek>(path: &Path, r: R) -> Result<Decoder<R>, IoError> {
    Ok(Decoder::new(r)
        .map_err(|e| tiff_err(path, e))?
        .with_limits(limits_of(TAG_BYTES)))
}

/// Size and stored element type of the current page (gray only).
pub(crate) fn page_header<R: Read + Seek>(
    path: &Path,
    d: &mut Decoder<R>,
) -> Result<(usize, usize, RawType), IoError> {
    let (w, h) = d.dimensions().map_err(|e| tiff_err(path, e))?;
    let bits = match d.colortype().map_err(|e| tiff_err(path, e))? {
        ColorType::Gray(b) => b,
        other => {
            return Err(IoError::unsupported(
                path,
                format!("TIFF colour type {other:?} is not supported (gray images only)"),
            ));
        }
    };
    let format = d
        .find_tag_unsigned::<u16>(Tag::SampleFormat)
        .map_err(|e| tiff_err(path, e))?
        .unwrap_or(1);
    let t = match (bits, format) {
        (8, 1) => RawType::U8,
        (8, 2) => RawType::I8,
        (16, 1) => RawType::U16,
        (16, 2) => RawType::I16,
        (32, 3) => RawType::F32,
        _ => {
            return Err(IoError::unsupported(
                path,
                format!(
                    "TIFF sample type of {bits} bits (format {format}) is not supported (8/16-bit integer or 32-bit float only)"
                ),
            ));
        }
    };
    Ok((w as usize, h as usize, t))
}

/// Read the current page (whose header is `w` x `h` of `t`) as a gray
/// plane. `file_len` bounds what the page may need: no more than the file
/// holds (uncompressed) or [`MAX_EXPANSION`] times it (compressed).
pub(crate) fn read_page<R: Read + Seek>(
    path: &Path,
    d: Decoder<R>,
    (w, h, t): (usize, usize, RawType),
    file_len: u64,
) -> Result<(Decoder<R>, Plane), IoError> {
    let mut d = d;
    let bytes = (w as u64)
        .saturating_mul(h as u64)
        .saturating_mul(t.size() as u64);
    let compression = d
        .find_tag_unsigned::<u16>(Tag::Compression)
        .map_err(|e| tiff_err(path, e))?
        .unwrap_or(1);
    let most = if compression == 1 {
        file_len
    } else {
        file_len.saturating_mul(MAX_EXPANSION)
    };
    if bytes > most {
        return Err(IoError::invalid(
            path,
            format!("TIFF page of {w} x {h} needs {bytes} bytes, more than the file can hold"),
        ));
    }
    let page =
        usize::try_from(bytes).map_err(|_| IoError::unsupported(path, "TIFF page is too large"))?;
    // The decoder allocates the page itself: allow exactly that much, then
    // go back to the tag limit.
    d = d.with_limits(limits_of(page.max(TAG_BYTES)));
    let result = d.read_image().map_err(|e| tiff_err(path, e));
    d = d.with_limits(limits_of(TAG_BYTES));
    let plane = match result? {
        DecodingResult::U8(v) => Plane::U8(v),
        DecodingResult::U16(v) => Plane::U16(v),
        DecodingResult::I16(v) => Plane::I16(v),
        DecodingResult::I8(v) => Plane::I16(v.into_iter().map(i16::from).collect()),
        DecodingResult::F32(v) => Plane::F32(v),
        _ => {
            return Err(IoError::unsupported(
                path,
                "TIFF sample type is not supported (8/16-bit integer or 32-bit float only)",
            ));
        }
    };
    if plane.len() != w * h {
        return Err(IoError::invalid(
            path,
            format!("TIFF page of {w} x {h} decoded to {} samples", plane.len()),
        ));
    }
    Ok((d, plane))
}

/// The `key=value` lines of an ImageJ description, or None.
fn imagej_description<R: Read + Seek>(d: &mut Decoder<R>) -> Option<HashMap<String, String>> {
    let s = d.get_tag_ascii_string(Tag::ImageDescription).ok()?;
    if !s.starts_with("ImageJ=") {
        return None;
    }
    Some(
        s.lines()
            .filter_map(|l| l.split_once('='))
            .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
            .collect(),
    )
}

/// A resolution tag in pixels per unit: `None` when absent, an error when
/// present but not a positive finite number.
fn resolution<R: Read + Seek>(
    path: &Path,
    d: &mut Decoder<R>,
    tag: Tag,
) -> Result<Option<f64>, IoError> {
    let v = match d.find_tag(tag).map_err(|e| tiff_err(path, e))? {
        None => return Ok(None),
        Some(v) => v,
    };
    let x = match v {
        tiff::decoder::ifd::Value::Rational(n, den) if den > 0 => f64::from(n) / f64::from(den),
        tiff::decoder::ifd::Value::Float(f) => f64::from(f),
        tiff::decoder::ifd::Value::Double(f) => f,
        _ => f64::NAN,
    };
    if !(x.is_finite() && x > 0.0 && (1.0 / x).is_finite()) {
        return Err(IoError::invalid(
            path,
            format!("{tag:?} {x} is not a positive resolution (voxel spacing would be invalid)"),
        ));
    }
    Ok(Some(x))
}

/// Spacing, unit, origin and direction of the first page (dims left 1).
/// Without an ImageJ description the file has no spacing: 1 and an unknown
/// unit. With one, a resolution or `spacing=` that is zero, negative or
/// not a number is an error.
pub(crate) fn geometry_of<R: Read + Seek>(
    path: &Path,
    d: &mut Decoder<R>,
) -> Result<Geometry, IoError> {
    let mut g = unknown_geometry();
    let Some(desc) = imagej_description(d) else {
        return Ok(g);
    };
    let (unit, scale) = desc
        .get("unit")
        .map(|u| unit_with_scale(u))
        .unwrap_or((LengthUnit::Unknown, 1.0));
    g.unit = unit;
    if let Some(x) = resolution(path, d, Tag::XResolution)? {
        g.spacing[0] = scale / x;
    }
    g.spacing[1] = match resolution(path, d, Tag::YResolution)? {
        Some(y) => scale / y,
        None => g.spacing[0],
    };
    g.spacing[2] = match desc.get("spacing") {
        Some(s) => match s.parse::<f64>() {
            Ok(z) if z.is_finite() && z > 0.0 => z * scale,
            _ => {
                return Err(IoError::invalid(
                    path,
                    format!("ImageJ spacing={s} is not a positive number"),
                ));
            }
        },
        None => g.spacing[0],
    };
    if let Some(o) = desc.get("interslice.origin") {
        g.origin = parse_list::<3>(o)
            .ok_or_else(|| IoError::invalid(path, format!("bad interslice.origin={o}")))?;
    }
    if let Some(s) = desc.get("interslice.direction") {
        let dir = s
            .split(',')
            .map(|x| x.trim().parse().ok())
            .collect::<Option<Vec<f64>>>()
            .and_then(|v| <[f64; 9]>::try_from(v).ok())
            .ok_or_else(|| IoError::invalid(path, format!("bad interslice.direction={s}")))?;
        g.direction = [
            [dir[0], dir[1], dir[2]],
            [dir[3], dir[4], dir[5]],
            [dir[6], dir[7], dir[8]],
        ];
    }
    crate::header::checked(path, g)
}

/// Read a multi-page TIFF (a file or bytes) as a volume.
pub(crate) fn read(src: Source<'_>, limits: &ReadLimits, want: Want) -> Result<Loaded, IoError> {
    match src.bytes {
        Some(b) => read_from(src.name, Cursor::new(b), b.len() as u64, limits, want),
        None => {
            let f = raw::open(src.name)?;
            let len = f
                .get_ref()
                .metadata()
                .map_err(|e| IoError::read(src.name, e))?
                .len();
            read_from(src.name, f, len, limits, want)
        }
    }
}

fn read_from<R: Read + Seek>(
    path: &Path,
    r: R,
    file_len: u64,
    limits: &ReadLimits,
    want: Want,
) -> Result<Loaded, IoError> {
    let mut d = decoder(path, r)?;
    let mut g = geometry_of(path, &mut d)?;
    if let Some(desc) = imagej_description(&mut d) {
        for key in ["channels", "frames"] {
            if let Some(n) = desc.get(key).and_then(|s| s.parse::<u64>().ok())
                && n > 1
            {
                return Err(IoError::unsupported(
                    path,
                    format!("ImageJ hyperstack with {n} {key} is not supported"),
                ));
            }
        }
    }
    let first = page_header(path, &mut d)?;
    let (w, h, t) = first;
    let page_voxels = (w as u64).saturating_mul(h as u64);
    // Pages are counted (their directories only) up to what the limits allow.
    let most_pages = match limits.expected_dims {
        Some(e) => e[2] as u64,
        None => limits.max_voxels / page_voxels.max(1),
    };
    let check = |pages: usize| {
        let bytes = page_voxels
            .saturating_mul(pages as u64)
            .saturating_mul(t.size() as u64);
        limits.check(path, [w, h, pages], bytes)
    };
    if want == Want::Header {
        let mut pages = 1usize;
        while d.more_images() {
            if pages as u64 >= most_pages {
                check(pages + 1)?;
                return Err(IoError::unsupported(path, "TIFF has too many pages"));
            }
            d.next_image().map_err(|e| tiff_err(path, e))?;
            pages += 1;
        }
        check(pages)?;
        g.dims = [w, h, pages];
        return Ok(Loaded::Header(VolumeHeader {
            format: Format::Tiff,
            geometry: g,
            stored_type: t,
            data_bytes: page_voxels * pages as u64 * t.size() as u64,
        }));
    }
    // The page size (and the page count the caller expects) is checked
    // before the first page is decoded.
    check(limits.expected_dims.map_or(1, |e| e[2]))?;
    let mut stack = Stack::default();
    let mut header = first;
    loop {
        if header != first {
            return Err(IoError::invalid(
                path,
                format!(
                    "page {} is {} x {} {:?} but the first is {w} x {h} {t:?} (all pages must have one size and type)",
                    stack.len(),
                    header.0,
                    header.1,
                    header.2
                ),
            ));
        }
        if stack.len() as u64 >= most_pages {
            check(stack.len() + 1)?;
        }
        let (next, plane) = read_page(path, d, header, file_len)?;
        d = next;
        stack.push(path, w, h, plane)?;
        if !d.more_images() {
            break;
        }
        d.next_image().map_err(|e| tiff_err(path, e))?;
        header = page_header(path, &mut d)?;
    }
    check(stack.len())?;
    g.dims = [1; 3];
    stack.finish(path, g).map(Loaded::Volume)
}

fn imagej_unit(u: LengthUnit) -> &'static str {
    match u {
        LengthUnit::Micrometre => "micron",
        LengthUnit::Millimetre => "mm",
        LengthUnit::Metre => "m",
        LengthUnit::Unknown => "pixel",
    }
}

fn description(g: &Geometry, v: &AnyVolume) -> String {
    let (min, max) = v.min_max();
    let n = crate::header::num;
    let d = g.direction;
    let mut s = format!(
        "ImageJ=1.11a\nimages={nz}\nslices={nz}\nunit={}\nspacing={}\nloop=false\nmin={}\nmax={}\n",
        imagej_unit(g.unit),
        n(g.spacing[2]),
        n(min),
        n(max),
        nz = g.dims[2]
    );
    if g.origin != [0.0; 3] {
        s.push_str(&format!(
            "interslice.origin={},{},{}\n",
            n(g.origin[0]),
            n(g.origin[1]),
            n(g.origin[2])
        ));
    }
    if d != IDENTITY_DIRECTION {
        let all: Vec<String> = d.iter().flatten().map(|&x| n(x)).collect();
        s.push_str(&format!("interslice.direction={}\n", all.join(",")));
    }
    s
}

/// The page data of a volume, written contiguously (what ImageJ and
/// tifffile expect of an ImageJ stack: they read `images=` pages from the
/// first page's offset on), then one directory per page.
fn write_pages<W: std::io::Write + std::io::Seek, K: TiffKind>(
    enc: &mut TiffEncoder<W, K>,
    v: &AnyVolume,
    desc: &str,
) -> Result<(), TiffError> {
    let g = v.geometry();
    let [nx, ny, nz] = g.dims;
    let t = crate::raw::RawType::of(v);
    let page_bytes = (nx * ny * t.size()) as u64;
    let (bits, format): (u16, u16) = match v {
        AnyVolume::U8(_) => (8, 1),
        AnyVolume::U16(_) => (16, 1),
        AnyVolume::I16(_) => (16, 2),
        AnyVolume::F32(_) => (32, 3),
    };
    let (xn, xd) = resolution_rational(g.spacing[0]);
    let (yn, yd) = resolution_rational(g.spacing[1]);
    let mut first = enc.new_directory()?;
    let start = match v {
        AnyVolume::U8(x) => first.write_data(x.data())?,
        AnyVolume::U16(x) => first.write_data(x.data())?,
        AnyVolume::I16(x) => first.write_data(x.data())?,
        AnyVolume::F32(x) => first.write_data(x.data())?,
    };
    let tags = |d: &mut tiff::encoder::DirectoryEncoder<'_, W, K>, k: usize| {
        d.write_tag(Tag::NewSubfileType, 0u32)?;
        d.write_tag(Tag::ImageWidth, nx as u32)?;
        d.write_tag(Tag::ImageLength, ny as u32)?;
        d.write_tag(Tag::BitsPerSample, bits)?;
        d.write_tag(Tag::Compression, 1u16)?;
        d.write_tag(Tag::PhotometricInterpretation, 1u16)?;
        if k == 0 {
            d.write_tag(Tag::ImageDescription, desc)?;
        }
        let offset = start + k as u64 * page_bytes;
        d.write_tag(Tag::StripOffsets, K::convert_offset(offset)?)?;
        d.write_tag(Tag::SamplesPerPixel, 1u16)?;
        d.write_tag(Tag::RowsPerStrip, ny as u32)?;
        d.write_tag(Tag::StripByteCounts, K::convert_offset(page_bytes)?)?;
        d.write_tag(Tag::XResolution, Rational { n: xn, d: xd })?;
        d.write_tag(Tag::YResolution, Rational { n: yn, d: yd })?;
        d.write_tag(Tag::ResolutionUnit, 1u16)?;
        d.write_tag(Tag::SampleFormat, format)
    };
    tags(&mut first, 0)?;
    first.finish()?;
    for k in 1..nz {
        let mut d = enc.new_directory()?;
        tags(&mut d, k)?;
        d.finish()?;
    }
    Ok(())
}

/// Write a volume as a multi-page TIFF with ImageJ metadata, atomically.
pub fn write(path: &Path, v: &AnyVolume) -> Result<(), IoError> {
    raw::write_atomic_with(path, |w| encode(w, path, v))
}

/// The bytes of a multi-page TIFF into `w` (TIFF needs to seek back to its
/// directories); `path` names it in errors.
pub(crate) fn encode(
    w: &mut (impl std::io::Write + std::io::Seek),
    path: &Path,
    v: &AnyVolume,
) -> Result<(), IoError> {
    let g = v.geometry();
    let [nx, ny, _] = g.dims;
    if nx > u32::MAX as usize || ny > u32::MAX as usize {
        return Err(IoError::unsupported(
            path,
            "TIFF pages are at most 2^32-1 pixels wide",
        ));
    }
    let bytes = g.len() * crate::raw::RawType::of(v).size();
    let desc = description(g, v);
    let to_io = |e: TiffError| match e {
        TiffError::IoError(e) => e,
        other => std::io::Error::other(other.to_string()),
    };
    let mut write = || -> std::io::Result<()> {
        // Classic TIFF offsets are 32-bit; leave room for the directories.
        if bytes > (1 << 32) - (1 << 24) {
            write_pages(&mut TiffEncoder::new_big(&mut *w).map_err(to_io)?, v, &desc)
        } else {
            write_pages(&mut TiffEncoder::new(&mut *w).map_err(to_io)?, v, &desc)
        }
        .map_err(to_io)
    };
    write().map_err(|e| IoError::write(path, e))
}
