//! Little-endian voxel bytes: the one byte encoding of voxel values in the
//! workspace, x-fastest like the volumes themselves. The raw, NRRD, NIfTI and
//! MetaImage writers, the slice bytes the server sends and the label volumes
//! the store keeps all use it, so a volume written one way reads back the
//! same through any other.
use crate::AnyVolume;
use rayon::prelude::*;
use std::ops::Range;

/// A voxel type with a fixed-size little-endian byte form.
pub trait LeBytes: Copy + Send + Sync {
    /// Bytes per value.
    const SIZE: usize;
    /// The little-endian bytes of one value.
    type Bytes: IntoIterator<Item = u8>;
    /// The little-endian bytes of `self`.
    fn le(self) -> Self::Bytes;
    /// The value of `SIZE` little-endian bytes.
    fn from_le(bytes: &[u8]) -> Self;
}

macro_rules! le_bytes {
    ($($t:ty),*) => {$(
        impl LeBytes for $t {
            const SIZE: usize = std::mem::size_of::<$t>();
            type Bytes = [u8; std::mem::size_of::<$t>()];
            fn le(self) -> Self::Bytes {
                self.to_le_bytes()
            }
            fn from_le(bytes: &[u8]) -> Self {
                <$t>::from_le_bytes(bytes.try_into().expect("SIZE bytes"))
            }
        }
    )*};
}
le_bytes!(u8, i8, u16, i16, u32, i32, f32, f64);

/// Values below which encoding stays on one thread.
const PAR_MIN: usize = 1 << 14;

/// The values as little-endian bytes, in order.
pub fn encode_le<T: LeBytes>(values: &[T]) -> Vec<u8> {
    values
        .par_iter()
        .with_min_len(PAR_MIN)
        .flat_map_iter(|x| x.le())
        .collect()
}

/// Inverse of [`encode_le`]; `None` when the byte count is not a multiple of
/// the value size.
pub fn decode_le<T: LeBytes>(bytes: &[u8]) -> Option<Vec<T>> {
    if !bytes.len().is_multiple_of(T::SIZE) {
        return None;
    }
    Some(
        bytes
            .par_chunks_exact(T::SIZE)
            .with_min_len(PAR_MIN)
            .map(T::from_le)
            .collect(),
    )
}

impl AnyVolume {
    /// The voxels `range` (indices into the x-fastest data) as little-endian
    /// bytes. Panics when `range` is out of bounds, as slicing does.
    pub fn le_bytes(&self, range: Range<usize>) -> Vec<u8> {
        match self {
            AnyVolume::U8(v) => v.data()[range].to_vec(),
            AnyVolume::U16(v) => encode_le(&v.data()[range]),
            AnyVolume::I16(v) => encode_le(&v.data()[range]),
            AnyVolume::F32(v) => encode_le(&v.data()[range]),
        }
    }

    /// Every voxel as little-endian bytes, x-fastest.
    pub fn to_le_bytes(&self) -> Vec<u8> {
        self.le_bytes(0..self.geometry().len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Geometry, LengthUnit, Volume};
    use proptest::prelude::*;

    fn round_trip<T: LeBytes + PartialEq + std::fmt::Debug>(v: Vec<T>) {
        let bytes = encode_le(&v);
        assert_eq!(bytes.len(), v.len() * T::SIZE);
        assert_eq!(decode_le::<T>(&bytes).unwrap(), v);
        if T::SIZE > 1 && !bytes.is_empty() {
            assert!(decode_le::<T>(&bytes[1..]).is_none());
        }
    }

    #[test]
    fn known_bytes() {
        assert_eq!(encode_le(&[0x0102u16, 0xA0B0]), vec![2, 1, 0xB0, 0xA0]);
        assert_eq!(encode_le(&[-2i16]), vec![0xFE, 0xFF]);
        assert_eq!(encode_le(&[1.0f32]), vec![0, 0, 0x80, 0x3F]);
        assert_eq!(decode_le::<u32>(&[1, 0, 0, 1]), Some(vec![0x0100_0001]));
    }

    #[test]
    fn any_volume_bytes_match_the_values() {
        let g = Geometry::new([3, 2, 1], [1.0; 3], LengthUnit::default()).unwrap();
        let data = vec![0u16, 1, 256, 65535, 7, 8];
        let v = AnyVolume::U16(Volume::from_vec(g.clone(), data.clone()).unwrap());
        assert_eq!(v.to_le_bytes(), encode_le(&data));
        assert_eq!(v.le_bytes(2..4), vec![0, 1, 255, 255]);
        let f = AnyVolume::F32(Volume::from_vec(g.clone(), vec![-0.5f32; 6]).unwrap());
        assert_eq!(decode_le::<f32>(&f.to_le_bytes()).unwrap(), vec![-0.5; 6]);
        let b = AnyVolume::U8(Volume::from_vec(g.clone(), vec![9u8; 6]).unwrap());
        assert_eq!(b.to_le_bytes(), vec![9; 6]);
        let i = AnyVolume::I16(Volume::from_vec(g, vec![-3i16; 6]).unwrap());
        assert_eq!(decode_le::<i16>(&i.to_le_bytes()).unwrap(), vec![-3; 6]);
    }

    proptest! {
        #[test]
        fn every_type_round_trips(
            u8s in proptest::collection::vec(any::<u8>(), 0..64),
            i8s in proptest::collection::vec(any::<i8>(), 0..64),
            u16s in proptest::collection::vec(any::<u16>(), 0..64),
            i16s in proptest::collection::vec(any::<i16>(), 0..64),
            u32s in proptest::collection::vec(any::<u32>(), 0..64),
            i32s in proptest::collection::vec(any::<i32>(), 0..64),
            f32s in proptest::collection::vec(any::<u32>(), 0..64),
            f64s in proptest::collection::vec(any::<u64>(), 0..64),
        ) {
            round_trip(u8s);
            round_trip(i8s);
            round_trip(u16s);
            round_trip(i16s);
            round_trip(u32s);
            round_trip(i32s);
            // Floats by bit pattern, so NaNs compare too.
            let f: Vec<f32> = f32s.into_iter().map(f32::from_bits).collect();
            let back: Vec<f32> = decode_le(&encode_le(&f)).unwrap();
            prop_assert_eq!(back.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), f.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
            let d: Vec<f64> = f64s.into_iter().map(f64::from_bits).collect();
            let back: Vec<f64> = decode_le(&encode_le(&d)).unwrap();
            prop_assert_eq!(back.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), d.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
        }
    }

    #[test]
    fn large_arrays_encode_in_order() {
        let v: Vec<u16> = (0..100_000u32).map(|i| (i * 7) as u16).collect();
        round_trip(v);
    }
}
