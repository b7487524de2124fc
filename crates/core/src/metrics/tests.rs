//! Property tests of the metrics against a direct brute-force computation.
use super::*;
use crate::{Geometry, LengthUnit, Volume};
use proptest::prelude::*;

/// Border voxels by the definition, written independently of `border.rs`.
fn brute_border(m: &[bool], d: [usize; 3]) -> Vec<[usize; 3]> {
    let [nx, ny, nz] = d;
    let at = |i: isize, j: isize, k: isize| {
        i >= 0
            && j >= 0
            && k >= 0
            && (i as usize) < nx
            && (j as usize) < ny
            && (k as usize) < nz
            && m[i as usize + nx * (j as usize + ny * k as usize)]
    };
    let mut out = vec![];
    for k in 0..nz as isize {
        for j in 0..ny as isize {
            for i in 0..nx as isize {
                if at(i, j, k)
                    && [
                        (1, 0, 0),
                        (-1, 0, 0),
                        (0, 1, 0),
                        (0, -1, 0),
                        (0, 0, 1),
                        (0, 0, -1),
                    ]
                    .iter()
                    .any(|&(a, b, c)| !at(i + a, j + b, k + c))
                {
                    out.push([i as usize, j as usize, k as usize]);
                }
            }
        }
    }
    out
}

fn brute_directed(a: &[[usize; 3]], b: &[[usize; 3]], s: [f64; 3]) -> Vec<f64> {
    a.iter()
        .map(|p| {
            b.iter()
                .map(|q| {
                    (0..3)
                        .map(|x| ((p[x] as f64 - q[x] as f64) * s[x]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// numpy-style percentile on a sorted copy (independent of `stats.rs`).
fn brute_pct(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let h = (v.len() - 1) as f64 * q / 100.0;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    v[lo] + (h - lo as f64) * (v[hi] - v[lo])
}

fn close(a: Option<f64>, b: f64) -> bool {
    a.is_some_and(|a| (a - b).abs() <= 1e-9 * b.abs().max(1.0))
}

fn masks() -> impl Strategy<Value = ([usize; 3], [f64; 3], Vec<bool>, Vec<bool>)> {
    (
        1usize..8,
        1usize..8,
        1usize..8,
        0.3f64..3.0,
        0.3f64..3.0,
        0.3f64..3.0,
    )
        .prop_flat_map(|(x, y, z, a, b, c)| {
            let n = x * y * z;
            (
                Just([x, y, z]),
                Just([a, b, c]),
                proptest::collection::vec(proptest::bool::weighted(0.4), n),
                proptest::collection::vec(proptest::bool::weighted(0.4), n),
            )
        })
}

proptest! {
    #[test]
    fn metrics_match_brute_force((d, s, g, p) in masks(), tol in 0.0f64..3.0) {
        let geo = Geometry::new(d, s, LengthUnit::Millimetre).unwrap();
        let gm = Volume::from_vec(geo.clone(), g.clone()).unwrap();
        let pm = Volume::from_vec(geo.clone(), p.clone()).unwrap();
        let m = evaluate_masks(&gm, &pm, tol).unwrap();
        // The same through label volumes with two labels.
        let lab = |a: &[bool], b: &[bool]| -> LabelVolume {
            Volume::from_vec(geo.clone(), a.iter().zip(b).map(|(&x, &y)| if x { 3 } else if y { 1 } else { 0 }).collect()).unwrap()
        };
        let other: Vec<bool> = g.iter().map(|x| !x).collect();
        let gl = lab(&g, &other);
        let pl = lab(&p, &other);
        prop_assert_eq!(&evaluate_label(&gl, &pl, 3, tol).unwrap(), &m);
        let all = evaluate_all(&gl, &pl, tol).unwrap();
        match all.get(&3) {
            Some(x) => prop_assert_eq!(x, &m),
            None => prop_assert!(m.tp + m.fp + m.fn_ == 0),
        }
        // Together, and with one label only (the union is that label).
        let (all2, fg) = evaluate_all_and_foreground(&gl, &pl, tol).unwrap();
        prop_assert_eq!(&all2, &all);
        prop_assert_eq!(&fg, &evaluate_foreground(&gl, &pl, tol).unwrap());
        let only = |a: &[bool]| -> LabelVolume {
            Volume::from_vec(geo.clone(), a.iter().map(|&x| u16::from(x) * 3).collect()).unwrap()
        };
        let (go, po) = (only(&g), only(&p));
        let (one, fg1) = evaluate_all_and_foreground(&go, &po, tol).unwrap();
        prop_assert_eq!(&fg1, &evaluate_foreground(&go, &po, tol).unwrap());
        prop_assert!(one.len() <= 1);
        prop_assert_eq!(overlap_only(&gl, &pl, 3).unwrap(), m.confusion());

        let tp = g.iter().zip(&p).filter(|(a, b)| **a && **b).count() as u64;
        prop_assert_eq!(m.tp, tp);
        prop_assert_eq!(m.tp + m.fn_, g.iter().filter(|x| **x).count() as u64);
        prop_assert_eq!(m.tp + m.fp, p.iter().filter(|x| **x).count() as u64);
        prop_assert_eq!(m.total(), g.len() as u64);

        let bg = brute_border(&g, d);
        let bp = brute_border(&p, d);
        prop_assert_eq!(m.border_gt, bg.len() as u64);
        prop_assert_eq!(m.border_seg, bp.len() as u64);
        if bg.is_empty() || bp.is_empty() {
            prop_assert!(m.hd.is_none() && m.hd95.is_none() && m.hd95_pooled.is_none());
            prop_assert!(m.assd.is_none() && m.masd.is_none() && m.nsd.is_none());
        } else {
            let gs = brute_directed(&bg, &bp, s);
            let sg = brute_directed(&bp, &bg, s);
            let pooled: Vec<f64> = gs.iter().chain(&sg).copied().collect();
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            prop_assert!(close(m.hd, pooled.iter().copied().fold(0.0, f64::max)));
            prop_assert!(close(m.hd95, brute_pct(&gs, 95.0).max(brute_pct(&sg, 95.0))));
            prop_assert!(close(m.hd95_pooled, brute_pct(&pooled, 95.0)));
            prop_assert!(close(m.assd, mean(&pooled)));
            prop_assert!(close(m.masd, (mean(&gs) + mean(&sg)) / 2.0));
            prop_assert!(close(m.mean_gt_to_seg, mean(&gs)));
            prop_assert!(close(m.hd95_seg_to_gt, brute_pct(&sg, 95.0)));
            // Keep clear of ties at the tolerance, where rounding may decide.
            if pooled.iter().all(|x| (x - tol).abs() > 1e-9) {
                let within = pooled.iter().filter(|&&x| x <= tol).count() as f64;
                prop_assert!(close(m.nsd, within / pooled.len() as f64));
            }
        }
    }
}

impl Metrics {
    fn total(&self) -> u64 {
        self.tp + self.fp + self.fn_ + self.tn
    }
}

#[test]
fn geometry_mismatch_and_bad_tolerance_are_errors() {
    let a =
        Volume::<u16>::zeros(Geometry::new([4, 4, 4], [1.0; 3], LengthUnit::Millimetre).unwrap());
    let b =
        Volume::<u16>::zeros(Geometry::new([4, 4, 5], [1.0; 3], LengthUnit::Millimetre).unwrap());
    let c = Volume::<u16>::zeros(
        Geometry::new([4, 4, 4], [1.0, 1.0, 2.0], LengthUnit::Millimetre).unwrap(),
    );
    assert!(matches!(
        evaluate_label(&a, &b, 1, 1.0),
        Err(CoreError::GeometryMismatch(_))
    ));
    assert!(matches!(
        evaluate_all(&a, &c, 1.0),
        Err(CoreError::GeometryMismatch(_))
    ));
    assert!(overlap_only(&a, &c, 1).is_err());
    assert!(evaluate_label(&a, &a, 1, -1.0).is_err());
    assert!(evaluate_label(&a, &a, 1, f64::NAN).is_err());
}

#[test]
fn both_empty_gives_nulls_and_json_keys() {
    let g = Geometry::new([3, 3, 3], [0.35, 0.35, 0.5], LengthUnit::Micrometre).unwrap();
    let a = Volume::<u16>::zeros(g);
    let m = evaluate_label(&a, &a, 1, 1.0).unwrap();
    assert_eq!((m.tp, m.fp, m.fn_, m.tn), (0, 0, 0, 27));
    assert_eq!(m.dice, None);
    assert_eq!(m.specificity, Some(1.0));
    assert_eq!(m.hd, None);
    // Every key of the `evaluate --json` contract, in its order.
    let keys = "tp fp fn tn dice jaccard sensitivity specificity precision volume_similarity \
                volume_gt volume_seg hd hd95 hd95_pooled assd masd nsd tolerance unit \
                border_gt border_seg hd_gt_to_seg hd_seg_to_gt hd95_gt_to_seg hd95_seg_to_gt \
                mean_gt_to_seg mean_seg_to_gt";
    let text = serde_json::to_string(&m).unwrap();
    // A flat object whose values hold neither ',' nor ':'.
    let got: Vec<&str> = text[1..text.len() - 1]
        .split(',')
        .map(|kv| kv.split(':').next().unwrap_or_default().trim_matches('"'))
        .collect();
    assert_eq!(got, keys.split_whitespace().collect::<Vec<_>>());
    let j = serde_json::to_value(&m).unwrap();
    assert!(j["dice"].is_null());
    assert_eq!(j["unit"], "µm");
    assert!(evaluate_all(&a, &a, 1.0).unwrap().is_empty());
}

#[test]
fn single_voxel_offset_by_one_anisotropic_slice() {
    // One voxel shifted by one slice along z with sz = 3 mm: every distance is 3.
    let g = Geometry::new([3, 3, 4], [1.0, 1.0, 3.0], LengthUnit::Millimetre).unwrap();
    let mut a = Volume::<u16>::zeros(g.clone());
    let mut b = Volume::<u16>::zeros(g);
    a.set(1, 1, 1, 1);
    b.set(1, 1, 2, 1);
    let m = evaluate_label(&a, &b, 1, 1.0).unwrap();
    assert_eq!(m.hd, Some(3.0));
    assert_eq!(m.hd95, Some(3.0));
    assert_eq!(m.assd, Some(3.0));
    assert_eq!(m.nsd, Some(0.0));
    assert_eq!(m.volume_gt, 3.0);
    assert_eq!(m.dice, Some(0.0));
}

proptest! {
    #[test]
    fn foreground_is_the_union_of_all_labels(
        (d, s, g, p) in masks(),
        lg in proptest::collection::vec(0u16..4, 343),
        lp in proptest::collection::vec(0u16..4, 343),
    ) {
        let geo = Geometry::new(d, s, LengthUnit::Micrometre).unwrap();
        let n = g.len();
        // Labels 1..=3 where the mask is set, 0 elsewhere.
        let label = |m: &[bool], l: &[u16]| -> LabelVolume {
            Volume::from_vec(
                geo.clone(),
                m.iter().zip(l).map(|(&x, &v)| if x { v.max(1) } else { 0 }).collect(),
            )
            .unwrap()
        };
        let gl = label(&g, &lg[..n]);
        let pl = label(&p, &lp[..n]);
        let gm = Volume::from_vec(geo.clone(), g.clone()).unwrap();
        let pm = Volume::from_vec(geo.clone(), p.clone()).unwrap();
        prop_assert_eq!(
            evaluate_foreground(&gl, &pl, 1.0).unwrap(),
            evaluate_masks(&gm, &pm, 1.0).unwrap()
        );
    }
}
