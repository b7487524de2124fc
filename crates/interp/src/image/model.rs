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
        let mut all: Vec<f32> = inside.iter().chain(&outside).copied().collect();
        all.sort_unstable_by(f32::total_cmp);
        let lo = all[all.len() / 100];
        let hi = all[all.len() - 1 - all.len() / 100];
        if hi <= lo {
            return None;
        }
        let scale = BINS as f32 / (hi - lo);
        let mut model = IntensityModel {
            lo,
            scale,
            llr: vec![0.0; BINS],
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
        }
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
