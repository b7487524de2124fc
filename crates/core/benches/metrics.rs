//! Benchmarks of the metrics: overlap counts on a 512³ pair beside the raw
//! one-pass read of both arrays (the floor any overlap metric can reach), the
//! full metrics (HD95, ASSD, ...) on a 256³ and a 512³ pair, and the exact EDT
//! on 256³.
//!
//! The `blob_*` groups run on the irregular blob pairs of
//! `python/bench/blobs.py` (dense borders, about a tenth of the voxels, close
//! to each other), as written by `blobs.py --raw DIR`: uint8, x fastest,
//! spacing 0.35 × 0.35 × 0.5 µm. Set `INTERSLICE_BLOBS=DIR` to run them;
//! without it they are skipped.
//! Run with `cargo bench -p interslice-core --bench metrics` (add `-- blob` for
//! the blob groups only).
use criterion::{Criterion, criterion_group, criterion_main};
use interslice_core::edt::{squared_edt_3d, squared_edt_3d_f32};
use interslice_core::metrics::{confusion_of, evaluate_label, evaluate_label_data, overlap_only};
use interslice_core::{Geometry, LabelVolume, LengthUnit, Volume};
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Duration;

/// A ball in voxel coordinates.
#[derive(Clone, Copy)]
struct Ball {
    c: [f64; 3],
    r: f64,
}

/// Seeded blob pair: a large ball with random bumps and dents for the ground
/// truth; the segmentation moves every ball by up to 2 voxels and changes its
/// radius by up to 10 %, like a segmentation that is close but not equal.
fn blob_pair(n: usize, seed: u64) -> (LabelVolume, LabelVolume) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let h = n as f64 / 2.0;
    let mut gt = vec![Ball {
        c: [h, h, h],
        r: 0.33 * n as f64,
    }];
    let mut dents = vec![];
    for b in 0..24 {
        // Points near the surface of the main ball.
        let dir: [f64; 3] = [0, 1, 2].map(|_| rng.gen_range(-1.0..1.0));
        let len = dir.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-9);
        let at = [0, 1, 2].map(|a| h + dir[a] / len * 0.33 * n as f64);
        let ball = Ball {
            c: at,
            r: rng.gen_range(0.04..0.12) * n as f64,
        };
        if b % 3 == 0 {
            dents.push(ball)
        } else {
            gt.push(ball)
        }
    }
    let mut jitter = |bs: &[Ball]| -> Vec<Ball> {
        bs.iter()
            .map(|b| Ball {
                c: b.c.map(|x| x + rng.gen_range(-2.0..2.0)),
                r: b.r * rng.gen_range(0.9..1.1),
            })
            .collect()
    };
    let seg = jitter(&gt);
    let seg_dents = jitter(&dents);
    let g = Geometry::new([n; 3], [0.35, 0.35, 0.5], LengthUnit::Micrometre).unwrap();
    // Paint each ball as runs along x (the setup of the 512³ pair stays fast).
    let paint = |balls: &[Ball], dents: &[Ball]| -> Vec<u16> {
        let mut data = vec![0u16; n * n * n];
        let run = |b: &Ball, y: f64, z: f64| -> Option<(usize, usize)> {
            let r2 = b.r * b.r - (y - b.c[1]).powi(2) - (z - b.c[2]).powi(2);
            if r2 < 0.0 {
                return None;
            }
            let h = r2.sqrt();
            let lo = (b.c[0] - h).ceil().max(0.0) as usize;
            let hi = ((b.c[0] + h).floor() + 1.0).clamp(0.0, n as f64) as usize;
            (lo < hi).then_some((lo, hi))
        };
        data.par_chunks_mut(n * n)
            .enumerate()
            .for_each(|(k, slab)| {
                let z = k as f64;
                for (j, row) in slab.chunks_mut(n).enumerate() {
                    let y = j as f64;
                    for b in balls {
                        if let Some((lo, hi)) = run(b, y, z) {
                            row[lo..hi].fill(1);
                        }
                    }
                    for b in dents {
                        if let Some((lo, hi)) = run(b, y, z) {
                            row[lo..hi].fill(0);
                        }
                    }
                }
            });
        data
    };
    (
        Volume::from_vec(g.clone(), paint(&gt, &dents)).unwrap(),
        Volume::from_vec(g, paint(&seg, &seg_dents)).unwrap(),
    )
}

/// The floor: read both arrays once and count equal voxels.
fn count_equal<T: Copy + PartialEq + Sync>(a: &[T], b: &[T]) -> u64 {
    a.par_chunks(1 << 16)
        .zip(b.par_chunks(1 << 16))
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| u32::from(p == q)).sum::<u32>() as u64)
        .sum()
}

fn overlap_512(c: &mut Criterion) {
    let (gt, seg) = blob_pair(512, 512);
    let gt8: Vec<u8> = gt.data().par_iter().map(|&x| x as u8).collect();
    let seg8: Vec<u8> = seg.data().par_iter().map(|&x| x as u8).collect();
    let mut g = c.benchmark_group("overlap_512");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    g.bench_function("floor_count_equal_u8", |b| {
        b.iter(|| count_equal(black_box(&gt8), black_box(&seg8)))
    });
    g.bench_function("confusion_u8", |b| {
        b.iter(|| confusion_of(black_box(&gt8), black_box(&seg8), 1u8))
    });
    g.bench_function("floor_count_equal_u16", |b| {
        b.iter(|| count_equal(black_box(gt.data()), black_box(seg.data())))
    });
    g.bench_function("overlap_only_u16", |b| {
        b.iter(|| overlap_only(black_box(&gt), black_box(&seg), 1).unwrap())
    });
    g.finish();
}

fn distances_256(c: &mut Criterion) {
    let (gt, seg) = blob_pair(256, 256);
    let mut g = c.benchmark_group("metrics_256");
    g.sample_size(10).measurement_time(Duration::from_secs(6));
    g.bench_function("evaluate_label_all_metrics", |b| {
        b.iter(|| evaluate_label(black_box(&gt), black_box(&seg), 1, 1.0).unwrap())
    });
    g.finish();
}

fn distances_512(c: &mut Criterion) {
    let (gt, seg) = blob_pair(512, 512);
    let mut g = c.benchmark_group("metrics_512");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function("evaluate_label_all_metrics", |b| {
        b.iter(|| evaluate_label(black_box(&gt), black_box(&seg), 1, 1.0).unwrap())
    });
    g.finish();
}

fn edt_256(c: &mut Criterion) {
    let (gt, _) = blob_pair(256, 256);
    let features: Vec<bool> = gt.data().par_iter().map(|&x| x == 0).collect();
    let mut g = c.benchmark_group("edt_256");
    g.sample_size(10).measurement_time(Duration::from_secs(6));
    g.bench_function("squared_edt_3d_f64", |b| {
        b.iter(|| squared_edt_3d(black_box(&features), [256; 3], [0.35, 0.35, 0.5]))
    });
    g.bench_function("squared_edt_3d_f32", |b| {
        b.iter(|| squared_edt_3d_f32(black_box(&features), [256; 3], [0.35, 0.35, 0.5]))
    });
    g.finish();
}

/// The blob pair of size `n` from the folder named by `INTERSLICE_BLOBS`, or
/// `None` (with a printed line) when it is unset or the files are missing.
fn blob_files(n: usize) -> Option<(Vec<u8>, Vec<u8>)> {
    let Some(dir) = std::env::var_os("INTERSLICE_BLOBS") else {
        println!("blob_{n}: skipped (set INTERSLICE_BLOBS to the folder of `blobs.py --raw`)");
        return None;
    };
    let dir = std::path::PathBuf::from(dir);
    let read = |role: &str| -> Option<Vec<u8>> {
        let path = dir.join(format!("blob{n}_{role}.u8"));
        match std::fs::read(&path) {
            Ok(v) if v.len() == n * n * n => Some(v),
            Ok(v) => {
                println!(
                    "blob_{n}: skipped ({} has {} bytes, not {n}³)",
                    path.display(),
                    v.len()
                );
                None
            }
            Err(e) => {
                println!("blob_{n}: skipped ({}: {e})", path.display());
                None
            }
        }
    };
    Some((read("gt")?, read("pred")?))
}

fn blob(c: &mut Criterion, n: usize, secs: u64) {
    let Some((gt, seg)) = blob_files(n) else {
        return;
    };
    let geo = Geometry::new([n; 3], [0.35, 0.35, 0.5], LengthUnit::Micrometre).unwrap();
    let mut g = c.benchmark_group(format!("blob_{n}"));
    g.sample_size(10)
        .measurement_time(Duration::from_secs(secs));
    g.bench_function("floor_count_equal", |b| {
        b.iter(|| count_equal(black_box(&gt), black_box(&seg)))
    });
    g.bench_function("overlap_only", |b| {
        b.iter(|| confusion_of(black_box(&gt), black_box(&seg), 1u8))
    });
    g.bench_function("evaluate_label", |b| {
        b.iter(|| evaluate_label_data(&geo, black_box(&gt), black_box(&seg), 1u8, 1.0).unwrap())
    });
    g.finish();
}

fn blob_256(c: &mut Criterion) {
    blob(c, 256, 6);
}

fn blob_512(c: &mut Criterion) {
    blob(c, 512, 20);
}

criterion_group!(
    benches,
    overlap_512,
    distances_256,
    distances_512,
    edt_256,
    blob_256,
    blob_512
);
criterion_main!(benches);
