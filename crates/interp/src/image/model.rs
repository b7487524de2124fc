//! How the traced boundary sits on the image: the intensity histograms just
//! inside and just outside the tracing on the drawn slices, as a
//! log-likelihood ratio per intensity (a naive-Bayes region term in the sense
//! of Boykov & Jolly 2001, learned from the tracer's own slices).
use crate::sdf::signed_distance;
use crate::slices::Plane;

/// Histogram bins of the likelihood ratio.
const BINS: usize = 48;
/// The log-likelihood ratio is clamped to ±`CLAMP` (one bin never decides alone).
const CLAMP: f32 = 3.0;
/// Samples are taken within this many pixels of the traced boundary.
const BAND_PX: f32 = 6.0;

/// Log-likelihood ratio of "inside" per intensity bin.
#[derive(Debug, Clone)]
pub struct IntensityModel {
    lo: f32,
    scale: f32,
    llr: Vec<f32>,
    /// How well intensity alone tells the two sides apart (see
    /// [`IntensityModel::separation`]).
    separation: f64,
}

impl IntensityModel {
    /// Learn from `(mask, image)` pairs of drawn slices. `None` when the
    /// slices hold too few pixels on either side, or a constant image.
    pub fn learn<'a>(
        slices: impl Iterator<Item = (&'a [bool], &'a [f32])>,
        plane: &Plane,
    ) -> Option<IntensityModel> {
        let px = plane.spacing[0].min(plane.spacing[1]) as f32;
        let mut inside = Vec::new();
        let mut outside = Vec::new();
        for (m, img) in slices {
            if !m.iter().any(|&x| x) || m.iter().all(|&x| x) {
                continue;
            }
            let d = signed_distance(m, plane);
            for ((&di, &v), &mi) in d.iter().zip(img).zip(m) {
                if di.abs() <= BAND_PX * px && v.is_finite() {
                    if mi { inside.push(v) } else { outside.push(v) }
                }
            }
        }
        if inside.len() < 20 || outside.len() < 20 {
            return None;
        }
        let mut all: Vec<(f32, bool)> = inside
            .iter()
            .map(|&v| (v, true))
            .chain(outside.iter().map(|&v| (v, false)))
            .collect();
        all.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let lo = all[all.len() / 100].0;
        let hi = all[all.len() - 1 - all.len() / 100].0;
        if hi <= lo {
            return None;
        }
        let scale = BINS as f32 / (hi - lo);
        let mut model = IntensityModel {
            lo,
            scale,
            llr: vec![0.0; BINS],
            separation: separation(&all, inside.len(), outside.len()),
        };
        let mut hin = vec![1.0f64; BINS];
        let mut hout = vec![1.0f64; BINS];
        for &v in &inside {
            hin[model.bin(v)] += 1.0;
        }
        for &v in &outside {
            hout[model.bin(v)] += 1.0;
        }
        let (nin, nout): (f64, f64) = (hin.iter().sum(), hout.iter().sum());
        for b in 0..BINS {
            let r = ((hin[b] / nin) / (hout[b] / nout)).ln() as f32;
            model.llr[b] = r.clamp(-CLAMP, CLAMP);
        }
        Some(model)
    }

    /// A model that knows nothing (every ratio 0): the shape alone.
    pub fn flat() -> IntensityModel {
        IntensityModel {
            lo: 0.0,
            scale: 1.0,
            llr: vec![0.0; BINS],
            separation: 0.5,
        }
    }

    /// The area under the ROC curve of intensity alone telling the pixels
    /// just inside the tracing from those just outside (on the drawn
    /// slices, within the sampling band), whichever side is brighter: 1
    /// where the traced boundary is a clean intensity edge, 0.5 where
    /// intensity says nothing about it.
    pub fn separation(&self) -> f64 {
        self.separation
    }

    fn bin(&self, v: f32) -> usize {
        (((v - self.lo) * self.scale).floor().max(0.0) as usize).min(BINS - 1)
    }

    /// Log-likelihood ratio of "inside" for intensity `v` (0 for NaN).
    pub fn llr(&self, v: f32) -> f32 {
        if v.is_finite() {
            self.llr[self.bin(v)]
        } else {
            0.0
        }
    }
}

/// The area under the ROC curve (Mann–Whitney, ties halved) of the
/// `(intensity, inside)` samples `sorted` by intensity, `n_in` inside and
/// `n_out` outside, as `max(auc, 1 − auc)`.
fn separation(sorted: &[(f32, bool)], n_in: usize, n_out: usize) -> f64 {
    let mut rank_sum = 0.0f64;
    let mut i = 0;
    while i < sorted.len() {
        let j = i + sorted[i..]
            .iter()
            .take_while(|x| x.0 == sorted[i].0)
            .count();
        let mid_rank = (i + j + 1) as f64 / 2.0;
        rank_sum += mid_rank * sorted[i..j].iter().filter(|x| x.1).count() as f64;
        i = j;
    }
    let (ni, no) = (n_in as f64, n_out as f64);
    let auc = (rank_sum - ni * (ni + 1.0) / 2.0) / (ni * no);
    auc.max(1.0 - auc)
}

/// A 3 × 3 binomial blur of a row-major slice (edges replicated): a little
/// denoising before the histograms and the edge weights.
pub fn blur(s: &[f32], w: usize, h: usize) -> Vec<f32> {
    let at = |u: i64, v: i64| {
        s[u.clamp(0, w as i64 - 1) as usize + w * v.clamp(0, h as i64 - 1) as usize]
    };
    let mut out = vec![0.0f32; w * h];
    for v in 0..h as i64 {
        for u in 0..w as i64 {
            let mut acc = 0.0;
            for (dv, kv) in [(-1i64, 1.0f32), (0, 2.0), (1, 1.0)] {
                for (du, ku) in [(-1i64, 1.0f32), (0, 2.0), (1, 1.0)] {
                    acc += kv * ku * at(u + du, v + dv);
                }
            }
            out[u as usize + w * v as usize] = acc / 16.0;
        }
    }
    out
}
