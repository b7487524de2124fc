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
/// Fewest sampled pixels on each side of the tracing a measure is taken on.
const MIN_SIDE: usize = 20;

/// Which pixels of a drawn slice (`mask`, `image`) are sampled: within
/// [`BAND_PX`] pixels of the traced boundary, of finite intensity. `None`
/// where the slice holds no boundary (nothing, or nothing but, inside).
fn sampled(mask: &[bool], image: &[f32], plane: &Plane) -> Option<Vec<bool>> {
    if !mask.iter().any(|&x| x) || mask.iter().all(|&x| x) {
        return None;
    }
    let band = BAND_PX * plane.spacing[0].min(plane.spacing[1]) as f32;
    let d = signed_distance(mask, plane);
    Some(
        d.iter()
            .zip(image)
            .map(|(di, v)| di.abs() <= band && v.is_finite())
            .collect(),
    )
}

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
        let mut inside = Vec::new();
        let mut outside = Vec::new();
        for (m, img) in slices {
            let Some(near) = sampled(m, img, plane) else {
                continue;
            };
            for i in (0..m.len()).filter(|&i| near[i]) {
                if m[i] {
                    inside.push(img[i])
                } else {
                    outside.push(img[i])
                }
            }
        }
        if inside.len() < MIN_SIDE || outside.len() < MIN_SIDE {
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

    /// Log-likelihood ratio of "inside" for intensity `v` (0 for NaN),
    /// linear between the bins' centres: a step at every bin edge moved
    /// the decision by whole bins where the boundary's intensities fall
    /// in a few of them (the MNI template's white matter: +0.003–0.005 on
    /// the skipped slices with the ramp, T1 k-means class 4 up to +0.046;
    /// breast1's two-slice fit −0.008).
    pub fn llr(&self, v: f32) -> f32 {
        if !v.is_finite() {
            return 0.0;
        }
        let x = ((v - self.lo) * self.scale - 0.5).clamp(0.0, (BINS - 1) as f32);
        let b = (x.floor() as usize).min(BINS - 2);
        let f = x - b as f32;
        self.llr[b] * (1.0 - f) + self.llr[b + 1] * f
    }
}

/// The traced boundary's contrast over the image's noise as a random walk
/// sees it: on the drawn `(mask, image)` slices as they are (unblurred), the
/// difference of the mean intensities just inside and just outside the
/// tracing (within the sampling band) over the median intensity step
/// between 4-neighbours on the same side of it. `None` when the slices
/// hold too few pixels on either side.
pub fn edge_contrast<'a>(
    slices: impl Iterator<Item = (&'a [bool], &'a [f32])>,
    plane: &Plane,
) -> Option<f64> {
    let w = plane.width;
    let (mut sum_in, mut n_in, mut sum_out, mut n_out) = (0.0f64, 0usize, 0.0f64, 0usize);
    let mut steps: Vec<f32> = Vec::new();
    for (m, img) in slices {
        let Some(near) = sampled(m, img, plane) else {
            continue;
        };
        for i in (0..m.len()).filter(|&i| near[i]) {
            if m[i] {
                sum_in += f64::from(img[i]);
                n_in += 1;
            } else {
                sum_out += f64::from(img[i]);
                n_out += 1;
            }
            let right = (i % w + 1 < w).then_some(i + 1);
            let below = (i + w < m.len()).then_some(i + w);
            for j in [right, below].into_iter().flatten() {
                if near[j] && m[j] == m[i] {
                    steps.push((img[j] - img[i]).abs());
                }
            }
        }
    }
    if n_in < MIN_SIDE || n_out < MIN_SIDE || steps.is_empty() {
        return None;
    }
    let mid = steps.len() / 2;
    let noise = f64::from(*steps.select_nth_unstable_by(mid, f32::total_cmp).1);
    let contrast = (sum_in / n_in as f64 - sum_out / n_out as f64).abs();
    Some(contrast / noise.max(f64::MIN_POSITIVE))
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

#[cfg(test)]
mod tests {
    use super::*;

    const W: usize = 40;

    fn plane() -> Plane {
        Plane {
            width: W,
            height: W,
            spacing: [1.0, 1.0],
            slice_spacing: 1.0,
        }
    }

    /// A disc of radius 10 in the middle of a 40 × 40 slice.
    fn disc() -> Vec<bool> {
        (0..W * W)
            .map(|i| {
                let (u, v) = ((i % W) as f32 - 19.5, (i / W) as f32 - 19.5);
                u * u + v * v <= 100.0
            })
            .collect()
    }

    /// Noise uniform in [-1, 1], independent from pixel to pixel.
    fn noise(i: usize) -> f32 {
        let mut z = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f32 / (1u64 << 52) as f32 - 1.0
    }

    /// 100 inside the disc, 20 outside, plus `f(i)`.
    fn image(m: &[bool], f: impl Fn(usize) -> f32) -> Vec<f32> {
        m.iter()
            .enumerate()
            .map(|(i, &x)| if x { 100.0 } else { 20.0 } + f(i))
            .collect()
    }

    fn measured(m: &[bool], img: &[f32]) -> (f64, f64) {
        let blurred = blur(img, W, W);
        let model = IntensityModel::learn(std::iter::once((m, blurred.as_slice())), &plane());
        let contrast = edge_contrast(std::iter::once((m, img)), &plane());
        (model.unwrap().separation(), contrast.unwrap())
    }

    #[test]
    fn a_clean_edge_has_a_high_contrast() {
        let m = disc();
        let (separation, contrast) = measured(&m, &image(&m, |i| 5.0 * noise(i)));
        assert!(separation > 0.999, "{separation}");
        assert!(contrast > 10.0, "{contrast}");
    }

    #[test]
    fn noise_from_pixel_to_pixel_lowers_the_contrast_but_not_the_blurred_separation() {
        let m = disc();
        let (separation, contrast) = measured(&m, &image(&m, |i| 100.0 * noise(i)));
        assert!(separation > 0.95, "{separation}");
        assert!(contrast < 2.0, "{contrast}");
    }

    #[test]
    fn a_smooth_shading_keeps_the_contrast_where_the_separation_falls() {
        // Intensity rising by 4 per pixel along both axes: within the
        // sampling band each side spans about 250, far more than the edge's
        // 80, yet neighbours differ by 4.
        let m = disc();
        let shade = |i: usize| 4.0 * (i % W + i / W) as f32;
        let (separation, contrast) = measured(&m, &image(&m, shade));
        assert!(separation < 0.9, "{separation}");
        assert!(contrast > 10.0, "{contrast}");
    }

    #[test]
    fn too_few_pixels_on_a_side_give_no_contrast() {
        let full = vec![true; W * W];
        let img = vec![1.0; W * W];
        assert!(
            edge_contrast(std::iter::once((full.as_slice(), img.as_slice())), &plane()).is_none()
        );
    }
}
