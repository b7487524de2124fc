//! NIfTI-1 (`.nii`, `.nii.gz`).
//!
//! The header is parsed by the `nifti` crate (both byte orders); the voxel
//! data is read here so that its size is checked against the file before it
//! is allocated. Geometry follows ITK/SimpleITK (LPS): the NIfTI affine maps
//! voxels to RAS, and ITK negates its first two rows, so origin and direction
//! equal SimpleITK's `GetOrigin()`/`GetDirection()` for the same file.
//! Spacing is `pixdim[1..=3]`. The orientation comes from the sform when its
//! code is non-zero and its columns are orthogonal (ITK ≥ 5 prefers it),
//! otherwise from the qform quaternion, otherwise identity with origin 0.
//!
//! `scl_slope`/`scl_inter`: when the slope is 0 or 1 and the intercept 0 the
//! stored values are returned unchanged; otherwise the volume is read as f32
//! with `value * slope + inter` applied (the calibrated values are what the
//! file means). Nothing is ever rescaled on write (slope 1, intercept 0).
#![allow(clippy::needless_range_loop)] // 3x3 matrix code reads best with indices
use crate::limits::{Loaded, ReadLimits, VolumeHeader, Want, try_vec};
use crate::raw::{self, Endian, RawType};
use crate::source::Source;
use crate::{Format, IoError};
use flate2::read::MultiGzDecoder;
use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};
use rayon::prelude::*;
use std::io::{Read, Write};
use std::path::Path;

const NIFTI_XFORM_SCANNER_ANAT: i16 = 1;

fn raw_type(path: &Path, datatype: i16) -> Result<RawType, IoError> {
    Ok(match datatype {
        2 => RawType::U8,
        4 => RawType::I16,
        8 => RawType::I32,
        16 => RawType::F32,
        64 => RawType::F64,
        256 => RawType::I8,
        512 => RawType::U16,
        768 => RawType::U32,
        other => {
            let name = match other {
                32 => "complex64",
                128 => "RGB24",
                1024 => "i64",
                1280 => "u64",
                1536 => "f128",
                1792 => "complex128",
                2048 => "complex256",
                2304 => "RGBA32",
                _ => "unknown",
            };
            return Err(IoError::unsupported(
                path,
                format!("NIfTI datatype {other} ({name}) is not supported"),
            ));
        }
    })
}

fn datatype_code(t: RawType) -> (i16, i16) {
    match t {
        RawType::U8 => (2, 8),
        RawType::I16 => (4, 16),
        RawType::I32 => (8, 32),
        RawType::F32 => (16, 32),
        RawType::F64 => (64, 64),
        RawType::I8 => (256, 8),
        RawType::U16 => (512, 16),
        RawType::U32 => (768, 32),
    }
}

/// Read a `.nii` or `.nii.gz` file or bytes (gzip is detected from the magic bytes).
pub(crate) fn read(src: Source<'_>, limits: &ReadLimits, want: Want) -> Result<Loaded, IoError> {
    use std::io::BufRead;
    let path = src.name;
    let (mut file, file_len) = src.open()?;
    let head = file.fill_buf().map_err(|e| IoError::read(path, e))?;
    let gz = head.len() >= 2 && head[..2] == [0x1f, 0x8b];
    if gz {
        read_from(path, &mut MultiGzDecoder::new(file), None, limits, want)
    } else {
        read_from(path, &mut file, Some(file_len), limits, want)
    }
}

fn read_from(
    path: &Path,
    r: &mut dyn Read,
    file_len: Option<u64>,
    limits: &ReadLimits,
    want: Want,
) -> Result<Loaded, IoError> {
    let mut head = [0u8; 348];
    r.read_exact(&mut head).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => {
            IoError::invalid(path, "not a NIfTI-1 file (shorter than a 348-byte header)")
        }
        _ => IoError::read(path, e),
    })?;
    let sizeof_hdr_le = i32::from_le_bytes(head[0..4].try_into().expect("4 bytes"));
    let sizeof_hdr_be = i32::from_be_bytes(head[0..4].try_into().expect("4 bytes"));
    if sizeof_hdr_le == 540 || sizeof_hdr_be == 540 {
        return Err(IoError::unsupported(
            path,
            "NIfTI-2 files are not supported (save as NIfTI-1)",
        ));
    }
    if sizeof_hdr_le != 348 && sizeof_hdr_be != 348 {
        return Err(IoError::invalid(
            path,
            "not a NIfTI-1 file (header size is not 348)",
        ));
    }
    let h = nifti::NiftiHeader::from_reader(&head[..])
        .map_err(|e| IoError::invalid(path, format!("bad NIfTI header: {e}")))?;
    if &h.magic != b"n+1\0" {
        if &h.magic == b"ni1\0" {
            return Err(IoError::unsupported(
                path,
                "NIfTI header/image pairs (.hdr/.img) are not supported",
            ));
        }
        return Err(IoError::invalid(path, "not a NIfTI-1 file (bad magic)"));
    }
    let endian = match h.endianness {
        nifti::Endianness::Little => Endian::Little,
        nifti::Endianness::Big => Endian::Big,
    };
    // dim values are signed in the standard; the crate reads them as u16.
    let ndim = h.dim[0] as usize;
    if !(1..=7).contains(&ndim) {
        return Err(IoError::invalid(
            path,
            format!("bad dim[0] = {}", h.dim[0] as i16),
        ));
    }
    let mut dims = [1usize; 3];
    for a in 0..ndim {
        let d = h.dim[a + 1] as i16;
        if d <= 0 {
            return Err(IoError::invalid(
                path,
                format!("dim[{}] = {d} is not positive", a + 1),
            ));
        }
        if a < 3 {
            dims[a] = d as usize;
        } else if d != 1 {
            return Err(IoError::unsupported(
                path,
                format!(
                    "{ndim}D NIfTI with dim[{}] = {d} (only 3D volumes are supported)",
                    a + 1
                ),
            ));
        }
    }
    let t = raw_type(path, h.datatype)?;
    let geometry = geometry_of(path, &h, dims, ndim)?;
    let nbytes = limits.array_bytes(path, dims, t)?;
    let vox_offset = h.vox_offset;
    if !(vox_offset.is_finite() && vox_offset >= 348.0 && vox_offset < (1u64 << 31) as f32) {
        return Err(IoError::invalid(
            path,
            format!("bad vox_offset {vox_offset}"),
        ));
    }
    let vox_offset = vox_offset as u64;
    // Extensions are skipped; inside a gzip stream they are inflated too,
    // so they count towards what the read may decompress.
    if file_len.is_none() && (vox_offset - 348).saturating_add(nbytes as u64) > limits.max_bytes {
        return Err(IoError::unsupported(
            path,
            format!(
                "vox_offset {vox_offset} and the voxel data are more than the {} bytes a read may decompress",
                limits.max_bytes
            ),
        ));
    }
    if want == Want::Header {
        return Ok(Loaded::Header(VolumeHeader {
            format: if file_len.is_none() {
                Format::NiftiGz
            } else {
                Format::Nifti
            },
            geometry,
            stored_type: t,
            data_bytes: nbytes as u64,
        }));
    }
    if let Some(len) = file_len {
        let need = vox_offset + nbytes as u64;
        if len < need {
            return Err(IoError::invalid(
                path,
                format!(
                    "file is truncated: header dims {dims:?} need {need} bytes, the file has {len}"
                ),
            ));
        }
    }
    // Skip extensions up to the data.
    std::io::copy(&mut r.take(vox_offset - 348), &mut std::io::sink())
        .map_err(|e| IoError::read(path, e))?;
    let bytes = raw::read_data(path, r, nbytes)?;
    let v = raw::decode_volume(path, geometry, t, endian, &bytes)?;
    drop(bytes);
    let slope = h.scl_slope;
    let inter = h.scl_inter;
    let scaled =
        slope.is_finite() && slope != 0.0 && (slope != 1.0 || (inter.is_finite() && inter != 0.0));
    if !scaled {
        return Ok(Loaded::Volume(v));
    }
    let (s, i) = (
        f64::from(slope),
        if inter.is_finite() {
            f64::from(inter)
        } else {
            0.0
        },
    );
    let f = |x: f64| (x * s + i) as f32;
    let g = v.geometry().clone();
    let mut data: Vec<f32> = try_vec(path, g.len())?;
    match &v {
        AnyVolume::U8(v) => data.par_extend(v.data().par_iter().map(|&x| f(f64::from(x)))),
        AnyVolume::U16(v) => data.par_extend(v.data().par_iter().map(|&x| f(f64::from(x)))),
        AnyVolume::I16(v) => data.par_extend(v.data().par_iter().map(|&x| f(f64::from(x)))),
        AnyVolume::F32(v) => data.par_extend(v.data().par_iter().map(|&x| f(f64::from(x)))),
    }
    Ok(Loaded::Volume(AnyVolume::F32(
        Volume::from_vec(g, data).map_err(|e| IoError::invalid(path, e.to_string()))?,
    )))
}

/// An f32 header value as the f64 of its shortest decimal form, so a
/// spacing of 0.35 stored as f32 reads back as 0.35 (not 0.3499999940...).
fn decimal(x: f32) -> f64 {
    format!("{x}").parse().unwrap_or(f64::from(x))
}

fn unit_of(xyzt_units: u8) -> LengthUnit {
    match xyzt_units & 0x07 {
        1 => LengthUnit::Metre,
        3 => LengthUnit::Micrometre,
        // 2 is mm; 0 (unknown) is read as mm, like ITK does.
        _ => LengthUnit::Millimetre,
    }
}

/// Geometry of a header of `ndim` dimensions. `pixdim` of an axis the file
/// has must be finite and positive (an error, not a silent 1); an axis past
/// `ndim` (a 2D file's z) has no spacing in the file and gets 1.
fn geometry_of(
    path: &Path,
    h: &nifti::NiftiHeader,
    dims: [usize; 3],
    ndim: usize,
) -> Result<Geometry, IoError> {
    let mut spacing = [1.0f64; 3];
    for (a, s) in spacing.iter_mut().enumerate().take(ndim) {
        let p = decimal(h.pixdim[a + 1]);
        if !(p.is_finite() && p > 0.0) {
            return Err(IoError::invalid(
                path,
                format!(
                    "voxel spacing pixdim[{}] = {p} is not a positive number",
                    a + 1
                ),
            ));
        }
        *s = p;
    }
    // RAS affine: columns = axis directions (unit), translation.
    let (dir_ras, origin_ras) = if h.sform_code > 0 && sform_is_rigid(h) {
        sform_direction(h)
    } else if h.qform_code > 0 {
        qform_direction(h)
    } else if h.sform_code > 0 {
        sform_direction(h)
    } else {
        (interslice_core::geometry::IDENTITY_DIRECTION, [0.0; 3])
    };
    let mut direction = dir_ras;
    let mut origin = origin_ras;
    for r in 0..2 {
        origin[r] = -origin[r];
        for c in 0..3 {
            direction[r][c] = -direction[r][c];
        }
    }
    for o in origin.iter_mut() {
        if *o == 0.0 {
            *o = 0.0; // no -0.0
        }
    }
    for row in direction.iter_mut() {
        for x in row.iter_mut() {
            if *x == 0.0 {
                *x = 0.0;
            }
        }
    }
    let g = Geometry {
        dims,
        spacing,
        unit: unit_of(h.xyzt_units),
        origin,
        direction,
    };
    crate::header::checked(path, g)
}

fn srow(h: &nifti::NiftiHeader) -> [[f64; 4]; 3] {
    let c = |r: &[f32; 4]| {
        [
            f64::from(r[0]),
            f64::from(r[1]),
            f64::from(r[2]),
            f64::from(r[3]),
        ]
    };
    [c(&h.srow_x), c(&h.srow_y), c(&h.srow_z)]
}

fn sform_columns(h: &nifti::NiftiHeader) -> [[f64; 3]; 3] {
    // cols[c] = unit vector of axis c.
    let m = srow(h);
    let mut cols = [[0.0; 3]; 3];
    for (c, col) in cols.iter_mut().enumerate() {
        let v = [m[0][c], m[1][c], m[2][c]];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if n > 0.0 && n.is_finite() {
            *col = [v[0] / n, v[1] / n, v[2] / n];
        } else {
            col[c] = 1.0;
        }
    }
    cols
}

fn sform_is_rigid(h: &nifti::NiftiHeader) -> bool {
    let cols = sform_columns(h);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    dot(cols[0], cols[1]).abs() < 1e-4
        && dot(cols[0], cols[2]).abs() < 1e-4
        && dot(cols[1], cols[2]).abs() < 1e-4
}

fn sform_direction(h: &nifti::NiftiHeader) -> ([[f64; 3]; 3], [f64; 3]) {
    let cols = sform_columns(h);
    let mut d = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            d[r][c] = cols[c][r];
        }
    }
    (
        d,
        [
            decimal(h.srow_x[3]),
            decimal(h.srow_y[3]),
            decimal(h.srow_z[3]),
        ],
    )
}

fn qform_direction(h: &nifti::NiftiHeader) -> ([[f64; 3]; 3], [f64; 3]) {
    let (b, c, d) = (
        f64::from(h.quatern_b),
        f64::from(h.quatern_c),
        f64::from(h.quatern_d),
    );
    let a2 = 1.0 - (b * b + c * c + d * d);
    let (a, b, c, d) = if a2 < 1e-7 {
        // a is 0: 180° rotation; renormalise b, c, d.
        let n = (b * b + c * c + d * d).sqrt();
        (0.0, b / n, c / n, d / n)
    } else {
        (a2.sqrt(), b, c, d)
    };
    let qfac = if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
    let mut r = [
        [
            a * a + b * b - c * c - d * d,
            2.0 * (b * c - a * d),
            2.0 * (b * d + a * c),
        ],
        [
            2.0 * (b * c + a * d),
            a * a + c * c - b * b - d * d,
            2.0 * (c * d - a * b),
        ],
        [
            2.0 * (b * d - a * c),
            2.0 * (c * d + a * b),
            a * a + d * d - c * c - b * b,
        ],
    ];
    for row in r.iter_mut() {
        row[2] *= qfac;
    }
    (
        r,
        [
            decimal(h.quatern_x),
            decimal(h.quatern_y),
            decimal(h.quatern_z),
        ],
    )
}

/// Quaternion (b, c, d) and qfac of a rotation-or-reflection matrix, after
/// `nifti_mat44_to_quatern` of the NIfTI reference library (reimplemented:
/// the header fields are defined by that algorithm).
fn quatern_of(m: [[f64; 3]; 3]) -> ([f64; 3], f64) {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let mut r = m;
    let qfac = if det < 0.0 {
        for row in r.iter_mut() {
            row[2] = -row[2];
        }
        -1.0
    } else {
        1.0
    };
    let (r11, r12, r13) = (r[0][0], r[0][1], r[0][2]);
    let (r21, r22, r23) = (r[1][0], r[1][1], r[1][2]);
    let (r31, r32, r33) = (r[2][0], r[2][1], r[2][2]);
    let trace = r11 + r22 + r33 + 1.0;
    let (a, b, c, d);
    if trace > 0.5 {
        let aa = 0.5 * trace.sqrt();
        a = aa;
        b = 0.25 * (r32 - r23) / aa;
        c = 0.25 * (r13 - r31) / aa;
        d = 0.25 * (r21 - r12) / aa;
    } else {
        let xd = 1.0 + r11 - (r22 + r33);
        let yd = 1.0 + r22 - (r11 + r33);
        let zd = 1.0 + r33 - (r11 + r22);
        if xd > 1.0 {
            let bb = 0.5 * xd.sqrt();
            b = bb;
            c = 0.25 * (r12 + r21) / bb;
            d = 0.25 * (r13 + r31) / bb;
            a = 0.25 * (r32 - r23) / bb;
        } else if yd > 1.0 {
            let cc = 0.5 * yd.sqrt();
            c = cc;
            b = 0.25 * (r12 + r21) / cc;
            d = 0.25 * (r23 + r32) / cc;
            a = 0.25 * (r13 - r31) / cc;
        } else {
            let dd = 0.5 * zd.sqrt();
            d = dd;
            b = 0.25 * (r13 + r31) / dd;
            c = 0.25 * (r23 + r32) / dd;
            a = 0.25 * (r21 - r12) / dd;
        }
    }
    let (b, c, d) = if a < 0.0 { (-b, -c, -d) } else { (b, c, d) };
    ([b, c, d], qfac)
}

fn unit_code(u: LengthUnit) -> u8 {
    match u {
        LengthUnit::Metre => 1,
        LengthUnit::Millimetre => 2,
        LengthUnit::Micrometre => 3,
        LengthUnit::Unknown => 0,
    }
}

/// The 352 bytes (header + empty extension flag) written before the data.
fn header_bytes(g: &Geometry, t: RawType) -> Vec<u8> {
    let mut b = Vec::with_capacity(352);
    let i16s = |b: &mut Vec<u8>, x: i16| b.extend_from_slice(&x.to_le_bytes());
    let f32s = |b: &mut Vec<u8>, x: f64| b.extend_from_slice(&(x as f32).to_le_bytes());
    b.extend_from_slice(&348i32.to_le_bytes()); // sizeof_hdr
    b.extend_from_slice(&[0u8; 10]); // data_type
    b.extend_from_slice(&[0u8; 18]); // db_name
    b.extend_from_slice(&0i32.to_le_bytes()); // extents
    i16s(&mut b, 0); // session_error
    b.push(b'r'); // regular
    b.push(0); // dim_info
    let dims = [
        3i16,
        g.dims[0] as i16,
        g.dims[1] as i16,
        g.dims[2] as i16,
        1,
        1,
        1,
        1,
    ];
    for d in dims {
        i16s(&mut b, d);
    }
    for _ in 0..3 {
        f32s(&mut b, 0.0); // intent_p1..3
    }
    i16s(&mut b, 0); // intent_code
    let (code, bitpix) = datatype_code(t);
    i16s(&mut b, code);
    i16s(&mut b, bitpix);
    i16s(&mut b, 0); // slice_start
    // Direction back to RAS.
    let mut ras = g.direction;
    let mut org = g.origin;
    for r in 0..2 {
        org[r] = -org[r];
        for c in 0..3 {
            ras[r][c] = -ras[r][c];
        }
    }
    let (q, qfac) = quatern_of(ras);
    let pixdim = [
        qfac,
        g.spacing[0],
        g.spacing[1],
        g.spacing[2],
        1.0,
        1.0,
        1.0,
        1.0,
    ];
    for p in pixdim {
        f32s(&mut b, p);
    }
    f32s(&mut b, 352.0); // vox_offset
    f32s(&mut b, 1.0); // scl_slope
    f32s(&mut b, 0.0); // scl_inter
    i16s(&mut b, 0); // slice_end
    b.push(0); // slice_code
    b.push(unit_code(g.unit) | 8); // xyzt_units: space unit | seconds
    f32s(&mut b, 0.0); // cal_max
    f32s(&mut b, 0.0); // cal_min
    f32s(&mut b, 0.0); // slice_duration
    f32s(&mut b, 0.0); // toffset
    b.extend_from_slice(&0i32.to_le_bytes()); // glmax
    b.extend_from_slice(&0i32.to_le_bytes()); // glmin
    let mut descrip = [0u8; 80];
    let text = b"interslice";
    descrip[..text.len()].copy_from_slice(text);
    b.extend_from_slice(&descrip);
    b.extend_from_slice(&[0u8; 24]); // aux_file
    i16s(&mut b, NIFTI_XFORM_SCANNER_ANAT); // qform_code
    i16s(&mut b, NIFTI_XFORM_SCANNER_ANAT); // sform_code
    for x in q {
        f32s(&mut b, x);
    }
    for x in org {
        f32s(&mut b, x);
    }
    for r in 0..3 {
        for c in 0..3 {
            f32s(&mut b, ras[r][c] * g.spacing[c]);
        }
        f32s(&mut b, org[r]);
    }
    b.extend_from_slice(&[0u8; 16]); // intent_name
    b.extend_from_slice(b"n+1\0");
    debug_assert_eq!(b.len(), 348);
    b.extend_from_slice(&[0u8; 4]); // no extensions
    b
}

/// Write a `.nii` (or, with `gz`, `.nii.gz`) file atomically.
pub fn write(path: &Path, v: &AnyVolume, gz: bool) -> Result<(), IoError> {
    raw::write_atomic_with(path, |w| encode(w, path, v, gz))
}

/// The bytes of a `.nii` (or `.nii.gz`) file into `w`; `path` names it in errors.
pub(crate) fn encode(
    w: &mut impl Write,
    path: &Path,
    v: &AnyVolume,
    gz: bool,
) -> Result<(), IoError> {
    let g = v.geometry();
    if g.dims.iter().any(|&d| d > i16::MAX as usize) {
        return Err(IoError::unsupported(
            path,
            format!("NIfTI-1 dims are at most 32767, got {:?}", g.dims),
        ));
    }
    let head = header_bytes(g, RawType::of(v));
    let data = v.to_le_bytes();
    let write = || -> std::io::Result<()> {
        if gz {
            let mut e = flate2::write::GzEncoder::new(w, flate2::Compression::fast());
            e.write_all(&head)?;
            e.write_all(&data)?;
            e.finish()?;
        } else {
            w.write_all(&head)?;
            w.write_all(&data)?;
        }
        Ok(())
    };
    write().map_err(|e| IoError::write(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternion_round_trips_through_header_math() {
        // A rotation about z by 30° combined with a flip of the third axis.
        let (s, c) = (0.5f64, 0.75f64.sqrt());
        let m = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, -1.0]];
        let (q, qfac) = quatern_of(m);
        let h = nifti::NiftiHeader {
            quatern_b: q[0] as f32,
            quatern_c: q[1] as f32,
            quatern_d: q[2] as f32,
            pixdim: [qfac as f32, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
            ..Default::default()
        };
        let (back, _) = qform_direction(&h);
        for r in 0..3 {
            for cc in 0..3 {
                assert!((back[r][cc] - m[r][cc]).abs() < 1e-6, "{back:?} vs {m:?}");
            }
        }
    }
}
