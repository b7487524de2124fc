//! Benchmarks of the segmentation pathway: Otsu on a 512³ 16-bit volume
//! (parallel native histogram + threshold), the full `segment` at 256³, and
//! STAPLE of 3 raters at 256³. Run with `cargo bench -p interslice-core --bench segment`.
use criterion::{Criterion, criterion_group, criterion_main};
use interslice_core::segment::{SegmentParams, segment};
use interslice_core::staple::{StapleParams, staple};
use interslice_core::threshold::{Binning, Histogram, otsu};
use interslice_core::{AnyVolume, Geometry, LengthUnit, Mask, Volume};
use rand::{Rng, SeedableRng};
use std::hint::black_box;

/// A bimodal 16-bit volume: a bright ball on a noisy dark background.
fn volume(n: usize) -> AnyVolume {
    let g = Geometry::new([n, n, n], [0.35; 3], LengthUnit::Micrometre).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let c = n as f64 / 2.0;
    let r2 = (n as f64 / 3.0).powi(2);
    let mut data = Vec::with_capacity(g.len());
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let d2 = (i as f64 - c).powi(2) + (j as f64 - c).powi(2) + (k as f64 - c).powi(2);
                let base: f64 = if d2 < r2 { 30000.0 } else { 3000.0 };
                data.push((base + rng.gen_range(-2500.0..2500.0)) as u16);
            }
        }
    }
    AnyVolume::U16(Volume::from_vec(g, data).unwrap())
}

fn rater(truth: &Mask, flip: f64, seed: u64) -> Mask {
    // Flips drawn in storage order so the rater is the same on any thread count.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let data = truth
        .data()
        .iter()
        .map(|&t| if rng.gen_bool(flip) { !t } else { t })
        .collect();
    Mask::from_vec(truth.geometry().clone(), data).unwrap()
}

fn benches(c: &mut Criterion) {
    let mut g = c.benchmark_group("segment");
    g.sample_size(10);
    let v512 = volume(512);
    g.bench_function("otsu_u16_512", |b| {
        b.iter(|| {
            let h = Histogram::of_volume(black_box(&v512), Binning::Native).unwrap();
            black_box(otsu(&h).unwrap())
        })
    });
    drop(v512);
    let v256 = volume(256);
    g.bench_function("segment_otsu_u16_256", |b| {
        b.iter(|| {
            black_box(
                segment(
                    &v256,
                    &SegmentParams::default(),
                    &interslice_core::Cancel::new(),
                )
                .unwrap(),
            )
        })
    });
    let truth = match &v256 {
        AnyVolume::U16(x) => x.map(|a| a > 16000),
        _ => unreachable!(),
    };
    drop(v256);
    let raters = [
        rater(&truth, 0.01, 1),
        rater(&truth, 0.02, 2),
        rater(&truth, 0.05, 3),
    ];
    let refs: Vec<&Mask> = raters.iter().collect();
    g.bench_function("staple_3_raters_256", |b| {
        b.iter(|| {
            black_box(
                staple(
                    &refs,
                    StapleParams::default(),
                    &interslice_core::Cancel::new(),
                )
                .unwrap(),
            )
        })
    });
    g.finish();
}

criterion_group!(segment_benches, benches);
criterion_main!(segment_benches);
