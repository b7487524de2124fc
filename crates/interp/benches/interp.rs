//! Interpolation speed: `shape-based` and the default method on a 256³ label
//! volume drawn every 10th slice (k = 9 skipped), and every registered
//! method on the 200³ phantom at k = 9; the combination of z and x slices
//! (`multi_axis::combine`) of the 128³ phantom's cell, every 10th slice;
//! `advise` (five suggestions) on a 256×256×60 block of the 256³ phantom
//! drawn every 10th slice, shape-only and with the image.
//!
//! `cargo bench -p interslice-interp --bench interp`
use criterion::{Criterion, criterion_group, criterion_main};
use interslice_core::phantom::{PhantomParams, generate};
use interslice_core::{Axis, LabelVolume, Volume};
use interslice_interp::{DEFAULT_METHOD, by_name, interpolate_labels, methods};
use std::hint::black_box;

/// The phantom's labels with every slice but the drawn ones erased.
fn sparse(size: usize, k: usize) -> (LabelVolume, Vec<usize>) {
    let p = generate(&PhantomParams {
        size,
        seed: 1,
        bits: 8,
        noise: 0.0,
    })
    .expect("phantom");
    let nonempty = interslice_interp::drawn::nonempty_slices(&p.labels, Axis::Z);
    let (first, last) = (nonempty[0], *nonempty.last().expect("non-empty"));
    let mut drawn: Vec<usize> = (first..=last).step_by(k + 1).collect();
    if drawn.last() != Some(&last) {
        drawn.push(last);
    }
    let mut s: LabelVolume = Volume::zeros(p.labels.geometry().clone());
    for &d in &drawn {
        s.set_slice(Axis::Z, d, &p.labels.slice(Axis::Z, d).expect("in range"))
            .expect("same");
    }
    (s, drawn)
}

fn bench_256(c: &mut Criterion) {
    let (s, drawn) = sparse(256, 9);
    let mut g = c.benchmark_group("interp_256_k9");
    g.sample_size(10);
    for name in ["shape-based", DEFAULT_METHOD] {
        let m = by_name(name).expect("registered");
        g.bench_function(name, |b| {
            b.iter(|| interpolate_labels(m.as_ref(), black_box(&s), Axis::Z, &drawn).expect("ok"))
        });
    }
    g.finish();
}

fn bench_phantom_200(c: &mut Criterion) {
    let (s, drawn) = sparse(200, 9);
    let mut g = c.benchmark_group("interp_200_k9");
    g.sample_size(10);
    for m in methods() {
        g.bench_function(m.name(), |b| {
            b.iter(|| interpolate_labels(m.as_ref(), black_box(&s), Axis::Z, &drawn).expect("ok"))
        });
    }
    g.finish();
}

fn bench_multi_axis_128(c: &mut Criterion) {
    use interslice_interp::SparseMask;
    use interslice_interp::multi_axis::combine;
    let p = generate(&PhantomParams {
        size: 128,
        seed: 1,
        bits: 8,
        noise: 0.0,
    })
    .expect("phantom");
    let cell = p.labels.map(|l| l >= 1);
    let drawn: Vec<usize> = (4..128).step_by(10).collect();
    let keep = |axis: Axis| {
        let mut m = Volume::zeros(cell.geometry().clone());
        for &d in &drawn {
            m.set_slice(axis, d, &cell.slice(axis, d).expect("in range"))
                .expect("same");
        }
        m
    };
    let (z, x) = (keep(Axis::Z), keep(Axis::X));
    let mut g = c.benchmark_group("multi_axis_128_every_10th");
    g.sample_size(10);
    for name in ["shape-based", DEFAULT_METHOD] {
        let m = by_name(name).expect("registered");
        g.bench_function(name, |b| {
            b.iter(|| {
                let inputs = [
                    SparseMask::new(&z, Axis::Z, &drawn),
                    SparseMask::new(&x, Axis::X, &drawn),
                ];
                combine(m.as_ref(), black_box(&inputs)).expect("ok")
            })
        });
    }
    g.finish();
}

fn bench_advise_256x256x60(c: &mut Criterion) {
    use interslice_core::Geometry;
    use interslice_interp::advise::advise;
    use interslice_interp::image::Conditioned;
    let p = generate(&PhantomParams {
        size: 256,
        seed: 1,
        bits: 8,
        noise: 0.0,
    })
    .expect("phantom");
    // 60 slices through the middle of the cell.
    let (z0, nz, plane) = (98, 60, 256 * 256);
    let block = |g: &Geometry| Geometry {
        dims: [256, 256, nz],
        ..g.clone()
    };
    let labels = p.labels.data()[z0 * plane..(z0 + nz) * plane].to_vec();
    let labels = Volume::from_vec(block(p.labels.geometry()), labels).expect("block");
    let interslice_core::AnyVolume::U8(image) = &p.intensity else {
        panic!("an 8-bit phantom")
    };
    let image = image.map(f32::from);
    let image = image.data()[z0 * plane..(z0 + nz) * plane].to_vec();
    let image =
        Conditioned::from(Volume::from_vec(block(p.labels.geometry()), image).expect("block"));
    let drawn: Vec<usize> = (0..nz).step_by(10).chain([nz - 1]).collect();
    let mut sparse: LabelVolume = Volume::zeros(labels.geometry().clone());
    for &d in &drawn {
        sparse
            .set_slice(Axis::Z, d, &labels.slice(Axis::Z, d).expect("in range"))
            .expect("same");
    }
    let mut g = c.benchmark_group("advise_256x256x60_every_10th");
    g.sample_size(10);
    g.bench_function("shape-only", |b| {
        b.iter(|| advise(black_box(&sparse), Axis::Z, &drawn, 5, None, None).expect("ok"))
    });
    g.bench_function("with-image", |b| {
        b.iter(|| {
            advise(
                black_box(&sparse),
                Axis::Z,
                &drawn,
                5,
                None,
                Some(image.clone()),
            )
            .expect("ok")
        })
    });
    g.finish();
}

criterion_group!(
    benches,
    bench_256,
    bench_phantom_200,
    bench_multi_axis_128,
    bench_advise_256x256x60
);
criterion_main!(benches);
