//! Raw voxel buffers shared by the formats that store a plain array
//! (NIfTI, NRRD, MetaImage): element types, byte order, lossless
//! conversion into [`AnyVolume`], bounded reading and atomic writing.
use crate::IoError;
use crate::limits::try_vec;
use interslice_core::{AnyVolume, Geometry, Volume};
use rayon::prelude::*;
use std::io::{BufWriter, Read, Write};
use std::path::Path;

/// Byte order of a stored array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endian {
    /// Least significant byte first (every format we write).
    Little,
    /// Most significant byte first.
    Big,
}

/// Element types found in files. Types wider than the four in-memory
/// types are converted only when every value fits exactly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RawType {
    /// unsigned 8-bit
    U8,
    /// signed 8-bit (stored as i16 in memory)
    I8,
    /// unsigned 16-bit
    U16,
    /// signed 16-bit
    I16,
    /// unsigned 32-bit (narrowed to u16/i16 when the values fit)
    U32,
    /// signed 32-bit (narrowed to u16/i16 when the values fit)
    I32,
    /// 32-bit float
    F32,
    /// 64-bit float (narrowed to f32 when every value is exact in f32)
    F64,
}

impl RawType {
    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            RawType::U8 | RawType::I8 => 1,
            RawType::U16 | RawType::I16 => 2,
            RawType::U32 | RawType::I32 | RawType::F32 => 4,
            RawType::F64 => 8,
        }
    }

    /// The raw type that stores a volume's voxel type.
    pub fn of(v: &AnyVolume) -> RawType {
        match v {
            AnyVolume::U8(_) => RawType::U8,
            AnyVolume::U16(_) => RawType::U16,
            AnyVolume::I16(_) => RawType::I16,
            AnyVolume::F32(_) => RawType::F32,
        }
    }
}

/// Read exactly `len` bytes from `r`. The buffer grows only as data arrives
/// (at most 64 MiB is reserved ahead), so a header that lies about the size
/// of a short file fails with "truncated" instead of allocating the lie.
pub fn read_exact_bounded<R: Read + ?Sized>(
    path: &Path,
    r: &mut R,
    len: usize,
) -> Result<Vec<u8>, IoError> {
    let mut buf: Vec<u8> = Vec::new();
    let mut filled = 0;
    while filled < len {
        if filled == buf.len() {
            // Grow by doubling (64 MiB at first), never past `len`.
            let grow = buf.len().max(64 << 20).min(len - buf.len());
            buf.try_reserve_exact(grow).map_err(|_| {
                IoError::unsupported(
                    path,
                    format!("not enough memory for {len} bytes of voxel data"),
                )
            })?;
            buf.resize(buf.len() + grow, 0);
        }
        match r.read(&mut buf[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(IoError::read(path, e)),
        }
    }
    buf.truncate(filled);
    if buf.len() < len {
        return Err(IoError::invalid(
            path,
            format!(
                "file is truncated: the header needs {len} bytes of voxel data, found {}",
                buf.len()
            ),
        ));
    }
    Ok(buf)
}

/// Read exactly `len` bytes of voxel data that must be all the stream holds:
/// fewer is a truncated file, more means the header's dims do not match the
/// data. Reading to the end also checks a gzip or zlib stream's checksum.
/// At most one small buffer past `len` is read, so a stream that inflates
/// without end is refused at once.
pub fn read_data<R: Read + ?Sized>(path: &Path, r: &mut R, len: usize) -> Result<Vec<u8>, IoError> {
    let buf = read_exact_bounded(path, r, len)?;
    let mut extra = [0u8; 4096];
    loop {
        match r.read(&mut extra) {
            Ok(0) => return Ok(buf),
            Ok(_) => {
                return Err(IoError::invalid(
                    path,
                    format!(
                        "the voxel data is longer than the {len} bytes the header's dims need (dims do not match the data)"
                    ),
                ));
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(IoError::read(path, e)),
        }
    }
}

/// Decode every N-byte element, into a vector allocated fallibly.
fn decode<T: Send, const N: usize>(
    path: &Path,
    bytes: &[u8],
    endian: Endian,
    f: impl Fn([u8; N]) -> T + Sync + Send,
) -> Result<Vec<T>, IoError> {
    let mut out = try_vec(path, bytes.len() / N)?;
    out.par_extend(elements(bytes, endian).map(f));
    Ok(out)
}

/// The N-byte elements of an array in native order.
fn elements<const N: usize>(
    bytes: &[u8],
    endian: Endian,
) -> impl IndexedParallelIterator<Item = [u8; N]> + '_ {
    bytes
        .par_chunks_exact(N)
        .with_min_len(1 << 14)
        .map(move |c| {
            let mut a: [u8; N] = c.try_into().expect("chunk of N bytes");
            if endian == Endian::Big {
                a.reverse();
            }
            a
        })
}

/// Decode a raw array (x-fastest) into a volume, converting losslessly:
/// i8 → i16; u32/i32 → u16 or i16 when every value fits; f64 → f32 when every
/// value is exact in f32. Anything else is refused, never rescaled.
pub fn decode_volume(
    path: &Path,
    geometry: Geometry,
    t: RawType,
    endian: Endian,
    bytes: &[u8],
) -> Result<AnyVolume, IoError> {
    let n = geometry.len();
    if bytes.len() != n * t.size() {
        return Err(IoError::invalid(
            path,
            format!(
                "voxel data has {} bytes but dims {:?} need {}",
                bytes.len(),
                geometry.dims,
                n * t.size()
            ),
        ));
    }
    let bad = |e: interslice_core::CoreError| IoError::invalid(path, e.to_string());
    // Wide types are checked on the bytes, then converted straight into the
    // narrow type: no wide copy of the volume is ever made.
    let v = match t {
        RawType::U8 => {
            let mut data = try_vec(path, n)?;
            data.extend_from_slice(bytes);
            AnyVolume::U8(Volume::from_vec(geometry, data).map_err(bad)?)
        }
        RawType::I8 => AnyVolume::I16(
            Volume::from_vec(
                geometry,
                decode(path, bytes, endian, |a: [u8; 1]| i16::from(a[0] as i8))?,
            )
            .map_err(bad)?,
        ),
        RawType::U16 => AnyVolume::U16(
            Volume::from_vec(geometry, decode(path, bytes, endian, u16::from_le_bytes)?)
                .map_err(bad)?,
        ),
        RawType::I16 => AnyVolume::I16(
            Volume::from_vec(geometry, decode(path, bytes, endian, i16::from_le_bytes)?)
                .map_err(bad)?,
        ),
        RawType::F32 => AnyVolume::F32(
            Volume::from_vec(geometry, decode(path, bytes, endian, f32::from_le_bytes)?)
                .map_err(bad)?,
        ),
        RawType::U32 | RawType::I32 => {
            let signed = t == RawType::I32;
            let wide = move |a: [u8; 4]| {
                if signed {
                    i64::from(i32::from_le_bytes(a))
                } else {
                    i64::from(u32::from_le_bytes(a))
                }
            };
            let (lo, hi) = elements(bytes, endian)
                .map(wide)
                .fold(|| (i64::MAX, i64::MIN), |(l, h), x| (l.min(x), h.max(x)))
                .reduce(|| (i64::MAX, i64::MIN), |a, b| (a.0.min(b.0), a.1.max(b.1)));
            if lo >= 0 && hi <= i64::from(u16::MAX) {
                AnyVolume::U16(
                    Volume::from_vec(geometry, decode(path, bytes, endian, |a| wide(a) as u16)?)
                        .map_err(bad)?,
                )
            } else if lo >= i64::from(i16::MIN) && hi <= i64::from(i16::MAX) {
                AnyVolume::I16(
                    Volume::from_vec(geometry, decode(path, bytes, endian, |a| wide(a) as i16)?)
                        .map_err(bad)?,
                )
            } else if lo >= -F32_EXACT_INT && hi <= F32_EXACT_INT {
                // Counts beyond 16 bits (photon counting, some micro-CT) are
                // whole numbers up to 2^24 that f32 holds exactly.
                AnyVolume::F32(
                    Volume::from_vec(geometry, decode(path, bytes, endian, |a| wide(a) as f32)?)
                        .map_err(bad)?,
                )
            } else {
                return Err(IoError::unsupported(
                    path,
                    format!(
                        "32-bit integer values {lo}..={hi} fit neither 16 bits nor exactly in 32-bit float (|value| <= 16777216)"
                    ),
                ));
            }
        }
        RawType::F64 => {
            // Rounded to the nearest f32: a relative change of at most 6e-8,
            // far below what any scanner measures, and the only way a float64
            // file (what most analysis packages save) can be traced on. A
            // finite value beyond f32's range would become infinite: refused.
            if let Some(x) = elements(bytes, endian)
                .map(f64::from_le_bytes)
                .find_any(|x| x.is_finite() && (*x as f32).is_infinite())
            {
                return Err(IoError::unsupported(
                    path,
                    format!("64-bit float value {x:e} is beyond the 32-bit float range (±3.4e38)"),
                ));
            }
            AnyVolume::F32(
                Volume::from_vec(
                    geometry,
                    decode(path, bytes, endian, |a| f64::from_le_bytes(a) as f32)?,
                )
                .map_err(bad)?,
            )
        }
    };
    Ok(v)
}

/// The largest whole number every f32 holds exactly (2^24).
const F32_EXACT_INT: i64 = 1 << 24;

/// Write a file atomically: `f` writes into a temporary file in the same
/// directory, which is renamed over `path` only when everything succeeded.
/// On any error the temporary file is removed and `path` is untouched.
pub fn write_atomic(
    path: &Path,
    f: impl FnOnce(&mut BufWriter<&std::fs::File>) -> std::io::Result<()>,
) -> Result<(), IoError> {
    write_atomic_with(path, |w| f(w).map_err(|e| IoError::write(path, e)))
}

/// [`write_atomic`] for an encoder that reports its own errors (a format's
/// one-file writer, which checks what it writes before and while writing).
pub fn write_atomic_with(
    path: &Path,
    f: impl FnOnce(&mut BufWriter<&std::fs::File>) -> Result<(), IoError>,
) -> Result<(), IoError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| IoError::write(path, e))?;
    {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.as_file());
        f(&mut w)?;
        w.flush().map_err(|e| IoError::write(path, e))?;
    }
    // A temporary file is created private (0600); give the result the
    // permissions a plain `File::create` would.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = 0o666 & !umask();
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(mode))
            .map_err(|e| IoError::write(path, e))?;
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| IoError::write(path, e))?;
    tmp.persist(path)
        .map_err(|e| IoError::write(path, e.error))?;
    Ok(())
}

/// Open a file for reading with a path-naming error.
pub fn open(path: &Path) -> Result<std::io::BufReader<std::fs::File>, IoError> {
    let f = std::fs::File::open(path).map_err(|e| IoError::read(path, e))?;
    Ok(std::io::BufReader::with_capacity(1 << 20, f))
}

/// The process umask (read from /proc; 022 when it cannot be read), so
/// written files get the permissions a plain `File::create` would give.
#[cfg(unix)]
pub(crate) fn umask() -> u32 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("Umask:"))
                .and_then(|m| u32::from_str_radix(m.trim(), 8).ok())
        })
        .unwrap_or(0o022)
}
