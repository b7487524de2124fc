//! A project folder holding DICOM folders: a folder with one series is one
//! cell; a folder with several series gives one cell per series, each of
//! which reads its own series.
use dicom_core::{DataElement, PrimitiveValue, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
use interslice_core::AnyVolume;
use interslice_project::cells::{LoadedCell, display_name, scan, series_of};
use std::path::Path;

/// Write `slices` 8×6 int16 slices of series `uid` (SeriesNumber `number`)
/// into `dir`, voxel value `base + k` on slice k.
fn series(dir: &Path, uid: &str, number: i32, slices: usize, base: i16) {
    for k in 0..slices {
        let mut o = InMemDicomObject::new_empty();
        let mut put = |tag, vr, v| o.put(DataElement::new(tag, vr, v));
        put(
            tags::SOP_CLASS_UID,
            VR::UI,
            PrimitiveValue::from("1.2.840.10008.5.1.4.1.1.4"),
        );
        put(
            tags::SOP_INSTANCE_UID,
            VR::UI,
            PrimitiveValue::from(format!("{uid}.{k}")),
        );
        put(tags::SERIES_INSTANCE_UID, VR::UI, PrimitiveValue::from(uid));
        put(
            tags::SERIES_NUMBER,
            VR::IS,
            PrimitiveValue::from(number.to_string()),
        );
        put(tags::MODALITY, VR::CS, PrimitiveValue::from("MR"));
        let z = format!("{:.1}", 2.5 * k as f64);
        put(
            tags::IMAGE_POSITION_PATIENT,
            VR::DS,
            PrimitiveValue::Strs(vec!["0".into(), "0".into(), z].into_iter().collect()),
        );
        put(
            tags::IMAGE_ORIENTATION_PATIENT,
            VR::DS,
            PrimitiveValue::Strs(
                ["1", "0", "0", "0", "1", "0"]
                    .map(String::from)
                    .into_iter()
                    .collect(),
            ),
        );
        put(
            tags::PIXEL_SPACING,
            VR::DS,
            PrimitiveValue::Strs(["0.5", "0.5"].map(String::from).into_iter().collect()),
        );
        put(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16));
        put(
            tags::PHOTOMETRIC_INTERPRETATION,
            VR::CS,
            PrimitiveValue::from("MONOCHROME2"),
        );
        put(tags::ROWS, VR::US, PrimitiveValue::from(6u16));
        put(tags::COLUMNS, VR::US, PrimitiveValue::from(8u16));
        put(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(16u16));
        put(tags::BITS_STORED, VR::US, PrimitiveValue::from(16u16));
        put(tags::HIGH_BIT, VR::US, PrimitiveValue::from(15u16));
        put(
            tags::PIXEL_REPRESENTATION,
            VR::US,
            PrimitiveValue::from(1u16),
        );
        let pixels = vec![(base + k as i16) as u16; 48];
        put(tags::PIXEL_DATA, VR::OW, PrimitiveValue::U16(pixels.into()));
        let file = o
            .with_meta(FileMetaTableBuilder::new().transfer_syntax("1.2.840.10008.1.2.1"))
            .unwrap();
        file.write_to_file(dir.join(format!("{uid}-{k}.dcm")))
            .unwrap();
    }
}

fn i16_voxels(c: &LoadedCell) -> Vec<i16> {
    match &c.volume {
        AnyVolume::I16(v) => v.data().to_vec(),
        other => panic!("i16 expected, got {}", other.type_name()),
    }
}

#[test]
fn one_cell_per_dicom_series() {
    let project = tempfile::tempdir().unwrap();
    let single = project.path().join("head");
    let multi = project.path().join("study");
    std::fs::create_dir_all(&single).unwrap();
    std::fs::create_dir_all(&multi).unwrap();
    series(&single, "1.2.9.1", 1, 3, 10);
    series(&multi, "1.2.9.7", 7, 4, 100);
    series(&multi, "1.2.9.3", 3, 5, 200);

    let cells = scan(project.path()).unwrap();
    let ids: Vec<&str> = cells.keys().map(String::as_str).collect();
    assert_eq!(ids, ["head", "study-s3", "study-s7"]);
    assert_eq!(cells["head"], single);
    assert_eq!(
        series_of(&cells["study-s3"]),
        Some((multi.as_path(), "1.2.9.3"))
    );
    assert_eq!(display_name(&cells["study-s7"]), "study (series 1.2.9.7)");

    let head = LoadedCell::load(&cells["head"]).unwrap();
    assert_eq!(head.volume.geometry().dims, [8, 6, 3]);
    let s3 = LoadedCell::load(&cells["study-s3"]).unwrap();
    assert_eq!(s3.volume.geometry().dims, [8, 6, 5]);
    assert_eq!(i16_voxels(&s3)[48 * 4], 204);
    let s7 = LoadedCell::load(&cells["study-s7"]).unwrap();
    assert_eq!(s7.volume.geometry().dims, [8, 6, 4]);
    assert_eq!(i16_voxels(&s7)[48 * 3], 103);
    assert!((s7.volume.geometry().spacing[2] - 2.5).abs() < 1e-9);
}

#[test]
fn repeated_series_numbers_fall_back_to_positions() {
    let project = tempfile::tempdir().unwrap();
    let multi = project.path().join("scan");
    std::fs::create_dir_all(&multi).unwrap();
    series(&multi, "1.2.9.1", 2, 2, 0);
    series(&multi, "1.2.9.2", 2, 3, 0);
    let cells = scan(project.path()).unwrap();
    let ids: Vec<&str> = cells.keys().map(String::as_str).collect();
    assert_eq!(ids, ["scan-1", "scan-2"]);
    let dims: Vec<usize> = cells
        .values()
        .map(|p| LoadedCell::load(p).unwrap().volume.geometry().dims[2])
        .collect();
    assert_eq!(dims, [2, 3]);
}
