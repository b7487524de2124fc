//! Voxel types wider than the in-memory ones (u8, u16, i16, f32): what each
//! becomes, and which values are refused (docs/formats.md, "In memory").
use interslice_core::AnyVolume;
use interslice_io::read_volume;
use std::path::PathBuf;

/// A raw little-endian NRRD of 2×2×2 voxels of NRRD `kind` holding `bytes`.
fn nrrd(dir: &tempfile::TempDir, name: &str, kind: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.path().join(name);
    let mut f = format!(
        "NRRD0004\ntype: {kind}\ndimension: 3\nsizes: 2 2 2\nspacings: 1 1 1\nendian: little\nencoding: raw\n\n"
    )
    .into_bytes();
    f.extend_from_slice(bytes);
    std::fs::write(&p, f).unwrap();
    p
}

fn f64_bytes(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn i32_bytes(v: &[i32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn float64_is_rounded_to_the_nearest_float32() {
    let dir = tempfile::tempdir().unwrap();
    let values = [
        0.1,
        -1000.25,
        1e-30,
        3.0e38,
        -7.123456789012345,
        0.0,
        1.0 / 3.0,
        42.0,
    ];
    let v = read_volume(&nrrd(&dir, "mr.nrrd", "double", &f64_bytes(&values))).unwrap();
    let AnyVolume::F32(v) = v else {
        panic!("float64 should read as f32, got {v:?}")
    };
    for (got, want) in v.data().iter().zip(values) {
        assert_eq!(*got, want as f32);
        let rel = ((f64::from(*got) - want) / want.abs().max(f64::MIN_POSITIVE)).abs();
        assert!(rel <= 6e-8, "{want}: relative change {rel}");
    }
}

#[test]
fn float64_keeps_nan_and_infinities() {
    let dir = tempfile::tempdir().unwrap();
    let values = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1.5,
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    let AnyVolume::F32(v) =
        read_volume(&nrrd(&dir, "nan.nrrd", "double", &f64_bytes(&values))).unwrap()
    else {
        panic!("float64 should read as f32")
    };
    assert!(v.data()[0].is_nan());
    assert_eq!(v.data()[1], f32::INFINITY);
    assert_eq!(v.data()[2], f32::NEG_INFINITY);
    assert_eq!(v.data()[3], 1.5);
}

#[test]
fn float64_beyond_the_float32_range_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut values = [1.0; 8];
    values[5] = -1e300;
    let e = read_volume(&nrrd(&dir, "huge.nrrd", "double", &f64_bytes(&values)))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("huge.nrrd") && e.contains("-1e300") && e.contains("range"),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn int32_goes_to_the_narrowest_exact_type() {
    let dir = tempfile::tempdir().unwrap();
    let fits_u16 = [0, 1, 2, 3, 65535, 5, 6, 7];
    let v = read_volume(&nrrd(&dir, "u.nrrd", "int", &i32_bytes(&fits_u16))).unwrap();
    assert!(
        matches!(&v, AnyVolume::U16(u) if u.data()[4] == 65535),
        "{v:?}"
    );
    let fits_i16 = [-1000, 1, 2, 3, 3000, 5, 6, 7];
    let v = read_volume(&nrrd(&dir, "i.nrrd", "int", &i32_bytes(&fits_i16))).unwrap();
    assert!(
        matches!(&v, AnyVolume::I16(i) if i.data()[0] == -1000),
        "{v:?}"
    );
    let counts = [0, 70_000, -5, 16_777_216, -16_777_216, 1, 2, 3];
    let AnyVolume::F32(v) = read_volume(&nrrd(&dir, "c.nrrd", "int", &i32_bytes(&counts))).unwrap()
    else {
        panic!("32-bit counts beyond 16 bits should read as f32")
    };
    let back: Vec<i32> = v.data().iter().map(|x| *x as i32).collect();
    assert_eq!(back, counts);
}

#[test]
fn int32_not_exact_in_float32_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let values = [0, 16_777_217, 2, 3, 4, 5, 6, 7];
    let e = read_volume(&nrrd(&dir, "wide.nrrd", "int", &i32_bytes(&values)))
        .unwrap_err()
        .to_string();
    assert!(e.contains("wide.nrrd") && e.contains("16777217"), "{e}");
}
