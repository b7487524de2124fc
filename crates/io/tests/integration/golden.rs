//! Files written by SimpleITK, nibabel, tifffile and pynrrd (see
//! `data/make_golden.py`) are read with exact values and geometry.
use interslice_core::{AnyVolume, Geometry, LengthUnit};
use interslice_io::{Format, read_labels, read_volume};
use std::path::PathBuf;

const DIMS: [usize; 3] = [5, 4, 3];

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-9)
}

fn check_geometry(g: &Geometry, spacing: [f64; 3], origin: [f64; 3], unit: LengthUnit) {
    assert_eq!(g.dims, DIMS);
    assert!(
        close(g.spacing, spacing),
        "spacing {:?} != {spacing:?}",
        g.spacing
    );
    assert!(
        close(g.origin, origin),
        "origin {:?} != {origin:?}",
        g.origin
    );
    assert_eq!(g.unit, unit);
}

/// Voxel (i, j, k) of the generated volumes: `i + 10 j + 100 k`.
fn expected(idx: usize) -> i64 {
    let (i, j, k) = (idx % 5, (idx / 5) % 4, idx / 20);
    (i + 10 * j + 100 * k) as i64
}

#[test]
fn nibabel_nifti_u16_micrometres() {
    let v = read_volume(&data("nibabel_u16.nii.gz")).unwrap();
    let AnyVolume::U16(v) = v else {
        panic!("expected u16, got {}", v.type_name())
    };
    // nibabel's RAS affine origin (10, -20, 2.5) is (-10, 20, 2.5) in LPS.
    check_geometry(
        v.geometry(),
        [0.35, 0.5, 1.25],
        [-10.0, 20.0, 2.5],
        LengthUnit::Micrometre,
    );
    assert_eq!(
        v.geometry().direction,
        [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
    );
    for (idx, &x) in v.data().iter().enumerate() {
        assert_eq!(i64::from(x), 1000 + expected(idx), "voxel {idx}");
    }
}

#[test]
fn simpleitk_nrrd_u8_with_flipped_axis() {
    let v = read_volume(&data("sitk_u8.nrrd")).unwrap();
    let AnyVolume::U8(v) = v else {
        panic!("expected u8, got {}", v.type_name())
    };
    check_geometry(
        v.geometry(),
        [0.5, 0.75, 2.0],
        [1.5, -2.5, 3.0],
        LengthUnit::Millimetre,
    );
    assert_eq!(
        v.geometry().direction,
        [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    );
    for (idx, &x) in v.data().iter().enumerate() {
        let (i, j, k) = (idx % 5, (idx / 5) % 4, idx / 20);
        assert_eq!(usize::from(x), i + 5 * j + 20 * k, "voxel {idx}");
    }
}

#[test]
fn simpleitk_mha_i16_zlib() {
    let v = read_volume(&data("sitk_i16.mha")).unwrap();
    let AnyVolume::I16(v) = v else {
        panic!("expected i16, got {}", v.type_name())
    };
    check_geometry(
        v.geometry(),
        [0.35, 0.35, 0.7],
        [-1.0, 2.0, -3.0],
        LengthUnit::Millimetre,
    );
    for (idx, &x) in v.data().iter().enumerate() {
        assert_eq!(i64::from(x), expected(idx) - 500, "voxel {idx}");
    }
}

#[test]
fn simpleitk_mhd_f32_with_raw_file() {
    let v = read_volume(&data("sitk_f32.mhd")).unwrap();
    let AnyVolume::F32(v) = v else {
        panic!("expected f32, got {}", v.type_name())
    };
    check_geometry(
        v.geometry(),
        [1.0, 2.0, 3.0],
        [0.0; 3],
        LengthUnit::Millimetre,
    );
    for (idx, &x) in v.data().iter().enumerate() {
        assert_eq!(x, 0.25 * expected(idx) as f32 - 3.0, "voxel {idx}");
    }
}

#[test]
fn tifffile_imagej_stack_u16() {
    let v = read_volume(&data("tifffile_u16.tif")).unwrap();
    let AnyVolume::U16(v) = v else {
        panic!("expected u16, got {}", v.type_name())
    };
    check_geometry(
        v.geometry(),
        [0.35, 0.35, 1.05],
        [0.0; 3],
        LengthUnit::Micrometre,
    );
    for (idx, &x) in v.data().iter().enumerate() {
        assert_eq!(i64::from(x), 1000 + expected(idx), "voxel {idx}");
    }
}

#[test]
fn tiff_slice_folder_is_sorted_naturally() {
    let path = data("tifffile_slices");
    assert_eq!(Format::of_path(&path).unwrap(), Format::SliceFolder);
    let v = read_volume(&path).unwrap();
    let AnyVolume::U8(v) = v else {
        panic!("expected u8, got {}", v.type_name())
    };
    assert_eq!(v.dims(), [5, 4, 12]);
    // slice_1 .. slice_12 in natural order: plane n holds 10 n + (i + 5 j).
    for k in 0..12 {
        for j in 0..4 {
            for i in 0..5 {
                assert_eq!(usize::from(v.get(i, j, k)), i + 5 * j + 10 * k);
            }
        }
    }
}

#[test]
fn slicer_segmentation_with_two_layers_is_merged() {
    let v = read_labels(&data("layers.seg.nrrd")).unwrap();
    // RAS (4, 3, -1) with -0.5 mm x/y steps is LPS (-4, -3, -1) with +0.5 steps.
    check_geometry(
        v.geometry(),
        [0.5, 0.5, 1.0],
        [-4.0, -3.0, -1.0],
        LengthUnit::Millimetre,
    );
    assert_eq!(
        v.geometry().direction,
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    );
    // Label values 1, 2, 1 are not distinct: segments become labels 1, 2, 3.
    assert_eq!(v.label_counts(), vec![(1, 16), (2, 1), (3, 1)]);
    assert_eq!(v.get(1, 1, 0), 1);
    assert_eq!(v.get(2, 1, 0), 1);
    assert_eq!(v.get(2, 1, 1), 2);
    assert_eq!(
        v.get(2, 2, 1),
        3,
        "the later segment wins where they overlap"
    );
    assert_eq!(v.get(0, 0, 0), 0);
}
