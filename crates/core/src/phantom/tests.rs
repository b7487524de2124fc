use super::*;
use crate::Axis;

fn params(size: usize, seed: u64, bits: u8, noise: f64) -> PhantomParams {
    PhantomParams {
        size,
        seed,
        bits,
        noise,
    }
}

fn values(v: &AnyVolume) -> Vec<f64> {
    match v {
        AnyVolume::U8(v) => v.data().iter().map(|&x| x as f64).collect(),
        AnyVolume::U16(v) => v.data().iter().map(|&x| x as f64).collect(),
        _ => unreachable!("phantoms are u8 or u16"),
    }
}

fn centre(g: &Geometry, idx: usize) -> [f64; 3] {
    let [i, j, k] = g.ijk(idx);
    [i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5]
}

#[test]
fn bad_params_are_errors() {
    for p in [
        params(0, 1, 8, 0.0),
        params(MIN_SIZE - 1, 1, 8, 0.0),
        params(MAX_SIZE + 1, 1, 8, 0.0),
        params(64, 1, 12, 0.0),
        params(64, 1, 8, -0.1),
        params(64, 1, 8, f64::NAN),
        params(64, 1, 8, 0.6),
    ] {
        let e = generate(&p).unwrap_err().to_string();
        assert!(e.starts_with("phantom ") && !e.contains('\n'), "{e}");
    }
}

#[test]
fn structures_nest_and_match_the_model() {
    let mut seen_counts = std::collections::BTreeSet::new();
    for seed in 1..=12u64 {
        let p = params(40, seed, 8, 0.02);
        let m = model(&p).unwrap();
        seen_counts.insert(m.nucleoli.len());
        assert!((1..=3).contains(&m.nucleoli.len()));
        if seed > 4 {
            continue; // rendering is checked on a few seeds, the model on all
        }
        let ph = generate(&p).unwrap();
        let g = ph.labels.geometry().clone();
        let max_label = 2 + m.nucleoli.len() as u16;
        for (idx, &l) in ph.labels.data().iter().enumerate() {
            assert!(l <= max_label, "label {l}");
            let c = centre(&g, idx);
            // Every labelled voxel is inside the structures that contain it.
            assert_eq!(l >= 1, m.cell.contains(c));
            if l >= 2 {
                assert!(m.nucleus.contains(c) && m.cell.contains(c));
            }
            if l >= 3 {
                assert!(m.nucleoli[(l - 3) as usize].contains(c));
            }
            // The cell never touches the border of the volume.
            let [i, j, k] = g.ijk(idx);
            if [i, j, k].iter().any(|&x| x == 0 || x == 39) {
                assert_eq!(l, 0, "border voxel {i},{j},{k}");
            }
        }
        // Every structure exists; counts are consistent and volumes physical.
        let s = &ph.structures;
        assert_eq!(s.len(), 2 + m.nucleoli.len());
        assert_eq!(s[0].name, "Cell");
        assert_eq!(s[1].name, "Nucleus");
        assert_eq!(s[2].name, "Nucleolus 1");
        let nonzero = ph.labels.data().iter().filter(|&&l| l > 0).count() as u64;
        let nuclear = ph.labels.data().iter().filter(|&&l| l >= 2).count() as u64;
        assert_eq!(s[0].voxels, nonzero);
        assert_eq!(s[1].voxels, nuclear);
        assert_eq!(s.iter().map(|x| x.label_voxels).sum::<u64>(), nonzero);
        for x in s {
            assert!(x.label_voxels > 0, "{} is empty", x.name);
            let want = x.voxels as f64 * 0.35 * 0.35 * 0.35;
            assert!((x.volume - want).abs() <= 1e-9 * want);
        }
        let ratio = s[1].voxels as f64 / s[0].voxels as f64;
        assert!(
            (0.05..0.4).contains(&ratio),
            "nucleus/cell volume ratio {ratio}"
        );
    }
    assert!(
        seen_counts.len() >= 2,
        "nucleolus counts vary: {seen_counts:?}"
    );
}

#[test]
fn mean_intensity_increases_with_stain_density() {
    for (bits, noise, seed) in [(8, 0.02, 3), (16, 0.1, 4), (8, 0.0, 5)] {
        let ph = generate(&params(48, seed, bits, noise)).unwrap();
        let vals = values(&ph.intensity);
        let mut sum = [0.0f64; 4];
        let mut cnt = [0usize; 4];
        for (v, &l) in vals.iter().zip(ph.labels.data()) {
            let c = (l as usize).min(3);
            sum[c] += v;
            cnt[c] += 1;
        }
        let mean: Vec<f64> = (0..4).map(|c| sum[c] / cnt[c] as f64).collect();
        assert!(
            mean.windows(2).all(|w| w[0] < w[1]),
            "bits {bits}: means background, cytoplasm, nucleus, nucleoli = {mean:?}"
        );
        // Levels near the model's. The background is compared by its median:
        // quantisation clips the noise at 0, which lifts the *mean* of a level
        // of 0.05 with noise 0.1 by 0.02 (E[max(X, 0)] = 0.0698 for
        // X ~ N(0.05, 0.1²)), while the median stays at 0.05. Nucleoli are only
        // 2-3 voxels in radius at this size, so the blur (σ = 0.7 voxel) mixes
        // most of their voxels with the darker nucleus: their mean sits about
        // 0.11 below the model level here (0.05 at 128³), hence 0.15.
        let full = if bits == 8 { 255.0 } else { 65535.0 };
        let mut bg: Vec<f64> = vals
            .iter()
            .zip(ph.labels.data())
            .filter(|(_, l)| **l == 0)
            .map(|(v, _)| v / full)
            .collect();
        bg.sort_by(f64::total_cmp);
        let bg_median = bg[bg.len() / 2];
        assert!((bg_median - LEVEL_BACKGROUND).abs() < 0.01, "{bg_median}");
        assert!((mean[3] / full - LEVEL_NUCLEOLUS).abs() < 0.15, "{mean:?}");
    }
}

#[test]
fn noise_has_the_requested_standard_deviation() {
    // Far from the cell (the corner 6³ block) the clean field is the flat background.
    for (noise, bits) in [(0.0, 8u8), (0.05, 8), (0.03, 16)] {
        let ph = generate(&params(64, 9, bits, noise)).unwrap();
        let full = if bits == 8 { 255.0 } else { 65535.0 };
        let g = ph.labels.geometry().clone();
        let vals = values(&ph.intensity);
        let corner: Vec<f64> = (0..6)
            .flat_map(|k| (0..6).flat_map(move |j| (0..6).map(move |i| (i, j, k))))
            .map(|(i, j, k)| vals[g.index(i, j, k)] / full)
            .collect();
        let mean = corner.iter().sum::<f64>() / corner.len() as f64;
        let sd = (corner.iter().map(|v| (v - mean).powi(2)).sum::<f64>()
            / (corner.len() - 1) as f64)
            .sqrt();
        if noise == 0.0 {
            assert!(
                corner
                    .iter()
                    .all(|&v| v == (LEVEL_BACKGROUND * full).round() / full)
            );
        } else {
            assert!((sd / noise - 1.0).abs() < 0.15, "noise {noise}: sd {sd}");
            assert!(
                (mean - LEVEL_BACKGROUND).abs()
                    < 3.0 * noise / (corner.len() as f64).sqrt() + 0.003
            );
        }
    }
}

#[test]
fn same_seed_same_bytes_on_any_thread_count() {
    let p = params(40, 77, 16, 0.05);
    let a = generate(&p).unwrap();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = one.install(|| generate(&p).unwrap());
    assert_eq!(a, b);
    let c = generate(&params(40, 78, 16, 0.05)).unwrap();
    assert_ne!(a.labels, c.labels);
    assert_ne!(a.intensity, c.intensity);
    // The noise level changes the intensities but not the shapes.
    let d = generate(&params(40, 77, 16, 0.01)).unwrap();
    assert_eq!(a.labels, d.labels);
    assert_ne!(a.intensity, d.intensity);
}

#[test]
fn sizes_and_bit_depths() {
    for (size, bits) in [(32usize, 8u8), (33, 16), (64, 16)] {
        let ph = generate(&params(size, 2, bits, 0.02)).unwrap();
        let g = ph.intensity.geometry();
        assert_eq!(g.dims, [size; 3]);
        assert_eq!(g.spacing, [0.35; 3]);
        assert_eq!(g.unit, LengthUnit::Micrometre);
        assert_eq!(ph.labels.geometry(), g);
        assert_eq!(
            ph.intensity.type_name(),
            if bits == 8 { "u8" } else { "u16" }
        );
        let (_, max) = ph.intensity.min_max();
        if bits == 16 {
            assert!(max > 40000.0, "16-bit uses its range: max {max}");
        } else {
            assert!(max > 180.0 && max <= 255.0);
        }
        assert!(ph.structures.iter().all(|s| s.label_voxels > 0));
    }
}

/// Share of random pairs of voxels of `inside` whose joining segment leaves
/// it (sampled every half voxel): about 0 for a digitised convex shape
/// (rounding at the border), clearly more for an indented one.
///
/// An earlier version tested only the midpoint of each pair. Midpoints of
/// random pairs crowd towards the centre, so that measure barely sees a dent
/// at the periphery: a ball with a bite 80 % of its radius deep scored 0.002,
/// far below the 0.02 it was asked for. The whole segment does see it.
fn segment_defect(g: &Geometry, inside: &dyn Fn(u16) -> bool, labels: &[u16]) -> f64 {
    let voxels: Vec<[usize; 3]> = labels
        .iter()
        .enumerate()
        .filter(|(_, l)| inside(**l))
        .map(|(i, _)| g.ijk(i))
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let trials = 20_000;
    let mut outside = 0;
    for _ in 0..trials {
        let a = voxels[rng.gen_range(0..voxels.len())];
        let b = voxels[rng.gen_range(0..voxels.len())];
        let len = (0..3)
            .map(|d| (a[d] as f64 - b[d] as f64).powi(2))
            .sum::<f64>()
            .sqrt();
        let steps = (2.0 * len).ceil() as usize;
        let leaves = (1..steps).any(|s| {
            let t = s as f64 / steps as f64;
            let m: [usize; 3] = std::array::from_fn(|d| {
                (a[d] as f64 + t * (b[d] as f64 - a[d] as f64)).round() as usize
            });
            !inside(labels[g.index(m[0], m[1], m[2])])
        });
        outside += usize::from(leaves);
    }
    outside as f64 / trials as f64
}

#[test]
fn nucleus_is_indented_not_convex() {
    for seed in [1u64, 2, 3] {
        let ph = generate(&params(64, seed, 8, 0.0)).unwrap();
        let g = ph.labels.geometry().clone();
        let nucleus = segment_defect(&g, &|l| l >= 2, ph.labels.data());
        // The same measure on a digitised ball of similar size (the control).
        let m = model(&params(64, seed, 8, 0.0)).unwrap();
        let r = m.nucleus.radius;
        let ball: Vec<u16> = (0..g.len())
            .map(|i| {
                let p = centre(&g, i);
                let d2: f64 = (0..3).map(|a| (p[a] - 32.0).powi(2)).sum();
                u16::from(d2 <= r * r) * 2
            })
            .collect();
        let control = segment_defect(&g, &|l| l >= 2, &ball);
        assert!(control < 0.002, "ball: {control}");
        assert!(
            nucleus > 0.005 && nucleus > 5.0 * control,
            "seed {seed}: nucleus {nucleus}, ball {control}"
        );
    }
}

#[test]
fn slices_show_every_structure() {
    // The central z slice crosses cell and nucleus; a y slice too.
    let ph = generate(&params(48, 11, 8, 0.02)).unwrap();
    for axis in [Axis::Z, Axis::Y, Axis::X] {
        let s = ph.labels.slice(axis, 24).unwrap();
        assert!(s.contains(&1) && s.contains(&2), "axis {axis}");
    }
}
