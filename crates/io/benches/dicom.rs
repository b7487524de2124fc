//! Reading a 512 x 512 x 61 int16 CT series (61 DICOM files written here,
//! oblique, intercept -1024): the header scan that lists the series, the
//! whole read that `interslice info` does, and the read plus the copy of the
//! first slice that a viewer serves. Run with
//! `cargo bench -p interslice-io --bench dicom`.
use criterion::{Criterion, criterion_group, criterion_main};
use dicom_core::{DataElement, PrimitiveValue, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
use interslice_core::{AnyVolume, Axis};
use std::hint::black_box;
use std::path::Path;

const N: usize = 512;
const SLICES: usize = 61;

fn ds(values: &[f64]) -> PrimitiveValue {
    PrimitiveValue::Strs(values.iter().map(|v| format!("{v:.6}")).collect())
}

/// A CT-like series: a disc of soft tissue (around 1064 stored, 40 HU) in air.
fn write_series(dir: &Path) {
    let tilt = 0.2f64;
    let (c, s) = (tilt.cos(), tilt.sin());
    for k in 0..SLICES {
        let mut o = InMemDicomObject::new_empty();
        let mut put = |tag, vr, v| {
            o.put(DataElement::new(tag, vr, v));
        };
        put(
            tags::SOP_CLASS_UID,
            VR::UI,
            PrimitiveValue::from("1.2.840.10008.5.1.4.1.1.2"),
        );
        put(
            tags::SOP_INSTANCE_UID,
            VR::UI,
            PrimitiveValue::from(format!("1.2.3.4.{k}")),
        );
        put(
            tags::SERIES_INSTANCE_UID,
            VR::UI,
            PrimitiveValue::from("1.2.3.4"),
        );
        put(tags::MODALITY, VR::CS, PrimitiveValue::from("CT"));
        let z = 1.25 * k as f64;
        put(
            tags::IMAGE_POSITION_PATIENT,
            VR::DS,
            ds(&[-160.0, -160.0 - z * s, z * c]),
        );
        put(
            tags::IMAGE_ORIENTATION_PATIENT,
            VR::DS,
            ds(&[1.0, 0.0, 0.0, 0.0, c, s]),
        );
        put(tags::PIXEL_SPACING, VR::DS, ds(&[0.625, 0.625]));
        put(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16));
        put(
            tags::PHOTOMETRIC_INTERPRETATION,
            VR::CS,
            PrimitiveValue::from("MONOCHROME2"),
        );
        put(tags::ROWS, VR::US, PrimitiveValue::from(N as u16));
        put(tags::COLUMNS, VR::US, PrimitiveValue::from(N as u16));
        put(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(16u16));
        put(tags::BITS_STORED, VR::US, PrimitiveValue::from(16u16));
        put(tags::HIGH_BIT, VR::US, PrimitiveValue::from(15u16));
        put(
            tags::PIXEL_REPRESENTATION,
            VR::US,
            PrimitiveValue::from(1u16),
        );
        put(tags::RESCALE_SLOPE, VR::DS, ds(&[1.0]));
        put(tags::RESCALE_INTERCEPT, VR::DS, ds(&[-1024.0]));
        let pixels: Vec<u16> = (0..N * N)
            .map(|i| {
                let (x, y) = ((i % N) as f64 - 256.0, (i / N) as f64 - 256.0);
                let inside = x * x + y * y < 200.0 * 200.0;
                (if inside {
                    1064 + (i * 7 + k) % 40
                } else {
                    (i * 13) % 20
                }) as u16
            })
            .collect();
        put(tags::PIXEL_DATA, VR::OW, PrimitiveValue::U16(pixels.into()));
        let file = o
            .with_meta(FileMetaTableBuilder::new().transfer_syntax("1.2.840.10008.1.2.1"))
            .unwrap();
        // Names that do not sort in slice order.
        file.write_to_file(dir.join(format!("IM{:04}", (k * 37) % 101)))
            .unwrap();
    }
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    write_series(dir.path());
    let mut g = c.benchmark_group("dicom 512x512x61 i16");
    g.sample_size(10);
    g.bench_function("list series (headers)", |b| {
        b.iter(|| black_box(interslice_io::dicom::list_series(dir.path()).unwrap()))
    });
    g.bench_function("read volume (info)", |b| {
        b.iter(|| black_box(interslice_io::read_volume(dir.path()).unwrap()))
    });
    g.bench_function("read volume + first slice", |b| {
        b.iter(|| {
            let AnyVolume::I16(v) = interslice_io::read_volume(dir.path()).unwrap() else {
                panic!("i16 expected")
            };
            let slice: Vec<i16> = v.view(Axis::Z, 0).unwrap().iter().collect();
            black_box(slice)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
