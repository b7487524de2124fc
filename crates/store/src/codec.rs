//! Compact blobs for masks and label volumes: bit-packed or little-endian, then
//! DEFLATE (a 512³ mask is 16 MiB packed and usually a few hundred KiB stored).
use crate::{Result, StoreError};
use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use interslice_core::le::{decode_le, encode_le};
use std::io::{Read, Write};

fn deflate(bytes: &[u8]) -> Vec<u8> {
    let mut enc = DeflateEncoder::new(Vec::new(), Compression::fast());
    // Writing to a Vec cannot fail.
    enc.write_all(bytes).expect("write to Vec");
    enc.finish().expect("finish to Vec")
}

fn inflate(blob: &[u8], expected: usize) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(expected);
    DeflateDecoder::new(blob)
        .take(expected as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| StoreError::Corrupt(e.to_string()))?;
    if out.len() != expected {
        return Err(StoreError::Corrupt(format!(
            "blob holds {} bytes, expected {expected}",
            out.len()
        )));
    }
    Ok(out)
}

/// Pack booleans 8 to a byte (LSB first) and deflate.
pub fn encode_mask(mask: &[bool]) -> Vec<u8> {
    let mut packed = vec![0u8; mask.len().div_ceil(8)];
    for (i, &b) in mask.iter().enumerate() {
        if b {
            packed[i / 8] |= 1 << (i % 8);
        }
    }
    deflate(&packed)
}

/// Inverse of [`encode_mask`] for `len` voxels.
pub fn decode_mask(blob: &[u8], len: usize) -> Result<Vec<bool>> {
    let packed = inflate(blob, len.div_ceil(8))?;
    Ok((0..len)
        .map(|i| packed[i / 8] & (1 << (i % 8)) != 0)
        .collect())
}

/// Little-endian u16 and deflate.
pub fn encode_labels(labels: &[u16]) -> Vec<u8> {
    deflate(&encode_le(labels))
}

/// Inverse of [`encode_labels`] for `len` voxels.
pub fn decode_labels(blob: &[u8], len: usize) -> Result<Vec<u16>> {
    let bytes = inflate(blob, len * 2)?;
    decode_le(&bytes).ok_or_else(|| StoreError::Corrupt("odd label byte count".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_round_trip() {
        let m: Vec<bool> = (0..1001).map(|i| i % 3 == 0 || i % 7 == 1).collect();
        assert_eq!(decode_mask(&encode_mask(&m), m.len()).unwrap(), m);
        assert!(decode_mask(&encode_mask(&m), m.len() + 100).is_err());
    }

    #[test]
    fn labels_round_trip() {
        let l: Vec<u16> = (0..777).map(|i| (i * 37 % 65536) as u16).collect();
        assert_eq!(decode_labels(&encode_labels(&l), l.len()).unwrap(), l);
        assert!(decode_labels(b"not deflate", 10).is_err());
    }
}
