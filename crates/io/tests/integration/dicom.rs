//! DICOM series reading, on small files written here with `dicom-object`:
//! geometry (sorted along the normal whatever the file names, oblique
//! direction, spacing from the positions), voxel types and rescale,
//! multi-frame files, series selection, and the one-line errors for gaps,
//! mixed orientations, undecodable transfer syntaxes and hostile headers.
use dicom_core::value::{DataSetSequence, PixelFragmentSequence};
use dicom_core::{DataElement, PrimitiveValue, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
use interslice_core::AnyVolume;
use interslice_io::{Format, dicom, read_volume, read_volume_series};
use std::path::{Path, PathBuf};

const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
const JPEG_2000: &str = "1.2.840.10008.1.2.4.91";
const CT_STORAGE: &str = "1.2.840.10008.5.1.4.1.1.2";

/// One image file to write: a single frame unless `frame_positions` is set.
#[derive(Clone)]
struct Img {
    series: String,
    rows: u16,
    cols: u16,
    position: Option<[f64; 3]>,
    orientation: Option<[f64; 6]>,
    /// PixelSpacing as stored: row spacing, column spacing.
    pixel_spacing: [f64; 2],
    bits_allocated: u16,
    bits_stored: u16,
    signed: bool,
    /// Stored samples (all frames), written in `bits_allocated` bits.
    samples: Vec<u16>,
    slope: Option<f64>,
    intercept: Option<f64>,
    transfer_syntax: &'static str,
    /// Enhanced multi-frame: one position per frame (per-frame groups).
    frame_positions: Option<Vec<[f64; 3]>>,
    /// Legacy multi-frame: NumberOfFrames without per-frame groups.
    legacy_frames: Option<usize>,
    spacing_between_slices: Option<f64>,
    instance: i32,
}

impl Img {
    fn new(position: [f64; 3], samples: Vec<u16>) -> Img {
        Img {
            series: "1.2.3.1".into(),
            rows: 2,
            cols: 3,
            position: Some(position),
            orientation: Some([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            pixel_spacing: [0.5, 0.8],
            bits_allocated: 16,
            bits_stored: 16,
            signed: true,
            samples,
            slope: None,
            intercept: None,
            transfer_syntax: EXPLICIT_LE,
            frame_positions: None,
            legacy_frames: None,
            spacing_between_slices: None,
            instance: 1,
        }
    }
}

fn ds(values: &[f64]) -> PrimitiveValue {
    PrimitiveValue::Strs(values.iter().map(|v| format!("{v}")).collect())
}

fn put(obj: &mut InMemDicomObject, tag: dicom_core::Tag, vr: VR, v: PrimitiveValue) {
    obj.put(DataElement::new(tag, vr, v));
}

fn item(tag: dicom_core::Tag, inner: InMemDicomObject) -> InMemDicomObject {
    let mut o = InMemDicomObject::new_empty();
    o.put(DataElement::new(
        tag,
        VR::SQ,
        DataSetSequence::from(vec![inner]),
    ));
    o
}

fn write(path: &Path, img: &Img) {
    let mut o = InMemDicomObject::new_empty();
    let uid = format!("1.2.3.9.{}", img.instance);
    put(
        &mut o,
        tags::SOP_CLASS_UID,
        VR::UI,
        PrimitiveValue::from(CT_STORAGE),
    );
    put(
        &mut o,
        tags::SOP_INSTANCE_UID,
        VR::UI,
        PrimitiveValue::from(uid.as_str()),
    );
    put(&mut o, tags::MODALITY, VR::CS, PrimitiveValue::from("CT"));
    put(
        &mut o,
        tags::SERIES_DESCRIPTION,
        VR::LO,
        PrimitiveValue::from("test series"),
    );
    put(
        &mut o,
        tags::SERIES_INSTANCE_UID,
        VR::UI,
        PrimitiveValue::from(img.series.as_str()),
    );
    put(
        &mut o,
        tags::INSTANCE_NUMBER,
        VR::IS,
        PrimitiveValue::from(img.instance.to_string()),
    );
    if let Some(p) = img.position {
        put(&mut o, tags::IMAGE_POSITION_PATIENT, VR::DS, ds(&p));
    }
    if let Some(r) = img.orientation {
        put(&mut o, tags::IMAGE_ORIENTATION_PATIENT, VR::DS, ds(&r));
    }
    put(&mut o, tags::PIXEL_SPACING, VR::DS, ds(&img.pixel_spacing));
    if let Some(s) = img.spacing_between_slices {
        put(&mut o, tags::SPACING_BETWEEN_SLICES, VR::DS, ds(&[s]));
    }
    put(
        &mut o,
        tags::SAMPLES_PER_PIXEL,
        VR::US,
        PrimitiveValue::from(1u16),
    );
    put(
        &mut o,
        tags::PHOTOMETRIC_INTERPRETATION,
        VR::CS,
        PrimitiveValue::from("MONOCHROME2"),
    );
    put(&mut o, tags::ROWS, VR::US, PrimitiveValue::from(img.rows));
    put(
        &mut o,
        tags::COLUMNS,
        VR::US,
        PrimitiveValue::from(img.cols),
    );
    put(
        &mut o,
        tags::BITS_ALLOCATED,
        VR::US,
        PrimitiveValue::from(img.bits_allocated),
    );
    put(
        &mut o,
        tags::BITS_STORED,
        VR::US,
        PrimitiveValue::from(img.bits_stored),
    );
    put(
        &mut o,
        tags::HIGH_BIT,
        VR::US,
        PrimitiveValue::from(img.bits_stored - 1),
    );
    put(
        &mut o,
        tags::PIXEL_REPRESENTATION,
        VR::US,
        PrimitiveValue::from(u16::from(img.signed)),
    );
    if let Some(s) = img.slope {
        put(&mut o, tags::RESCALE_SLOPE, VR::DS, ds(&[s]));
    }
    if let Some(b) = img.intercept {
        put(&mut o, tags::RESCALE_INTERCEPT, VR::DS, ds(&[b]));
    }
    if let Some(n) = img.legacy_frames {
        put(
            &mut o,
            tags::NUMBER_OF_FRAMES,
            VR::IS,
            PrimitiveValue::from(n.to_string()),
        );
    }
    if let Some(positions) = &img.frame_positions {
        put(
            &mut o,
            tags::NUMBER_OF_FRAMES,
            VR::IS,
            PrimitiveValue::from(positions.len().to_string()),
        );
        o.remove_element(tags::IMAGE_POSITION_PATIENT);
        o.remove_element(tags::IMAGE_ORIENTATION_PATIENT);
        o.remove_element(tags::PIXEL_SPACING);
        let mut orient = InMemDicomObject::new_empty();
        put(
            &mut orient,
            tags::IMAGE_ORIENTATION_PATIENT,
            VR::DS,
            ds(&img.orientation.unwrap()),
        );
        let mut measures = InMemDicomObject::new_empty();
        put(
            &mut measures,
            tags::PIXEL_SPACING,
            VR::DS,
            ds(&img.pixel_spacing),
        );
        let mut shared = item(tags::PLANE_ORIENTATION_SEQUENCE, orient);
        shared.put(DataElement::new(
            tags::PIXEL_MEASURES_SEQUENCE,
            VR::SQ,
            DataSetSequence::from(vec![measures]),
        ));
        o.put(DataElement::new(
            tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE,
            VR::SQ,
            DataSetSequence::from(vec![shared]),
        ));
        let per_frame: Vec<InMemDicomObject> = positions
            .iter()
            .map(|p| {
                let mut pos = InMemDicomObject::new_empty();
                put(&mut pos, tags::IMAGE_POSITION_PATIENT, VR::DS, ds(p));
                item(tags::PLANE_POSITION_SEQUENCE, pos)
            })
            .collect();
        o.put(DataElement::new(
            tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE,
            VR::SQ,
            DataSetSequence::from(per_frame),
        ));
    }
    if img.transfer_syntax == EXPLICIT_LE {
        if img.bits_allocated == 8 {
            let bytes: Vec<u8> = img.samples.iter().map(|&s| s as u8).collect();
            put(
                &mut o,
                tags::PIXEL_DATA,
                VR::OB,
                PrimitiveValue::from(bytes),
            );
        } else {
            put(
                &mut o,
                tags::PIXEL_DATA,
                VR::OW,
                PrimitiveValue::U16(img.samples.clone().into()),
            );
        }
    } else {
        // Some bytes in an encapsulated fragment: the reader must refuse the
        // syntax before trying to decode them.
        o.put(DataElement::new(
            tags::PIXEL_DATA,
            VR::OB,
            PixelFragmentSequence::new_fragments(vec![vec![0xFF, 0x4F, 0xFF, 0x51, 0, 0]]),
        ));
    }
    let file = o
        .with_meta(FileMetaTableBuilder::new().transfer_syntax(img.transfer_syntax))
        .unwrap();
    file.write_to_file(path).unwrap();
}

/// Slice k of a 3 x 2 image: value 100 k + pixel index, minus 50.
fn samples(k: usize) -> Vec<u16> {
    (0..6)
        .map(|i| (100 * k as i32 + i - 50) as i16 as u16)
        .collect()
}

const R: [f64; 3] = [0.6, 0.8, 0.0];
const C: [f64; 3] = [0.0, 0.0, -1.0];
/// R x C.
const N: [f64; 3] = [-0.8, 0.6, 0.0];

fn oblique_position(k: usize) -> [f64; 3] {
    let d = 2.5 * k as f64;
    [10.0 + d * N[0], -4.0 + d * N[1], 7.0 + d * N[2]]
}

/// Five oblique slices written under shuffled names with shuffled
/// instance numbers; returns the folder.
fn oblique_series(dir: &Path, skip: Option<usize>) -> PathBuf {
    let names = ["b.dcm", "IM0003", "a10.dcm", "z.dcm", "c2"];
    let order = [3usize, 0, 4, 1, 2];
    for (k, name) in order.iter().map(|&i| (i, names[i])) {
        if Some(k) == skip {
            continue;
        }
        let mut img = Img::new(oblique_position(k), samples(k));
        img.orientation = Some([R[0], R[1], R[2], C[0], C[1], C[2]]);
        img.instance = [5, 1, 4, 2, 3][k];
        write(&dir.join(name), &img);
    }
    dir.to_path_buf()
}

fn i16_data(v: &AnyVolume) -> Vec<i16> {
    match v {
        AnyVolume::I16(v) => v.data().to_vec(),
        other => panic!("expected i16, got {}", other.type_name()),
    }
}

fn err(path: &Path, series: Option<&str>) -> String {
    let e = read_volume_series(path, series).unwrap_err().to_string();
    assert!(!e.contains('\n'), "error is not one line: {e}");
    e
}

#[test]
fn shuffled_names_sort_along_the_normal() {
    let dir = tempfile::tempdir().unwrap();
    oblique_series(dir.path(), None);
    assert_eq!(Format::of_path(dir.path()).unwrap(), Format::Dicom);
    assert_eq!(
        Format::of_path(&dir.path().join("IM0003")).unwrap(),
        Format::Dicom
    );
    let v = read_volume(dir.path()).unwrap();
    let g = v.geometry();
    assert_eq!(g.dims, [3, 2, 5]);
    // PixelSpacing is (row, column): x is the column spacing.
    assert!((g.spacing[0] - 0.8).abs() < 1e-12 && (g.spacing[1] - 0.5).abs() < 1e-12);
    assert!((g.spacing[2] - 2.5).abs() < 1e-9, "{:?}", g.spacing);
    let o = oblique_position(0);
    assert!(
        (0..3).all(|i| (g.origin[i] - o[i]).abs() < 1e-9),
        "{:?}",
        g.origin
    );
    for r in 0..3 {
        for (c, axis) in [R, C, N].iter().enumerate() {
            assert!(
                (g.direction[r][c] - axis[r]).abs() < 1e-9,
                "{:?}",
                g.direction
            );
        }
    }
    let expected: Vec<i16> = (0..5).flat_map(samples).map(|s| s as i16).collect();
    assert_eq!(i16_data(&v), expected);
}

#[test]
fn a_gap_names_the_missing_position() {
    let dir = tempfile::tempdir().unwrap();
    oblique_series(dir.path(), Some(2));
    let e = err(dir.path(), None);
    let p = oblique_position(2);
    assert!(
        e.contains("slice missing between") && e.contains("1 missing"),
        "{e}"
    );
    assert!(e.contains("between IM0003 and z.dcm"), "{e}");
    assert!(
        e.contains(&format!("({}, {}, {})", p[0], p[1], p[2])),
        "{e}"
    );
}

#[test]
fn mixed_orientations_and_sizes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for k in 0..3 {
        let mut img = Img::new([0.0, 0.0, k as f64], samples(k));
        if k == 1 {
            img.orientation = Some([1.0, 0.0, 0.0, 0.0, 0.0, -1.0]);
        }
        write(&dir.path().join(format!("s{k}.dcm")), &img);
    }
    let e = err(dir.path(), None);
    assert!(
        e.contains("mixed orientations") && e.contains("s1.dcm"),
        "{e}"
    );

    let dir = tempfile::tempdir().unwrap();
    for k in 0..3 {
        let mut img = Img::new([0.0, 0.0, k as f64], samples(k));
        if k == 2 {
            img.cols = 2;
            img.samples.truncate(4);
        }
        write(&dir.path().join(format!("s{k}.dcm")), &img);
    }
    let e = err(dir.path(), None);
    assert!(
        e.contains("mixed image sizes") && e.contains("s2.dcm is 2 x 2"),
        "{e}"
    );
}

#[test]
fn repeated_positions_and_uneven_steps_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (k, z) in [0.0, 1.0, 1.0, 2.0].iter().enumerate() {
        write(
            &dir.path().join(format!("s{k}.dcm")),
            &Img::new([0.0, 0.0, *z], samples(k)),
        );
    }
    let e = err(dir.path(), None);
    assert!(e.contains("same position"), "{e}");

    let dir = tempfile::tempdir().unwrap();
    for (k, z) in [0.0, 1.0, 2.0, 3.5, 4.5].iter().enumerate() {
        write(
            &dir.path().join(format!("s{k}.dcm")),
            &Img::new([0.0, 0.0, *z], samples(k)),
        );
    }
    let e = err(dir.path(), None);
    assert!(
        e.contains("uneven slice spacing") && e.contains("1.5 mm apart"),
        "{e}"
    );

    // A sheared stack (gantry tilt): each slice 1 mm further along y.
    let dir = tempfile::tempdir().unwrap();
    for k in 0..4 {
        let img = Img::new([0.0, k as f64, 2.0 * k as f64], samples(k));
        write(&dir.path().join(format!("s{k}.dcm")), &img);
    }
    let e = err(dir.path(), None);
    assert!(e.contains("sheared"), "{e}");
}

#[test]
fn undecodable_transfer_syntax_is_named() {
    let dir = tempfile::tempdir().unwrap();
    for k in 0..3 {
        let mut img = Img::new([0.0, 0.0, k as f64], samples(k));
        if k == 1 {
            img.transfer_syntax = JPEG_2000;
        }
        write(&dir.path().join(format!("s{k}.dcm")), &img);
    }
    let e = err(dir.path(), None);
    assert!(
        e.contains("s1.dcm") && e.contains("JPEG 2000") && e.contains(JPEG_2000),
        "{e}"
    );
}

#[test]
fn enhanced_multi_frame_sorts_its_frames() {
    let dir = tempfile::tempdir().unwrap();
    // Frames stored in the order z = 6, 2, 4, 0: frame j holds slice order[j].
    let order = [3usize, 1, 2, 0];
    let all: Vec<u16> = order.iter().flat_map(|&k| samples(k)).collect();
    let mut img = Img::new([0.0; 3], all);
    img.frame_positions = Some(order.iter().map(|&k| [1.0, 2.0, 2.0 * k as f64]).collect());
    let path = dir.path().join("enhanced.dcm");
    write(&path, &img);
    for p in [dir.path(), path.as_path()] {
        let v = read_volume(p).unwrap();
        let g = v.geometry();
        assert_eq!(g.dims, [3, 2, 4]);
        assert_eq!(g.origin, [1.0, 2.0, 0.0]);
        assert!((g.spacing[2] - 2.0).abs() < 1e-12);
        assert!((g.spacing[0] - 0.8).abs() < 1e-12, "{:?}", g.spacing);
        let expected: Vec<i16> = (0..4).flat_map(samples).map(|s| s as i16).collect();
        assert_eq!(i16_data(&v), expected);
    }
}

#[test]
fn legacy_multi_frame_uses_spacing_between_slices() {
    let dir = tempfile::tempdir().unwrap();
    let all: Vec<u16> = (0..3).flat_map(samples).collect();
    let mut img = Img::new([5.0, 6.0, 7.0], all);
    img.legacy_frames = Some(3);
    img.spacing_between_slices = Some(3.0);
    write(&dir.path().join("nm.dcm"), &img);
    let v = read_volume(dir.path()).unwrap();
    assert_eq!(v.geometry().dims, [3, 2, 3]);
    assert_eq!(v.geometry().origin, [5.0, 6.0, 7.0]);
    assert!((v.geometry().spacing[2] - 3.0).abs() < 1e-12);

    img.spacing_between_slices = None;
    write(&dir.path().join("nm.dcm"), &img);
    let e = err(dir.path(), None);
    assert!(
        e.contains("nm.dcm frame 2 has no ImagePositionPatient"),
        "{e}"
    );
}

/// A two-slice series of one pixel format; returns the volume.
fn two_slices(
    bits_allocated: u16,
    bits_stored: u16,
    signed: bool,
    samples: [[u16; 6]; 2],
    rescale: Option<(f64, f64)>,
) -> AnyVolume {
    let dir = tempfile::tempdir().unwrap();
    for (k, s) in samples.iter().enumerate() {
        let mut img = Img::new([0.0, 0.0, k as f64], s.to_vec());
        img.bits_allocated = bits_allocated;
        img.bits_stored = bits_stored;
        img.signed = signed;
        if let Some((slope, intercept)) = rescale {
            img.slope = Some(slope);
            img.intercept = Some(intercept);
        }
        write(&dir.path().join(format!("{k}.dcm")), &img);
    }
    read_volume(dir.path()).unwrap()
}

#[test]
fn pixel_types_and_rescale() {
    let s = [[0, 1, 2, 3, 4, 250], [5, 6, 7, 8, 9, 255]];
    let AnyVolume::U8(v) = two_slices(8, 8, false, s, None) else {
        panic!("u8 expected")
    };
    assert_eq!(v.data()[5], 250);

    let s = [[0, 1, 2, 3, 4, 60000], [5, 6, 7, 8, 9, 65535]];
    let AnyVolume::U16(v) = two_slices(16, 16, false, s, None) else {
        panic!("u16 expected")
    };
    assert_eq!((v.data()[5], v.data()[11]), (60000, 65535));

    let neg = |x: i16| x as u16;
    let s = [
        [neg(-32768), neg(-1), 0, 1, 2, 3],
        [4, 5, 6, 7, 8, neg(32767)],
    ];
    let v = two_slices(16, 16, true, s, None);
    assert_eq!(&i16_data(&v)[..3], &[-32768, -1, 0]);

    // 12 stored bits: the top 4 bits hold something else and are masked;
    // signed 12-bit 0xFFF is -1.
    let s = [
        [0xF000 | 0x0FFF, 0x0800, 0x07FF, 0, 1, 2],
        [3, 4, 5, 6, 7, 8],
    ];
    let v = two_slices(16, 12, true, s, None);
    assert_eq!(&i16_data(&v)[..3], &[-1, -2048, 2047]);

    // CT: unsigned 12-bit with intercept -1024 gives HU in i16.
    let s = [[0, 1024, 4095, 0, 0, 0], [1, 2, 3, 4, 5, 6]];
    let v = two_slices(16, 12, false, s, Some((1.0, -1024.0)));
    assert_eq!(&i16_data(&v)[..3], &[-1024, 0, 3071]);

    // Any other slope gives f32.
    let s = [[0, 1, 2, 3, 4, 5], [6, 7, 8, 9, 10, 11]];
    let AnyVolume::F32(v) = two_slices(16, 16, false, s, Some((0.5, 1.25))) else {
        panic!("f32 expected")
    };
    assert_eq!(&v.data()[..3], &[1.25, 1.75, 2.25]);
}

#[test]
fn several_series_are_listed_and_chosen() {
    let dir = tempfile::tempdir().unwrap();
    for k in 0..3 {
        write(
            &dir.path().join(format!("a{k}.dcm")),
            &Img::new([0.0, 0.0, k as f64], samples(k)),
        );
    }
    for k in 0..2 {
        let mut img = Img::new([0.0, 0.0, 3.0 * k as f64], samples(k));
        img.series = "1.2.3.2".into();
        write(&dir.path().join(format!("b{k}.dcm")), &img);
    }
    // Not DICOM: ignored.
    std::fs::write(dir.path().join("notes.txt"), "scanner notes").unwrap();
    let list = dicom::list_series(dir.path()).unwrap();
    assert_eq!(list.len(), 2);
    assert_eq!(
        (list[0].uid.as_str(), list[0].files, list[0].dims),
        ("1.2.3.1", 3, [3, 2, 3])
    );
    assert_eq!(
        (list[1].uid.as_str(), list[1].files, list[1].dims),
        ("1.2.3.2", 2, [3, 2, 2])
    );
    assert_eq!(list[0].description, "test series");
    let e = err(dir.path(), None);
    assert!(
        e.contains("2 DICOM series") && e.contains("1.2.3.1") && e.contains("1.2.3.2"),
        "{e}"
    );
    let v = read_volume_series(dir.path(), Some("1.2.3.2")).unwrap();
    assert_eq!(v.geometry().dims, [3, 2, 2]);
    assert!((v.geometry().spacing[2] - 3.0).abs() < 1e-12);
    let e = err(dir.path(), Some("9.9"));
    assert!(e.contains("no DICOM series 9.9"), "{e}");
}

#[test]
fn series_option_on_other_formats_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("v.nrrd");
    let g = interslice_core::Geometry::new([2, 2, 2], [1.0; 3], Default::default()).unwrap();
    let v = AnyVolume::U8(interslice_core::Volume::zeros(g));
    interslice_io::write_volume(&p, &v).unwrap();
    let e = err(&p, Some("1.2"));
    assert!(e.contains("DICOM series") && e.contains("NRRD"), "{e}");
    let e = interslice_io::write_volume(&dir.path().join("out.dcm"), &v).unwrap_err();
    assert!(
        e.to_string().contains("writing DICOM is not supported"),
        "{e}"
    );
}

#[test]
fn single_slice_without_position_reads() {
    let dir = tempfile::tempdir().unwrap();
    let mut img = Img::new([0.0; 3], samples(1));
    img.position = None;
    img.orientation = None;
    let path = dir.path().join("one.dcm");
    write(&path, &img);
    let v = read_volume(&path).unwrap();
    assert_eq!(v.geometry().dims, [3, 2, 1]);
    assert_eq!(v.geometry().origin, [0.0; 3]);
}

#[test]
fn hostile_files_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.dcm");
    write(&good, &Img::new([0.0; 3], samples(0)));
    let bytes = std::fs::read(&good).unwrap();
    let case = dir.path().join("case");
    std::fs::create_dir(&case).unwrap();
    let file = case.join("x.dcm");
    // Every prefix past the magic, and byte flips across the file: an error
    // or a volume, never a panic.
    let mut cuts: Vec<usize> = (132..bytes.len()).step_by(7).collect();
    cuts.push(bytes.len() - 1);
    for n in cuts {
        std::fs::write(&file, &bytes[..n]).unwrap();
        if let Err(e) = read_volume(&case) {
            assert!(!e.to_string().contains('\n'), "{e}");
        }
    }
    for i in (132..bytes.len()).step_by(3) {
        let mut b = bytes.clone();
        b[i] ^= 0xA5;
        std::fs::write(&file, &b).unwrap();
        if let Err(e) = read_volume(&case) {
            assert!(!e.to_string().contains('\n'), "{e}");
        }
    }
    // Headers that claim more than the data holds.
    let mut img = Img::new([0.0; 3], samples(0));
    img.rows = 60000;
    img.cols = 60000;
    write(&file, &img);
    let e = err(&case, None);
    // Refused before any pixel memory: by the read limits (2^31 voxels) or
    // because the file is too short for what its header claims.
    assert!(
        (e.contains("file is truncated") && e.contains("x.dcm")) || e.contains("too large"),
        "{e}"
    );
    let mut img = Img::new([0.0; 3], samples(0));
    img.legacy_frames = Some(1 << 30);
    write(&file, &img);
    let e = err(&case, None);
    assert!(e.contains("NumberOfFrames"), "{e}");
    // A folder with DICM files that are not images.
    std::fs::write(&file, [&[0u8; 128][..], b"DICM"].concat()).unwrap();
    let e = err(&case, None);
    assert!(e.contains("x.dcm"), "{e}");
}
