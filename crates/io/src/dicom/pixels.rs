//! Pixel data of an arranged series: decoded by `dicom-pixeldata` (native,
//! deflate, RLE and JPEG baseline/extended/lossless transfer syntaxes), the
//! stored values extracted here (BitsStored/HighBit masking and sign
//! extension: the crate's unrescaled path ignores BitsStored), then the
//! modality rescale applied and the narrowest lossless voxel type chosen.
use super::header::{FileHeader, PixelFormat};
use super::series::{Arranged, Plane};
use crate::IoError;
use crate::raw::RawType;
use dicom_dictionary_std::tags;
use dicom_pixeldata::PixelDecoder;
use dicom_transfer_syntax_registry::{TransferSyntaxIndex, TransferSyntaxRegistry};
use interslice_core::{AnyVolume, Geometry, Volume};
use rayon::prelude::*;
use std::path::Path;

/// Largest integer an f32 holds exactly (2^24).
const F32_EXACT: i64 = 1 << 24;

/// Err, naming the syntax, when the file's pixel data cannot be decoded here.
pub(crate) fn check_transfer_syntax(h: &FileHeader) -> Result<(), IoError> {
    let uid = h.transfer_syntax.as_str();
    match TransferSyntaxRegistry.get(uid) {
        None => Err(IoError::unsupported(
            &h.path,
            format!("unknown DICOM transfer syntax {uid}"),
        )),
        Some(ts) if !ts.can_decode_all() => Err(IoError::unsupported(
            &h.path,
            format!(
                "DICOM transfer syntax {} ({uid}) cannot be decoded (readable: uncompressed, deflate, RLE, JPEG baseline, extended and lossless)",
                ts.name()
            ),
        )),
        Some(_) => Ok(()),
    }
}

/// Most bytes of pixels a compressed file may decode to, per byte of file
/// (deflate tops out near 1032:1, RLE at 64:1, JPEG lower still).
const MAX_COMPRESSION: u64 = 1024;

/// Err when the file is too small to hold the pixels its header claims
/// (uncompressed), or would decode to more than [`MAX_COMPRESSION`] times
/// its size: checked before any pixel memory is allocated.
fn check_file_size(h: &FileHeader, px: PixelFormat) -> Result<(), IoError> {
    let len = std::fs::metadata(&h.path)
        .map_err(|e| IoError::read(&h.path, e))?
        .len();
    let need = (h.rows * h.cols * px.bytes()) as u64 * h.frames.len() as u64;
    let native = TransferSyntaxRegistry
        .get(&h.transfer_syntax)
        .is_some_and(|ts| ts.is_codec_free());
    if native && len < need {
        return Err(IoError::invalid(
            &h.path,
            format!(
                "file is truncated: {} x {} x {} frames of {}-bit pixels need {need} bytes, the file has {len}",
                h.cols,
                h.rows,
                h.frames.len(),
                px.bits_allocated
            ),
        ));
    }
    if need > len.saturating_mul(MAX_COMPRESSION) {
        return Err(IoError::invalid(
            &h.path,
            format!(
                "{} x {} x {} frames would decode to {need} bytes, more than {MAX_COMPRESSION} times the file's {len}",
                h.cols,
                h.rows,
                h.frames.len()
            ),
        ));
    }
    Ok(())
}

/// Read the pixels of every plane and make the volume.
pub(crate) fn read(dir: &Path, files: &[FileHeader], a: &Arranged) -> Result<AnyVolume, IoError> {
    let plane_len = a.geometry.dims[0] * a.geometry.dims[1];
    // Bounds the allocation below (dims come from headers).
    crate::limits::ReadLimits::default().array_bytes(dir, a.geometry.dims, RawType::I32)?;
    let used: Vec<bool> = (0..files.len())
        .map(|i| a.planes.iter().any(|p| p.file == i))
        .collect();
    for (h, _) in files.iter().zip(&used).filter(|(_, u)| **u) {
        check_transfer_syntax(h)?;
        check_file_size(h, a.pixel)?;
    }
    let mut stored = vec![0i32; a.geometry.len()];
    let mut by_file: Vec<Vec<(usize, &mut [i32])>> = (0..files.len()).map(|_| Vec::new()).collect();
    for (p, chunk) in a.planes.iter().zip(stored.chunks_mut(plane_len)) {
        by_file[p.file].push((p.frame, chunk));
    }
    by_file
        .into_par_iter()
        .enumerate()
        .filter(|(_, frames)| !frames.is_empty())
        .try_for_each(|(i, frames)| decode_file(&files[i], a.pixel, frames))?;
    finish(dir, a.geometry.clone(), stored, &a.planes, a.pixel)
}

/// Decode one file and unpack the wanted frames into their planes.
fn decode_file(
    h: &FileHeader,
    pixel: PixelFormat,
    frames: Vec<(usize, &mut [i32])>,
) -> Result<(), IoError> {
    let path = h.path.as_path();
    let bytes = super::header::load(path)?;
    let obj = super::header::parse(path, &bytes, true)?;
    let n_frames = h.frames.len();
    match obj.get(tags::PIXEL_DATA).map(|e| e.value()) {
        None => return Err(IoError::invalid(path, "no PixelData")),
        // Every frame starts a new fragment: bounds what a decoder allocates.
        Some(dicom_core::DicomValue::PixelSequence(seq)) if seq.fragments().len() < n_frames => {
            return Err(IoError::invalid(
                path,
                format!(
                    "{} compressed fragments for {n_frames} frames",
                    seq.fragments().len()
                ),
            ));
        }
        Some(_) => {}
    }
    let decoded = obj
        .decode_pixel_data()
        .map_err(|e| IoError::invalid(path, format!("cannot decode the pixel data: {e}")))?;
    let data = decoded.data();
    let frame_bytes = h.rows * h.cols * pixel.bytes();
    if data.len() < n_frames * frame_bytes {
        return Err(IoError::invalid(
            path,
            format!(
                "pixel data has {} bytes but {} x {} x {n_frames} frames of {}-bit pixels need {}",
                data.len(),
                h.cols,
                h.rows,
                pixel.bits_allocated,
                n_frames * frame_bytes
            ),
        ));
    }
    for (k, out) in frames {
        unpack(&data[k * frame_bytes..(k + 1) * frame_bytes], pixel, out);
    }
    Ok(())
}

/// Stored values of one plane: the `bits_stored` bits ending at `high_bit`
/// of each sample, sign-extended when signed (other bits may hold overlays).
fn unpack(bytes: &[u8], px: PixelFormat, out: &mut [i32]) {
    let shift = u32::from(px.high_bit + 1 - px.bits_stored);
    let bits = u32::from(px.bits_stored);
    let mask = (1u32 << bits) - 1;
    let sign = 1u32 << (bits - 1);
    let value = |raw: u32| {
        let v = (raw >> shift) & mask;
        if px.signed && v & sign != 0 {
            v as i32 - (1i32 << bits)
        } else {
            v as i32
        }
    };
    if px.bits_allocated == 8 {
        for (o, &b) in out.iter_mut().zip(bytes) {
            *o = value(u32::from(b));
        }
    } else {
        // Decoded pixel data is in the machine's byte order.
        for (o, c) in out.iter_mut().zip(bytes.chunks_exact(2)) {
            *o = value(u32::from(u16::from_ne_bytes([c[0], c[1]])));
        }
    }
}

/// Apply each plane's RescaleSlope/Intercept and pick the voxel type.
///
/// Slope 1 with integral intercepts (CT in HU, most MR) stays integer: the
/// stored type when the rescaled values fit it, else whichever of u16 and
/// i16 holds them, else f32 when every value is exact there. Any other slope
/// or intercept gives f32 `stored * slope + intercept`.
fn finish(
    dir: &Path,
    geometry: Geometry,
    mut values: Vec<i32>,
    planes: &[Plane],
    px: PixelFormat,
) -> Result<AnyVolume, IoError> {
    let plane_len = geometry.dims[0] * geometry.dims[1];
    let bad = |e: interslice_core::CoreError| IoError::invalid(dir, e.to_string());
    let integer = planes
        .iter()
        .all(|p| p.slope == 1.0 && p.intercept.fract() == 0.0 && p.intercept.abs() <= 1e9);
    if !integer {
        let data: Vec<f32> = values
            .par_chunks(plane_len)
            .zip(planes)
            .flat_map_iter(|(chunk, p)| {
                chunk
                    .iter()
                    .map(move |&v| (f64::from(v) * p.slope + p.intercept) as f32)
            })
            .collect();
        return Ok(AnyVolume::F32(
            Volume::from_vec(geometry, data).map_err(bad)?,
        ));
    }
    values
        .par_chunks_mut(plane_len)
        .zip(planes)
        .filter(|(_, p)| p.intercept != 0.0)
        .for_each(|(chunk, p)| {
            let b = p.intercept as i32;
            chunk.iter_mut().for_each(|v| *v += b);
        });
    let (lo, hi) = values
        .par_iter()
        .fold(|| (i32::MAX, i32::MIN), |(l, h), &x| (l.min(x), h.max(x)))
        .reduce(|| (i32::MAX, i32::MIN), |a, b| (a.0.min(b.0), a.1.max(b.1)));
    let fits = |min: i64, max: i64| i64::from(lo) >= min && i64::from(hi) <= max;
    let fits_u8 = fits(0, 255);
    let fits_u16 = fits(0, 65535);
    let fits_i16 = fits(-32768, 32767);
    Ok(if px.bits_allocated == 8 && !px.signed && fits_u8 {
        AnyVolume::U8(
            Volume::from_vec(geometry, values.par_iter().map(|&v| v as u8).collect())
                .map_err(bad)?,
        )
    } else if (px.signed || !fits_u16) && fits_i16 {
        AnyVolume::I16(
            Volume::from_vec(geometry, values.par_iter().map(|&v| v as i16).collect())
                .map_err(bad)?,
        )
    } else if fits_u16 {
        AnyVolume::U16(
            Volume::from_vec(geometry, values.par_iter().map(|&v| v as u16).collect())
                .map_err(bad)?,
        )
    } else if fits(-F32_EXACT, F32_EXACT) {
        AnyVolume::F32(
            Volume::from_vec(geometry, values.par_iter().map(|&v| v as f32).collect())
                .map_err(bad)?,
        )
    } else {
        return Err(IoError::unsupported(
            dir,
            format!("rescaled values {lo}..={hi} do not fit 16 bits nor exactly in 32-bit float"),
        ));
    })
}
