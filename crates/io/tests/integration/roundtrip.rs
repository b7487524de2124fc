//! Every format reads back what it wrote: values, dims, spacing, unit,
//! origin and direction, for u8 and u16 (and i16/f32 where the format has them).
use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};
use interslice_io::{Format, read_labels, read_volume, write_labels, write_volume};
use std::path::Path;

/// Every writable format, by the name we give the output.
const NAMES: [&str; 7] = [
    "v.nii", "v.nii.gz", "v.nrrd", "v.mha", "v.mhd", "v.tif", "slices",
];

fn geometry() -> Geometry {
    let mut g = Geometry::new([7, 5, 4], [0.35, 0.5, 1.25], LengthUnit::Micrometre).unwrap();
    g.origin = [-3.5, 12.25, 7.0];
    g
}

/// An oblique direction: a 30° rotation about z, with the z axis flipped.
fn oblique(mut g: Geometry) -> Geometry {
    let (s, c) = (0.5f64, 0.75f64.sqrt());
    g.direction = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, -1.0]];
    g
}

fn volume_u8(g: Geometry) -> AnyVolume {
    let data = (0..g.len()).map(|n| (n * 7 % 256) as u8).collect();
    AnyVolume::U8(Volume::from_vec(g, data).unwrap())
}

fn volume_u16(g: Geometry) -> AnyVolume {
    let data = (0..g.len()).map(|n| (n * 613 % 65536) as u16).collect();
    AnyVolume::U16(Volume::from_vec(g, data).unwrap())
}

fn volume_i16(g: Geometry) -> AnyVolume {
    let data = (0..g.len())
        .map(|n| (n as i64 * 331 % 65536 - 32768) as i16)
        .collect();
    AnyVolume::I16(Volume::from_vec(g, data).unwrap())
}

fn volume_f32(g: Geometry) -> AnyVolume {
    let data = (0..g.len()).map(|n| n as f32 * 0.1 - 7.25).collect();
    AnyVolume::F32(Volume::from_vec(g, data).unwrap())
}

fn assert_same(path: &Path, a: &AnyVolume, b: &AnyVolume) {
    assert_eq!(a.type_name(), b.type_name(), "{}", path.display());
    let (ga, gb) = (a.geometry(), b.geometry());
    assert_eq!(ga.dims, gb.dims, "{}", path.display());
    assert_eq!(ga.spacing, gb.spacing, "spacing of {}", path.display());
    assert_eq!(ga.origin, gb.origin, "origin of {}", path.display());
    assert_eq!(ga.unit, gb.unit, "unit of {}", path.display());
    for r in 0..3 {
        for c in 0..3 {
            // NIfTI keeps the direction as an f32 quaternion.
            assert!(
                (ga.direction[r][c] - gb.direction[r][c]).abs() < 1e-6,
                "direction of {}: {:?} vs {:?}",
                path.display(),
                ga.direction,
                gb.direction
            );
        }
    }
    match (a, b) {
        (AnyVolume::U8(x), AnyVolume::U8(y)) => assert!(x.data() == y.data()),
        (AnyVolume::U16(x), AnyVolume::U16(y)) => assert!(x.data() == y.data()),
        (AnyVolume::I16(x), AnyVolume::I16(y)) => assert!(x.data() == y.data()),
        (AnyVolume::F32(x), AnyVolume::F32(y)) => assert!(x.data() == y.data()),
        _ => unreachable!(),
    }
}

fn round_trip(name: &str, v: &AnyVolume) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    write_volume(&path, v).unwrap_or_else(|e| panic!("write {name}: {e}"));
    let back = read_volume(&path).unwrap_or_else(|e| panic!("read {name}: {e}"));
    assert_same(&path, v, &back);
    // Nothing but the output (and a .mhd's .raw) is left in the folder.
    let mut left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    let expected: Vec<String> = if name == "v.mhd" {
        vec!["v.mhd".into(), "v.raw".into()]
    } else {
        vec![name.into()]
    };
    assert_eq!(left, expected, "stray files after writing {name}");
}

#[test]
fn u8_round_trips_in_every_format() {
    for name in NAMES {
        round_trip(name, &volume_u8(geometry()));
    }
}

#[test]
fn u16_round_trips_in_every_format() {
    for name in NAMES {
        round_trip(name, &volume_u16(geometry()));
    }
}

#[test]
fn i16_and_f32_round_trip_where_the_format_has_them() {
    for name in NAMES.iter().filter(|n| **n != "slices") {
        round_trip(name, &volume_i16(geometry()));
        round_trip(name, &volume_f32(geometry()));
    }
}

#[test]
fn oblique_direction_round_trips() {
    for name in NAMES {
        round_trip(name, &volume_u16(oblique(geometry())));
    }
}

#[test]
fn units_round_trip() {
    for unit in [
        LengthUnit::Millimetre,
        LengthUnit::Micrometre,
        LengthUnit::Metre,
    ] {
        let mut g = geometry();
        g.unit = unit;
        for name in NAMES {
            round_trip(name, &volume_u8(g.clone()));
        }
    }
}

#[test]
fn single_slice_and_large_dims_round_trip() {
    let g = Geometry::new([300, 1, 1], [2.0, 3.0, 4.0], LengthUnit::Millimetre).unwrap();
    for name in NAMES {
        round_trip(name, &volume_u16(g.clone()));
    }
}

#[test]
fn slice_folder_names_and_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let g = Geometry::new([3, 2, 12], [1.0; 3], LengthUnit::Micrometre).unwrap();
    write_volume(&out, &volume_u8(g.clone())).unwrap();
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names.len(), 12);
    assert_eq!(names[0], "slice_0000.png");
    assert_eq!(names[11], "slice_0011.png");
    // Writing again replaces the folder (fewer slices: no stale ones left).
    let g2 = Geometry::new([3, 2, 5], [1.0; 3], LengthUnit::Micrometre).unwrap();
    let v2 = volume_u16(g2);
    write_volume(&out, &v2).unwrap();
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 5);
    assert_same(&out, &v2, &read_volume(&out).unwrap());
    // A folder that holds other files is not replaced.
    std::fs::write(out.join("notes.txt"), "keep me").unwrap();
    let e = write_volume(&out, &v2).unwrap_err().to_string();
    assert!(e.contains("notes.txt"), "{e}");
    assert!(out.join("notes.txt").exists());
}

#[test]
fn format_of_path() {
    let f = |p: &str| Format::of_path(Path::new(p)).unwrap();
    assert_eq!(f("a.nii"), Format::Nifti);
    assert_eq!(f("A.NII.GZ"), Format::NiftiGz);
    assert_eq!(f("seg.seg.nrrd"), Format::Nrrd);
    assert_eq!(f("x.nhdr"), Format::Nhdr);
    assert_eq!(f("x.mha"), Format::Mha);
    assert_eq!(f("x.mhd"), Format::Mhd);
    assert_eq!(f("x.tiff"), Format::Tiff);
    assert_eq!(f("x.tif"), Format::Tiff);
    assert_eq!(f("slices/"), Format::SliceFolder);
    assert_eq!(f("no_such_folder_here"), Format::SliceFolder);
    let dir = tempfile::tempdir().unwrap();
    let with_dot = dir.path().join("stack.v1");
    std::fs::create_dir(&with_dot).unwrap();
    assert_eq!(Format::of_path(&with_dot).unwrap(), Format::SliceFolder);
    assert!(Format::of_path(Path::new("x.jpg")).is_err());
}

#[test]
fn labels_are_written_as_u8_when_they_fit() {
    let dir = tempfile::tempdir().unwrap();
    let g = geometry();
    let small =
        Volume::from_vec(g.clone(), (0..g.len()).map(|n| (n % 4) as u16).collect()).unwrap();
    let big = Volume::from_vec(g.clone(), (0..g.len()).map(|n| (n * 97) as u16).collect()).unwrap();
    for name in ["l.nii.gz", "l.nrrd", "l.mha", "l.tif", "l"] {
        let p = dir.path().join(name);
        write_labels(&p, &small).unwrap();
        assert_eq!(read_volume(&p).unwrap().type_name(), "u8");
        assert_eq!(read_labels(&p).unwrap(), small);
        write_labels(&p, &big).unwrap();
        assert_eq!(read_volume(&p).unwrap().type_name(), "u16");
        assert_eq!(read_labels(&p).unwrap(), big);
    }
}

#[test]
fn nrrd_ascii_big_endian_and_detached_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.nrrd");
    std::fs::write(
        &p,
        "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 1 2\nspacings: 0.5 0.5 2\nencoding: ascii\n\n1 -2\n300 4\n",
    )
    .unwrap();
    let AnyVolume::I16(v) = read_volume(&p).unwrap() else {
        panic!("expected i16")
    };
    assert_eq!(v.data(), &[1, -2, 300, 4]);
    assert_eq!(v.geometry().spacing, [0.5, 0.5, 2.0]);

    let raw = dir.path().join("b.raw");
    std::fs::write(&raw, [0u8, 1, 1, 0, 0xff, 0xff, 0, 2]).unwrap();
    let h = dir.path().join("b.nhdr");
    std::fs::write(
        &h,
        "NRRD0004\ntype: ushort\ndimension: 3\nspace: left-posterior-superior\nsizes: 2 2 1\n\
         space directions: (1,0,0) (0,1,0) (0,0,1)\nendian: big\nencoding: raw\ndata file: b.raw\n",
    )
    .unwrap();
    let AnyVolume::U16(v) = read_volume(&h).unwrap() else {
        panic!("expected u16")
    };
    assert_eq!(v.data(), &[1, 256, 65535, 2]);
}

#[test]
fn single_layer_slicer_segmentation_is_squeezed() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.seg.nrrd");
    let mut bytes =
        b"NRRD0004\ntype: unsigned char\ndimension: 4\nspace: left-posterior-superior\n\
sizes: 1 2 2 1\nspace directions: none (1,0,0) (0,1,0) (0,0,1)\nkinds: list domain domain domain\n\
encoding: raw\nspace origin: (0,0,0)\nSegment0_LabelValue:=3\nSegment0_Layer:=0\n\n"
            .to_vec();
    bytes.extend_from_slice(&[0, 3, 3, 0]);
    std::fs::write(&p, bytes).unwrap();
    let v = read_labels(&p).unwrap();
    assert_eq!(v.dims(), [2, 2, 1]);
    assert_eq!(v.data(), &[0, 3, 3, 0]);
}

#[test]
fn nifti_scaled_values_are_read_as_calibrated_floats() {
    // scl_slope 2, scl_inter 1: the file means 2 x + 1.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.nii");
    let g = Geometry::new([2, 1, 1], [1.0; 3], LengthUnit::Millimetre).unwrap();
    write_volume(&p, &AnyVolume::U8(Volume::from_vec(g, vec![3, 4]).unwrap())).unwrap();
    let mut b = std::fs::read(&p).unwrap();
    b[112..116].copy_from_slice(&2f32.to_le_bytes());
    b[116..120].copy_from_slice(&1f32.to_le_bytes());
    std::fs::write(&p, b).unwrap();
    let AnyVolume::F32(v) = read_volume(&p).unwrap() else {
        panic!("expected f32")
    };
    assert_eq!(v.data(), &[7.0, 9.0]);
}

/// ImageJ and tifffile read an ImageJ stack as `images=` pages stored one
/// after the other from the first page's offset: the pages must be contiguous.
#[test]
fn tiff_pages_are_contiguous_with_imagej_metadata() {
    use tiff::decoder::Decoder;
    use tiff::tags::Tag;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("c.tif");
    let v = volume_u16(geometry());
    write_volume(&p, &v).unwrap();
    let mut d = Decoder::new(std::fs::File::open(&p).unwrap()).unwrap();
    let desc = d.get_tag_ascii_string(Tag::ImageDescription).unwrap();
    assert!(desc.starts_with("ImageJ=") && desc.contains("images=4\n"));
    assert!(desc.contains("unit=micron\n") && desc.contains("spacing=1.25\n"));
    let page = 7 * 5 * 2;
    let mut offsets = Vec::new();
    loop {
        offsets.push(d.get_tag_u64(Tag::StripOffsets).unwrap());
        assert_eq!(d.get_tag_u64(Tag::StripByteCounts).unwrap(), page);
        if !d.more_images() {
            break;
        }
        d.next_image().unwrap();
    }
    assert_eq!(offsets.len(), 4);
    for (k, o) in offsets.iter().enumerate() {
        assert_eq!(*o, offsets[0] + k as u64 * page);
    }
}

/// PNG slices of other tools: 1-bit masks keep their stored values (0/1,
/// never stretched to 255) and a folder without our text chunk gets spacing 1.
#[test]
fn one_bit_png_slices_are_unpacked_without_scaling() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("masks");
    std::fs::create_dir(&folder).unwrap();
    for k in 0..3u8 {
        let f = std::fs::File::create(folder.join(format!("m{k}.png"))).unwrap();
        let mut enc = png::Encoder::new(f, 10, 2);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::One);
        let mut w = enc.write_header().unwrap();
        // Row 0: pixels 0..8 = 1010_0000 shifted by k, pixel 8, 9 = 1 1; row 1: all 0.
        w.write_image_data(&[0b1010_0000 >> k, 0b1100_0000, 0, 0])
            .unwrap();
    }
    let v = read_labels(&folder).unwrap();
    assert_eq!(v.dims(), [10, 2, 3]);
    assert_eq!(v.geometry().spacing, [1.0; 3]);
    assert_eq!(v.geometry().unit, LengthUnit::Unknown);
    for k in 0..3 {
        let row: Vec<u16> = (0..10).map(|i| v.get(i, 0, k)).collect();
        let mut want = vec![0u16; 10];
        want[k] = 1;
        want[k + 2] = 1;
        want[8] = 1;
        want[9] = 1;
        assert_eq!(row, want, "slice {k}");
        assert!((0..10).all(|i| v.get(i, 1, k) == 0));
    }
}

/// The in-memory writers give, byte for byte, what the file writers write,
/// for every one-file format, for u8- and u16-sized labels; the bytes read
/// back as the same volume; formats of more than one file are refused.
#[test]
fn in_memory_writers_equal_the_file_writers() {
    use interslice_core::LabelVolume;
    use interslice_io::{read_bytes, write_labels_bytes};
    let dir = tempfile::tempdir().unwrap();
    let g = oblique(geometry());
    for max in [7u16, 700] {
        let data: Vec<u16> = (0..g.len()).map(|i| (i as u16 * 13) % (max + 1)).collect();
        let labels = LabelVolume::from_vec(g.clone(), data).unwrap();
        for ext in ["nii", "nii.gz", "nrrd", "mha", "tif"] {
            let name = format!("l{max}.{ext}");
            let path = dir.path().join(&name);
            write_labels(&path, &labels).unwrap();
            let bytes = write_labels_bytes(&name, &labels).unwrap();
            assert_eq!(bytes, std::fs::read(&path).unwrap(), "{name}");
            let back = read_bytes(&name, &bytes, &Default::default()).unwrap();
            assert_eq!(back.to_labels().unwrap().data(), labels.data(), "{name}");
        }
        for name in ["l.mhd", "l.nhdr", "slices"] {
            let e = write_labels_bytes(name, &labels).unwrap_err().to_string();
            assert!(e.contains("one-file formats"), "{name}: {e}");
        }
    }
}
