//! Automated segmentation by intensity thresholds: the pipeline behind
//! `interslice segment` and the server's segmentation endpoint.
//!
//! 1. optional Gaussian smoothing (σ in physical units; integer volumes are
//!    rounded back to their type so that thresholds stay grey levels);
//! 2. a histogram: native bins (one per integer value) for u8/u16/i16,
//!    256 uniform bins for f32 (`threshold::histogram`);
//! 3. thresholds by Otsu, Rosin, exact k-means or exact multi-class Otsu;
//! 4. labels: a voxel `v` gets `#{t : v > t}` (0 = background; two classes
//!    give a 0/1 mask, `K` classes labels `1..K-1`);
//! 5. optionally only the largest connected component of the foreground
//!    (6- or 26-connected), and holes filled (per label, nested: the filled mask of `label >= l`
//!    is painted `l` where it is lower, so inner structures stay inside).
use crate::morph::{self, Connectivity};
use crate::threshold::{self, Binning, Histogram, RosinEnd, ThresholdError};
use crate::{AnyVolume, Cancel, CoreError, LabelVolume, Volume, Voxel};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Largest number of classes `segment` accepts (k-means, multi-Otsu).
pub const MAX_CLASSES: usize = 5;

/// A thresholding method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SegmentMethod {
    /// Otsu (1979), two classes.
    #[default]
    Otsu,
    /// Rosin's unimodal threshold (2001), two classes; for a dominant
    /// background peak with the object in the bright tail.
    Rosin,
    /// Exact k-means on intensities (`classes` = k, 2..=5).
    #[serde(rename = "kmeans")]
    KMeans,
    /// Exact multi-class Otsu (`classes` 2..=5).
    MultiOtsu,
}

impl SegmentMethod {
    /// Every method, in the order `--help` lists them.
    pub const ALL: [SegmentMethod; 4] = [
        SegmentMethod::Otsu,
        SegmentMethod::Rosin,
        SegmentMethod::KMeans,
        SegmentMethod::MultiOtsu,
    ];

    /// The CLI / API name.
    pub fn name(self) -> &'static str {
        match self {
            SegmentMethod::Otsu => "otsu",
            SegmentMethod::Rosin => "rosin",
            SegmentMethod::KMeans => "kmeans",
            SegmentMethod::MultiOtsu => "multi-otsu",
        }
    }

    /// Parse a CLI / API name.
    pub fn parse(s: &str) -> Result<SegmentMethod, CoreError> {
        let s = s.trim().to_ascii_lowercase();
        SegmentMethod::ALL
            .into_iter()
            .find(|m| m.name() == s || (s == "k-means" && *m == SegmentMethod::KMeans))
            .ok_or_else(|| {
                CoreError::Invalid(format!(
                    "unknown segmentation method '{s}' (expected otsu, rosin, kmeans or multi-otsu)"
                ))
            })
    }
}

impl fmt::Display for SegmentMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SegmentMethod {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        SegmentMethod::parse(s)
    }
}

/// Parameters of [`segment`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SegmentParams {
    /// The thresholding method.
    pub method: SegmentMethod,
    /// Number of classes including background (2 for Otsu and Rosin).
    pub classes: usize,
    /// Gaussian σ in the volume's physical unit; 0 = no smoothing.
    pub smooth_sigma: f64,
    /// Keep only the largest connected component of the foreground.
    pub largest_component: bool,
    /// How foreground voxels connect for `largest_component`: face (6) or
    /// full (26) neighbours. Holes are always filled with face-connected
    /// background, so a hole is what a 6-connected flood from outside misses.
    pub connectivity: Connectivity,
    /// Fill holes (background not connected to the border) in 3D.
    pub fill_holes: bool,
}

impl Default for SegmentParams {
    fn default() -> Self {
        SegmentParams {
            method: SegmentMethod::Otsu,
            classes: 2,
            smooth_sigma: 0.0,
            largest_component: false,
            connectivity: Connectivity::Face,
            fill_holes: false,
        }
    }
}

impl SegmentParams {
    /// Check the parameters against each other; one-line errors.
    pub fn validate(&self) -> Result<(), CoreError> {
        match self.method {
            SegmentMethod::Otsu | SegmentMethod::Rosin if self.classes != 2 => {
                Err(CoreError::Invalid(format!(
                    "{} separates 2 classes; use kmeans or multi-otsu for {} classes",
                    self.method, self.classes
                )))
            }
            SegmentMethod::KMeans | SegmentMethod::MultiOtsu
                if !(2..=MAX_CLASSES).contains(&self.classes) =>
            {
                Err(CoreError::Invalid(format!(
                    "{} needs 2 to {MAX_CLASSES} classes, not {}",
                    self.method, self.classes
                )))
            }
            _ if !(self.smooth_sigma.is_finite() && self.smooth_sigma >= 0.0) => {
                Err(CoreError::Invalid(format!(
                    "smoothing sigma must be a finite number >= 0, not {}",
                    self.smooth_sigma
                )))
            }
            _ => Ok(()),
        }
    }
}

/// The result of [`segment_detailed`]: the labels and how they were made.
#[derive(Debug, Clone, PartialEq)]
pub struct Segmentation {
    /// 0 = background, 1..K-1 the classes above each threshold.
    pub labels: LabelVolume,
    /// The thresholds, ascending, in intensity units (of the smoothed volume
    /// when smoothing was asked for); foreground of threshold `t` is `v > t`.
    pub thresholds: Vec<f64>,
    /// The histogram binning the thresholds were computed on.
    pub binning: Binning,
    /// Voxels of each label 1..K-1 after post-processing (`voxels[l - 1]`).
    pub voxels: Vec<u64>,
}

impl Segmentation {
    /// Physical volume of each label 1..K-1 (voxels × sx·sy·sz), in the
    /// volume's unit cubed.
    pub fn volumes(&self) -> Vec<f64> {
        let vv = self.labels.geometry().voxel_volume();
        self.voxels.iter().map(|&n| n as f64 * vv).collect()
    }

    /// What was done and found, as `interslice segment --json` (and the
    /// Python `threshold`) report it; `p` are the parameters it was made with.
    pub fn summary(&self, p: &SegmentParams) -> SegmentSummary {
        let unit = self.labels.geometry().unit.ascii();
        SegmentSummary {
            method: p.method.name(),
            classes: p.classes,
            thresholds: self.thresholds.clone(),
            foreground: "v > threshold",
            binning: match self.binning {
                Binning::Native => "native".to_string(),
                Binning::Uniform(n) => format!("uniform{n}"),
            },
            smooth: p.smooth_sigma,
            largest_component: p.largest_component,
            connectivity: p.connectivity.neighbours(),
            fill_holes: p.fill_holes,
            unit: format!("{unit}^3"),
            labels: self
                .voxels
                .iter()
                .zip(self.volumes())
                .enumerate()
                .map(|(i, (&voxels, volume))| ClassSummary {
                    label: i + 1,
                    voxels,
                    volume,
                })
                .collect(),
        }
    }
}

/// The report of a [`Segmentation`] (see [`Segmentation::summary`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentSummary {
    /// The method's name.
    pub method: &'static str,
    /// Classes including background.
    pub classes: usize,
    /// The thresholds, ascending.
    pub thresholds: Vec<f64>,
    /// How a threshold splits: always `v > threshold`.
    pub foreground: &'static str,
    /// The histogram binning: `native` or `uniformN`.
    pub binning: String,
    /// Gaussian σ applied first (physical units), 0 for none.
    pub smooth: f64,
    /// Whether only the largest connected component was kept.
    pub largest_component: bool,
    /// Neighbours of a voxel for that component: 6 or 26.
    pub connectivity: u8,
    /// Whether holes were filled.
    pub fill_holes: bool,
    /// The unit of the volumes, e.g. `um^3`.
    pub unit: String,
    /// Each label's voxels and physical volume.
    pub labels: Vec<ClassSummary>,
}

/// One label of a [`SegmentSummary`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassSummary {
    /// The label, 1..K-1.
    pub label: usize,
    /// Its voxels.
    pub voxels: u64,
    /// Its physical volume (voxels × sx·sy·sz).
    pub volume: f64,
}

fn err(e: ThresholdError) -> CoreError {
    CoreError::Invalid(e.to_string())
}

/// Segment `v` with `p` into a label volume (see the module docs); stops
/// with [`CoreError::Cancelled`] once `cancel` is set.
pub fn segment(
    v: &AnyVolume,
    p: &SegmentParams,
    cancel: &Cancel,
) -> Result<LabelVolume, CoreError> {
    Ok(segment_detailed(v, p, cancel)?.labels)
}

/// The thresholds `p` gives on `v` (after smoothing when asked), without labelling.
pub fn thresholds(
    v: &AnyVolume,
    p: &SegmentParams,
    cancel: &Cancel,
) -> Result<(Vec<f64>, Binning), CoreError> {
    p.validate()?;
    let smoothed;
    let v = if p.smooth_sigma > 0.0 {
        smoothed = smooth_same_type(v, p.smooth_sigma, cancel)?;
        &smoothed
    } else {
        v
    };
    thresholds_of(v, p)
}

fn thresholds_of(v: &AnyVolume, p: &SegmentParams) -> Result<(Vec<f64>, Binning), CoreError> {
    let binning = match v {
        AnyVolume::F32(_) => Binning::Uniform(256),
        _ => Binning::Native,
    };
    let h = Histogram::of_volume(v, binning).map_err(err)?;
    let found = h.nonempty_bins();
    if found < p.classes {
        return Err(err(ThresholdError::TooFewValues {
            classes: p.classes,
            found,
        }));
    }
    let t = match p.method {
        SegmentMethod::Otsu => vec![threshold::otsu(&h).map_err(err)?],
        SegmentMethod::Rosin => vec![
            threshold::rosin(&h, RosinEnd::FirstEmptyAfterLast)
                .map_err(err)?
                .threshold,
        ],
        SegmentMethod::MultiOtsu => threshold::multi_otsu(&h, p.classes).map_err(err)?,
        SegmentMethod::KMeans => {
            let (values, counts) = threshold::distinct_values(v).map_err(err)?;
            threshold::kmeans_exact(&values, &counts, p.classes)
                .map_err(err)?
                .thresholds
        }
    };
    Ok((t, binning))
}

/// Smooth and round back to the volume's own type (f32 stays f32).
fn smooth_same_type(v: &AnyVolume, sigma: f64, cancel: &Cancel) -> Result<AnyVolume, CoreError> {
    fn back<T: Voxel>(
        s: Volume<f32>,
        lo: f32,
        hi: f32,
        cast: impl Fn(f32) -> T + Sync,
    ) -> Volume<T> {
        s.map(|x| cast(x.round().clamp(lo, hi)))
    }
    Ok(match v {
        AnyVolume::U8(x) => AnyVolume::U8(back(
            morph::gaussian_smooth(x, sigma, cancel)?,
            0.0,
            255.0,
            |f| f as u8,
        )),
        AnyVolume::U16(x) => AnyVolume::U16(back(
            morph::gaussian_smooth(x, sigma, cancel)?,
            0.0,
            65535.0,
            |f| f as u16,
        )),
        AnyVolume::I16(x) => AnyVolume::I16(back(
            morph::gaussian_smooth(x, sigma, cancel)?,
            -32768.0,
            32767.0,
            |f| f as i16,
        )),
        AnyVolume::F32(x) => AnyVolume::F32(morph::gaussian_smooth(x, sigma, cancel)?),
    })
}

/// Segment `v` with `p`, returning the labels with the thresholds used.
pub fn segment_detailed(
    v: &AnyVolume,
    p: &SegmentParams,
    cancel: &Cancel,
) -> Result<Segmentation, CoreError> {
    p.validate()?;
    if let AnyVolume::F32(f) = v
        && f.data().par_iter().any(|x| !x.is_finite())
    {
        return Err(err(ThresholdError::NonFinite));
    }
    let smoothed;
    let v = if p.smooth_sigma > 0.0 {
        smoothed = smooth_same_type(v, p.smooth_sigma, cancel)?;
        &smoothed
    } else {
        v
    };
    cancel.check()?;
    let (thresholds, binning) = thresholds_of(v, p)?;
    let classify = |x: f64| thresholds.iter().filter(|&&t| x > t).count() as u16;
    let mut labels: LabelVolume = match v {
        AnyVolume::U8(x) => x.map(|a| classify(a as f64)),
        AnyVolume::U16(x) => x.map(|a| classify(a as f64)),
        AnyVolume::I16(x) => x.map(|a| classify(a as f64)),
        AnyVolume::F32(x) => x.map(|a| classify(a as f64)),
    };
    if p.largest_component {
        cancel.check()?;
        let keep = morph::largest_component(&labels.map(|l| l > 0), p.connectivity);
        labels
            .data_mut()
            .par_iter_mut()
            .zip(keep.data().par_iter())
            .for_each(|(l, &k)| {
                if !k {
                    *l = 0;
                }
            });
    }
    if p.fill_holes {
        for l in 1..p.classes as u16 {
            cancel.check()?;
            let filled = morph::fill_holes(&labels.map(|x| x >= l), Connectivity::Face);
            labels
                .data_mut()
                .par_iter_mut()
                .zip(filled.data().par_iter())
                .for_each(|(x, &f)| {
                    if f && *x < l {
                        *x = l;
                    }
                });
        }
    }
    let counts = labels.label_counts();
    let voxels = (1..p.classes as u16)
        .map(|l| counts.iter().find(|c| c.0 == l).map_or(0, |c| c.1))
        .collect();
    Ok(Segmentation {
        labels,
        thresholds,
        binning,
        voxels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Geometry, LengthUnit};

    /// A bright hollow ball (shell 200, cavity 40) on a background of 20..=29.
    fn ball() -> AnyVolume {
        let n = 24;
        let g = Geometry::new([n, n, n], [0.5, 0.5, 1.0], LengthUnit::Micrometre).unwrap();
        let mut v = Volume::<u8>::zeros(g);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let d = [i, j, k]
                        .iter()
                        .map(|&c| (c as f64 - 11.5).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    let x = if d < 4.0 {
                        40
                    } else if d < 8.0 {
                        200
                    } else {
                        20 + ((i * 7 + j * 3 + k) % 10) as u8
                    };
                    v.set(i, j, k, x);
                }
            }
        }
        // A stray bright voxel in a corner.
        v.set(0, 0, 0, 220);
        AnyVolume::U8(v)
    }

    #[test]
    fn otsu_then_clean_up() {
        let v = ball();
        let plain = segment_detailed(&v, &SegmentParams::default(), &Cancel::new()).unwrap();
        assert_eq!(plain.thresholds.len(), 1);
        let t = plain.thresholds[0];
        assert!((40.0..200.0).contains(&t), "{t}");
        let shell = plain.voxels[0];
        let clean = segment_detailed(
            &v,
            &SegmentParams {
                largest_component: true,
                fill_holes: true,
                ..Default::default()
            },
            &Cancel::new(),
        )
        .unwrap();
        // The stray voxel is gone and the cavity is filled.
        assert_eq!(clean.labels.get(0, 0, 0), 0);
        assert_eq!(clean.labels.get(12, 12, 12), 1);
        let cavity = match &v {
            AnyVolume::U8(x) => x.data().iter().filter(|&&a| a == 40).count() as u64,
            _ => unreachable!(),
        };
        assert_eq!(clean.voxels[0], shell - 1 + cavity);
        assert!((clean.volumes()[0] - clean.voxels[0] as f64 * 0.25).abs() < 1e-9);
    }

    #[test]
    fn three_classes_and_bad_parameters() {
        let v = ball();
        let p = SegmentParams {
            method: SegmentMethod::MultiOtsu,
            classes: 3,
            ..Default::default()
        };
        let s = segment_detailed(&v, &p, &Cancel::new()).unwrap();
        assert_eq!(s.thresholds.len(), 2);
        assert_eq!(s.labels.get(12, 12, 12), 1); // cavity (40) above the background
        assert_eq!(s.labels.get(12, 12, 5), 2); // shell
        let k = segment(
            &v,
            &SegmentParams {
                method: SegmentMethod::KMeans,
                classes: 3,
                ..Default::default()
            },
            &Cancel::new(),
        )
        .unwrap();
        assert_eq!(k.get(12, 12, 5), 2);
        // Refused: three classes of the default method, seven k-means classes,
        // a negative smoothing.
        let refused = [
            SegmentParams {
                classes: 3,
                ..Default::default()
            },
            SegmentParams {
                method: SegmentMethod::KMeans,
                classes: 7,
                ..Default::default()
            },
            SegmentParams {
                smooth_sigma: -1.0,
                ..Default::default()
            },
        ];
        for p in &refused {
            assert!(segment(&v, p, &Cancel::new()).is_err(), "{p:?}");
        }
        assert!(SegmentMethod::parse("watershed").is_err());
        assert_eq!(
            SegmentMethod::parse("multi-otsu").unwrap(),
            SegmentMethod::MultiOtsu
        );
        let g = Geometry::new([4, 4, 4], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let flat = AnyVolume::U8(Volume::filled(g, 9));
        let e = segment(&flat, &SegmentParams::default(), &Cancel::new())
            .unwrap_err()
            .to_string();
        assert!(e.contains("only 1 distinct value"), "{e}");
    }

    #[test]
    fn smoothing_keeps_the_type_and_removes_the_speck() {
        let v = ball();
        let s = segment_detailed(
            &v,
            &SegmentParams {
                smooth_sigma: 0.6,
                ..Default::default()
            },
            &Cancel::new(),
        )
        .unwrap();
        assert_eq!(s.binning, Binning::Native);
        // One bright voxel in a dark corner is smoothed below the threshold.
        assert_eq!(s.labels.get(0, 0, 0), 0);
        assert_eq!(s.labels.get(12, 12, 5), 1);
    }

    #[test]
    fn a_cancelled_segmentation_stops_with_cancelled() {
        let cancel = Cancel::new();
        cancel.cancel();
        let p = SegmentParams {
            smooth_sigma: 2.0,
            ..Default::default()
        };
        assert_eq!(
            segment_detailed(&ball(), &p, &cancel).unwrap_err(),
            CoreError::Cancelled
        );
    }
}
