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
use crate::IoError;
use crate::planes::{Plane, Stack, resolution_rational, unit_with_scale};
use crate::raw::{self, MAX_VOXELS};
use interslice_core::geometry::IDENTITY_DIRECTION;
use interslice_core::{AnyVolume, Geometry, LengthUnit};
use std::collections::HashMap;
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

/// Read the current page of a decoder as a gray plane.
pub fn read_page<R: std::io::Read + std::io::Seek>(
    path: &Path,
    d: &mut Decoder<R>,
) -> Result<(usize, usize, Plane), IoError> {
    let (w, h) = d.dimensions().map_err(|e| tiff_err(path, e))?;
    match d.colortype().map_err(|e| tiff_err(path, e))? {
        ColorType::Gray(_) => {}
        other => {
            return Err(IoError::unsupported(
                path,
                format!("TIFF colour type {other:?} is not supported (gray images only)"),
            ));
        }
    }
    let plane = match d.read_image().map_err(|e| tiff_err(path, e))? {
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
    Ok((w as usize, h as usize, plane))
}

/// The `key=value` lines of an ImageJ description, or None.
fn imagej_description<R: std::io::Read + std::io::Seek>(
    d: &mut Decoder<R>,
) -> Option<HashMap<String, String>> {
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

fn rational<R: std::io::Read + std::io::Seek>(d: &mut Decoder<R>, tag: Tag) -> Option<f64> {
    match d.find_tag(tag).ok()?? {
        tiff::decoder::ifd::Value::Rational(n, den) if n > 0 && den > 0 => {
            Some(f64::from(n) / f64::from(den))
        }
        tiff::decoder::ifd::Value::Float(f) if f > 0.0 => Some(f64::from(f)),
        tiff::decoder::ifd::Value::Double(f) if f > 0.0 => Some(f),
        _ => None,
    }
}

fn parse3(s: &str) -> Option<[f64; 3]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse().ok())
        .collect::<Option<_>>()?;
    v.try_into().ok()
}

/// Spacing, unit, origin and direction of the first page (dims left 1).
pub(crate) fn geometry_of<R: std::io::Read + std::io::Seek>(d: &mut Decoder<R>) -> Geometry {
    let mut g = Geometry {
        dims: [1; 3],
        spacing: [1.0; 3],
        unit: LengthUnit::Unknown,
        origin: [0.0; 3],
        direction: IDENTITY_DIRECTION,
    };
    let Some(desc) = imagej_description(d) else {
        return g;
    };
    let (unit, scale) = desc
        .get("unit")
        .map(|u| unit_with_scale(u))
        .unwrap_or((LengthUnit::Unknown, 1.0));
    g.unit = unit;
    let valid = |x: f64| x.is_finite() && x > 0.0;
    if let Some(x) = rational(d, Tag::XResolution).filter(|&x| valid(1.0 / x)) {
        g.spacing[0] = scale / x;
    }
    g.spacing[1] = match rational(d, Tag::YResolution).filter(|&y| valid(1.0 / y)) {
        Some(y) => scale / y,
        None => g.spacing[0],
    };
    if let Some(z) = desc
        .get("spacing")
        .and_then(|s| s.parse::<f64>().ok())
        .filter(|&z| valid(z))
    {
        g.spacing[2] = z.abs() * scale;
    } else {
        g.spacing[2] = g.spacing[0];
    }
    if let Some(o) = desc.get("interslice.origin").and_then(|s| parse3(s)) {
        g.origin = o;
    }
    if let Some(dir) = desc.get("interslice.direction").and_then(|s| {
        let v: Vec<f64> = s
            .split(',')
            .map(|x| x.trim().parse().ok())
            .collect::<Option<_>>()?;
        <[f64; 9]>::try_from(v).ok()
    }) {
        g.direction = [
            [dir[0], dir[1], dir[2]],
            [dir[3], dir[4], dir[5]],
            [dir[6], dir[7], dir[8]],
        ];
    }
    g
}

/// Open a TIFF decoder with limits that allow large pages but not absurd ones.
pub fn decoder(path: &Path) -> Result<Decoder<std::io::BufReader<std::fs::File>>, IoError> {
    let f = raw::open(path)?;
    let mut limits = Limits::default();
    limits.decoding_buffer_size = MAX_VOXELS.min(usize::MAX / 4);
    limits.intermediate_buffer_size = 1 << 30;
    Ok(Decoder::new(f)
        .map_err(|e| tiff_err(path, e))?
        .with_limits(limits))
}

/// Read a multi-page TIFF as a volume.
pub fn read(path: &Path) -> Result<AnyVolume, IoError> {
    let mut d = decoder(path)?;
    let mut g = geometry_of(&mut d);
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
    let mut stack = Stack::default();
    let mut voxels = 0usize;
    loop {
        let (w, h, plane) = read_page(path, &mut d)?;
        voxels = voxels.saturating_add(w * h);
        if voxels > MAX_VOXELS {
            return Err(IoError::unsupported(path, "TIFF stack is too large"));
        }
        stack.push(path, w, h, plane)?;
        if !d.more_images() {
            break;
        }
        d.next_image().map_err(|e| tiff_err(path, e))?;
    }
    g.dims = [1; 3];
    stack.finish(path, g)
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
    raw::write_atomic(path, |w| {
        // Classic TIFF offsets are 32-bit; leave room for the directories.
        if bytes > (1 << 32) - (1 << 24) {
            write_pages(&mut TiffEncoder::new_big(&mut *w).map_err(to_io)?, v, &desc)
        } else {
            write_pages(&mut TiffEncoder::new(&mut *w).map_err(to_io)?, v, &desc)
        }
        .map_err(to_io)
    })
}
