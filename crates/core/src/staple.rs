//! STAPLE: Simultaneous Truth And Performance Level Estimation (Warfield,
//! Zou & Wells, IEEE TMI 23(7), 2004), binary, one label at a time.
//!
//! Each rater `j` is modelled by a sensitivity `p_j = P(D_j = 1 | T = 1)` and
//! a specificity `q_j = P(D_j = 0 | T = 0)`; the hidden truth `T` has a prior
//! probability `g` of being foreground. EM alternates:
//!
//! * M-step: `p_j = Σ W·D_j / Σ W`, `q_j = Σ (1−W)(1−D_j) / Σ (1−W)`;
//! * E-step: `W = g·α / (g·α + (1−g)·β)` with `α = Π p_j^{D_j}(1−p_j)^{1−D_j}`
//!   and `β = Π (1−q_j)^{D_j} q_j^{1−D_j}`.
//!
//! As in ITK's `STAPLEImageFilter` (and so SimpleITK), `W` starts as the
//! fraction of raters marking a voxel, the prior `g` is the mean of that
//! fraction over the whole volume and stays fixed, every voxel of the volume
//! takes part (so specificities count the whole background), and iteration
//! stops when no `p_j` or `q_j` moved by more than 1e-7 (squared change
//! ≤ 1e-14). The consensus is `W > 0.5`.
//!
//! `W` depends only on which raters mark a voxel, so the EM runs on the
//! counts of the `2^R` rating patterns: one parallel pass over the voxels
//! builds the counts, every iteration costs `O(2^R · R)`, and one more
//! parallel pass paints the consensus. The result equals the voxel-wise
//! iteration (sums are only regrouped). Written here because no Rust crate
//! implements STAPLE.
use crate::{Cancel, CoreError, LabelVolume, Mask, Volume};
use rayon::prelude::*;

/// Most raters STAPLE accepts (patterns are counted in a `2^R` table).
pub const MAX_RATERS: usize = 20;

/// Settings of the EM iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StapleParams {
    /// Stop after this many iterations even without convergence.
    pub max_iterations: usize,
    /// Convergence: every `(Δp)²` and `(Δq)²` at most this (ITK: 1e-14).
    pub tolerance: f64,
}

impl Default for StapleParams {
    fn default() -> Self {
        StapleParams {
            max_iterations: 10_000,
            tolerance: 1e-14,
        }
    }
}

/// The estimate of one binary STAPLE run.
#[derive(Debug, Clone, PartialEq)]
pub struct Staple {
    /// Estimated sensitivity of each rater (NaN when the truth estimate has
    /// no foreground at all).
    pub sensitivity: Vec<f64>,
    /// Estimated specificity of each rater (NaN when the whole volume is foreground).
    pub specificity: Vec<f64>,
    /// The prior `g`: mean fraction of raters marking a voxel.
    pub prior: f64,
    /// EM iterations run.
    pub iterations: usize,
    /// True when the change fell below the tolerance.
    pub converged: bool,
    /// Posterior `W` of each rating pattern (bit `j` set = rater `j` marks
    /// the voxel), `2^R` entries.
    pub posterior: Vec<f64>,
    /// The consensus mask `W > 0.5`.
    pub consensus: Mask,
}

impl Staple {
    /// The posterior probability of every voxel as a volume (the output of
    /// ITK's filter).
    pub fn probability(&self, raters: &[&Mask]) -> Volume<f32> {
        let pat = patterns(raters);
        let post: Vec<f32> = self.posterior.iter().map(|&w| w as f32).collect();
        pat.map(|p| post[p as usize])
    }
}

/// The rating pattern of every voxel (bit j = rater j marks it).
fn patterns(raters: &[&Mask]) -> Volume<u32> {
    let g = raters[0].geometry().clone();
    let n = g.len();
    let mut out = vec![0u32; n];
    out.par_chunks_mut(1 << 16)
        .enumerate()
        .for_each(|(c, chunk)| {
            let start = c << 16;
            for (j, r) in raters.iter().enumerate() {
                let d = &r.data()[start..start + chunk.len()];
                for (o, &b) in chunk.iter_mut().zip(d) {
                    *o |= (b as u32) << j;
                }
            }
        });
    Volume::from_vec(g, out).expect("same geometry")
}

fn check(raters: &[&Mask]) -> Result<(), CoreError> {
    if raters.len() < 2 {
        return Err(CoreError::Invalid(format!(
            "STAPLE needs at least 2 raters, got {}",
            raters.len()
        )));
    }
    if raters.len() > MAX_RATERS {
        return Err(CoreError::Invalid(format!(
            "STAPLE takes at most {MAX_RATERS} raters, got {}",
            raters.len()
        )));
    }
    for r in &raters[1..] {
        raters[0].geometry().ensure_same_grid(r.geometry())?;
    }
    Ok(())
}

/// Binary STAPLE of `raters` (2..=20 masks on one grid); `cancel` is checked
/// before every EM iteration.
pub fn staple(
    raters: &[&Mask],
    params: StapleParams,
    cancel: &Cancel,
) -> Result<Staple, CoreError> {
    check(raters)?;
    let r = raters.len();
    let np = 1usize << r;
    let pat = patterns(raters);
    // Counts of every pattern, in parallel.
    let counts: Vec<f64> = pat
        .data()
        .par_chunks(1 << 16)
        .fold(
            || vec![0u64; np],
            |mut acc, c| {
                for &p in c {
                    acc[p as usize] += 1;
                }
                acc
            },
        )
        .reduce(
            || vec![0u64; np],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            },
        )
        .into_iter()
        .map(|c| c as f64)
        .collect();
    let n: f64 = counts.iter().sum();
    let marks = |p: usize, j: usize| (p >> j) & 1 == 1;
    // W starts as the vote fraction; the prior is its mean.
    let mut w: Vec<f64> = (0..np).map(|p| p.count_ones() as f64 / r as f64).collect();
    let prior = counts.iter().zip(&w).map(|(c, x)| c * x).sum::<f64>() / n;
    let mut sens = vec![f64::NAN; r];
    let mut spec = vec![f64::NAN; r];
    let mut last: Option<(Vec<f64>, Vec<f64>)> = None;
    let mut iterations = 0;
    let mut converged = false;
    for it in 0..params.max_iterations {
        cancel.check()?;
        iterations = it + 1;
        // M-step.
        let sw: f64 = counts.iter().zip(&w).map(|(c, x)| c * x).sum();
        let sb: f64 = counts.iter().zip(&w).map(|(c, x)| c * (1.0 - x)).sum();
        for j in 0..r {
            let (mut pn, mut qn) = (0.0, 0.0);
            for p in 0..np {
                if marks(p, j) {
                    pn += counts[p] * w[p];
                } else {
                    qn += counts[p] * (1.0 - w[p]);
                }
            }
            sens[j] = pn / sw;
            spec[j] = qn / sb;
        }
        // E-step.
        for (p, wp) in w.iter_mut().enumerate() {
            let (mut a, mut b) = (1.0f64, 1.0f64);
            for j in 0..r {
                if marks(p, j) {
                    a *= sens[j];
                    b *= 1.0 - spec[j];
                } else {
                    a *= 1.0 - sens[j];
                    b *= spec[j];
                }
            }
            let num = prior * a;
            let den = num + (1.0 - prior) * b;
            *wp = if den > 0.0 { num / den } else { 0.0 };
        }
        if let Some((lp, lq)) = &last {
            let small = |a: &[f64], b: &[f64]| {
                a.iter()
                    .zip(b)
                    .all(|(x, y)| (x - y) * (x - y) <= params.tolerance)
            };
            if small(&sens, lp) && small(&spec, lq) {
                converged = true;
                break;
            }
        }
        last = Some((sens.clone(), spec.clone()));
        if !(prior > 0.0 && prior < 1.0) {
            // Every rater agrees on the whole volume: nothing to estimate.
            converged = true;
            break;
        }
    }
    let fg: Vec<bool> = w.iter().map(|&x| x > 0.5).collect();
    let consensus = pat.map(|p| fg[p as usize]);
    Ok(Staple {
        sensitivity: sens,
        specificity: spec,
        prior,
        iterations,
        converged,
        posterior: w,
        consensus,
    })
}

/// Voxels marked by more than half of the raters (ties are background).
pub fn majority_vote(raters: &[&Mask]) -> Result<Mask, CoreError> {
    check(raters)?;
    let pat = patterns(raters);
    let half = raters.len() as u32;
    Ok(pat.map(|p| 2 * p.count_ones() > half))
}

/// STAPLE of label volumes, one binary run per label present in any rater;
/// the consensus labels are painted in ascending order, so a higher (inner)
/// label overwrites a lower one where both consensus masks hold.
pub fn staple_labels(
    raters: &[&LabelVolume],
    params: StapleParams,
    cancel: &Cancel,
) -> Result<(LabelVolume, Vec<(u16, Staple)>), CoreError> {
    if raters.is_empty() {
        return Err(CoreError::Invalid(
            "STAPLE needs at least 2 raters, got 0".into(),
        ));
    }
    let mut labels: Vec<u16> = raters
        .iter()
        .flat_map(|r| r.label_counts().into_iter().map(|c| c.0))
        .collect();
    labels.sort_unstable();
    labels.dedup();
    let mut out = LabelVolume::zeros(raters[0].geometry().clone());
    let mut per = Vec::with_capacity(labels.len());
    for l in labels {
        let masks: Vec<Mask> = raters.iter().map(|r| r.mask_of(l)).collect();
        let refs: Vec<&Mask> = masks.iter().collect();
        let s = staple(&refs, params, cancel)?;
        out.data_mut()
            .par_iter_mut()
            .zip(s.consensus.data().par_iter())
            .for_each(|(o, &c)| {
                if c {
                    *o = l;
                }
            });
        per.push((l, s));
    }
    Ok((out, per))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Geometry, LengthUnit};
    use rand::{Rng, SeedableRng};

    fn ellipsoid(n: usize, r: [f64; 3]) -> Mask {
        let g = Geometry::new([n, n, n], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let c = (n as f64 - 1.0) / 2.0;
        let mut m = Mask::zeros(g);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let d = ((i as f64 - c) / r[0]).powi(2)
                        + ((j as f64 - c) / r[1]).powi(2)
                        + ((k as f64 - c) / r[2]).powi(2);
                    m.set(i, j, k, d <= 1.0);
                }
            }
        }
        m
    }

    fn flip(truth: &Mask, p: f64, q: f64, seed: u64) -> Mask {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let data = truth
            .data()
            .iter()
            .map(|&t| if t { rng.gen_bool(p) } else { !rng.gen_bool(q) })
            .collect();
        Mask::from_vec(truth.geometry().clone(), data).unwrap()
    }

    fn dice(a: &Mask, b: &Mask) -> f64 {
        let (mut tp, mut na, mut nb) = (0.0, 0.0, 0.0);
        for (&x, &y) in a.data().iter().zip(b.data()) {
            tp += (x && y) as u8 as f64;
            na += x as u8 as f64;
            nb += y as u8 as f64;
        }
        2.0 * tp / (na + nb)
    }

    #[test]
    fn recovers_known_sensitivity_and_specificity() {
        let truth = ellipsoid(48, [18.0, 14.0, 10.0]);
        let pq = [(0.95, 0.99), (0.80, 0.97), (0.90, 0.90), (0.70, 0.995)];
        let raters: Vec<Mask> = pq
            .iter()
            .enumerate()
            .map(|(s, &(p, q))| flip(&truth, p, q, 11 + s as u64))
            .collect();
        let refs: Vec<&Mask> = raters.iter().collect();
        let s = staple(&refs, StapleParams::default(), &Cancel::new()).unwrap();
        assert!(s.converged);
        for (j, &(p, q)) in pq.iter().enumerate() {
            assert!(
                (s.sensitivity[j] - p).abs() < 0.02,
                "rater {j}: p {} vs {p}",
                s.sensitivity[j]
            );
            assert!(
                (s.specificity[j] - q).abs() < 0.02,
                "rater {j}: q {} vs {q}",
                s.specificity[j]
            );
        }
        assert!(dice(&s.consensus, &truth) > 0.95);
    }

    #[test]
    fn weighs_raters_by_their_quality_and_beats_majority_vote() {
        let truth = ellipsoid(40, [12.0, 9.0, 7.0]);
        let raters = [
            flip(&truth, 0.97, 0.998, 1),
            flip(&truth, 0.75, 0.97, 2),
            flip(&truth, 0.70, 0.98, 3),
        ];
        let refs: Vec<&Mask> = raters.iter().collect();
        let s = staple(&refs, StapleParams::default(), &Cancel::new()).unwrap();
        let mv = majority_vote(&refs).unwrap();
        let (ds, dm) = (dice(&s.consensus, &truth), dice(&mv, &truth));
        assert!(ds > dm + 0.01, "STAPLE {ds} vs majority {dm}");
        // The posterior of a voxel marked only by the good rater is above one half.
        assert!(s.posterior[0b001] > 0.5);
    }

    /// Recovery over several seeds, numbers of raters and qualities: every
    /// estimated sensitivity and specificity within 0.02 of the truth.
    #[test]
    fn recovery_holds_over_seeds() {
        let truth = ellipsoid(40, [15.0, 12.0, 9.0]);
        let mut worst = 0.0f64;
        for seed in 0..8u64 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(100 + seed);
            let r = 3 + (seed as usize % 4);
            let pq: Vec<(f64, f64)> = (0..r)
                .map(|_| (rng.gen_range(0.75..0.99), rng.gen_range(0.95..0.999)))
                .collect();
            let raters: Vec<Mask> = pq
                .iter()
                .enumerate()
                .map(|(j, &(p, q))| flip(&truth, p, q, seed * 31 + j as u64))
                .collect();
            let refs: Vec<&Mask> = raters.iter().collect();
            let s = staple(&refs, StapleParams::default(), &Cancel::new()).unwrap();
            assert!(s.converged, "seed {seed}");
            for (j, &(p, q)) in pq.iter().enumerate() {
                let (ep, eq) = ((s.sensitivity[j] - p).abs(), (s.specificity[j] - q).abs());
                worst = worst.max(ep).max(eq);
                assert!(
                    ep < 0.02,
                    "seed {seed} rater {j}: p {} vs {p}",
                    s.sensitivity[j]
                );
                assert!(
                    eq < 0.02,
                    "seed {seed} rater {j}: q {} vs {q}",
                    s.specificity[j]
                );
            }
        }
        eprintln!("largest sensitivity/specificity error over the seeds: {worst:.4}");
    }

    /// Three noisy copies of the phantom's nucleus (label 2 and the nucleoli
    /// inside it), each with its own error rates: STAPLE weighs the careful
    /// copy more and beats the majority vote.
    #[test]
    fn phantom_nucleus_consensus_beats_majority_vote() {
        let ph = crate::phantom::generate(&crate::phantom::PhantomParams {
            size: 64,
            seed: 3,
            bits: 8,
            noise: 0.02,
        })
        .unwrap();
        let nucleus = ph.labels.map(|l| l >= 2);
        let copies = [
            flip(&nucleus, 0.98, 0.999, 21),
            flip(&nucleus, 0.80, 0.995, 22),
            flip(&nucleus, 0.75, 0.99, 23),
        ];
        let refs: Vec<&Mask> = copies.iter().collect();
        let s = staple(&refs, StapleParams::default(), &Cancel::new()).unwrap();
        let mv = majority_vote(&refs).unwrap();
        let (ds, dm) = (dice(&s.consensus, &nucleus), dice(&mv, &nucleus));
        eprintln!("phantom nucleus: STAPLE Dice {ds:.4}, majority vote Dice {dm:.4}");
        assert!(ds > dm, "STAPLE {ds} vs majority {dm}");
        assert!(ds > 0.97, "{ds}");
    }

    #[test]
    fn identical_raters_and_labels() {
        let truth = ellipsoid(16, [5.0, 4.0, 3.0]);
        let s = staple(
            &[&truth, &truth, &truth],
            StapleParams::default(),
            &Cancel::new(),
        )
        .unwrap();
        assert_eq!(s.consensus, truth);
        assert!(s.sensitivity.iter().all(|&p| (p - 1.0).abs() < 1e-9));
        let lab = truth.map(|b| if b { 2u16 } else { 0 });
        let (c, per) =
            staple_labels(&[&lab, &lab], StapleParams::default(), &Cancel::new()).unwrap();
        assert_eq!(c, lab);
        assert_eq!(per.len(), 1);
        assert!(staple(&[&truth], StapleParams::default(), &Cancel::new()).is_err());
    }
}
