//! The digital phantom: synthetic optical-cell-CT volumes with their exact labels.
//!
//! A phantom is one stained cell imaged at 0.35 µm isotropic voxels: an
//! irregular cell body, a lobed and indented nucleus inside it and 1 to 3
//! nucleoli inside the nucleus, with hematoxylin-like intensities (denser
//! stain absorbs more and reconstructs brighter: background darkest, then
//! cytoplasm, nucleus with chromatin texture, nucleoli brightest), a little
//! Gaussian blur (the optics) and Gaussian noise. The label volume is exact:
//! a voxel carries the label of the innermost structure containing its
//! centre, so the ground truth is known without tracing. It is the demo data
//! and the test data of interpolation and evaluation.
//!
//! Generation is seeded (ChaCha8) and bit-reproducible: the same parameters
//! give identical bytes on any thread count, because every voxel is computed
//! independently and the noise of slab `k` comes from its own ChaCha stream.
//! See `docs/phantom.md` for the model, the label table and the intensity model.
use crate::contour_file::default_labels;
use crate::{AnyVolume, CoreError, Geometry, LabelVolume, LengthUnit, Volume};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub mod shape;

use shape::{Dent, Harmonic, StarShape, sphere_directions};

/// Voxel size of the phantom in µm (optical cell CT at 350 nm).
pub const SPACING_UM: f64 = 0.35;
/// Standard deviation of the Gaussian blur, in voxels.
pub const BLUR_SIGMA: f64 = 0.7;
/// Smallest volume side accepted (nucleoli need a few voxels).
pub const MIN_SIZE: usize = 32;
/// Largest volume side accepted (memory: about 9 bytes per voxel while generating).
pub const MAX_SIZE: usize = 512;

/// Mean relative intensity (0..1 of full scale) of the background.
pub const LEVEL_BACKGROUND: f64 = 0.05;
/// Mean relative intensity of the cytoplasm.
pub const LEVEL_CYTOPLASM: f64 = 0.22;
/// Mean relative intensity of the nucleus (before its brighter rim).
pub const LEVEL_NUCLEUS: f64 = 0.50;
/// Mean relative intensity of the nucleoli.
pub const LEVEL_NUCLEOLUS: f64 = 0.80;

/// What to generate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhantomParams {
    /// Voxels per side (the volume is `size³`), `MIN_SIZE..=MAX_SIZE`.
    pub size: usize,
    /// Random seed; the same seed gives the same bytes.
    pub seed: u64,
    /// Bits per intensity voxel: 8 or 16.
    pub bits: u8,
    /// Standard deviation of the Gaussian noise, as a fraction of full scale
    /// (0.02 = 2 %), in `0..=0.5`.
    pub noise: f64,
}

impl Default for PhantomParams {
    fn default() -> Self {
        PhantomParams {
            size: 128,
            seed: 1,
            bits: 8,
            noise: 0.02,
        }
    }
}

impl PhantomParams {
    /// Err with a one-line message for a size, bit depth or noise out of range.
    pub fn validate(&self) -> Result<(), CoreError> {
        if !(MIN_SIZE..=MAX_SIZE).contains(&self.size) {
            return Err(CoreError::Invalid(format!(
                "phantom size must be {MIN_SIZE}..={MAX_SIZE} voxels, got {}",
                self.size
            )));
        }
        if self.bits != 8 && self.bits != 16 {
            return Err(CoreError::Invalid(format!(
                "phantom bits must be 8 or 16, got {}",
                self.bits
            )));
        }
        if !(self.noise.is_finite() && (0.0..=0.5).contains(&self.noise)) {
            return Err(CoreError::Invalid(format!(
                "phantom noise must be in 0..=0.5 (fraction of full scale), got {}",
                self.noise
            )));
        }
        Ok(())
    }
}

/// The seed of cell `index` (1-based) of a series drawn with `seed`: a
/// SplitMix64 mix of both, so series of neighbouring seeds share no cell
/// (with `seed + index` the second cell of seed 1 would be the first of seed 2).
pub fn cell_seed(seed: u64, index: u64) -> u64 {
    let mut z = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(index)
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// One structure of a phantom with its size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StructureInfo {
    /// Display name ("Cell", "Nucleus", "Nucleolus 1", ...).
    pub name: String,
    /// Its label value.
    pub label: u16,
    /// Voxels of the full structure: the cell includes the nucleus and the
    /// nucleoli, the nucleus includes the nucleoli.
    pub voxels: u64,
    /// Voxels carrying this label in the painted label volume.
    pub label_voxels: u64,
    /// Physical volume of the full structure in µm³ (`voxels × 0.35³`).
    pub volume: f64,
}

/// A generated phantom.
#[derive(Debug, Clone, PartialEq)]
pub struct Phantom {
    /// The intensity volume (u8 or u16), 0.35 µm isotropic, unit µm.
    pub intensity: AnyVolume,
    /// The exact label volume on the same grid (0 background, 1 cell,
    /// 2 nucleus, 3.. nucleoli), a painted partition.
    pub labels: LabelVolume,
    /// Cell, nucleus and each nucleolus, in label order.
    pub structures: Vec<StructureInfo>,
}

/// A random plane-wave texture: the sum of `K` cosines normalised to unit
/// variance and clipped to ±1.5 (a cheap, seedable, band-limited 3D texture).
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    waves: Vec<([f64; 3], f64)>,
    norm: f64,
}

impl Texture {
    fn new(rng: &mut ChaCha8Rng, count: usize, wavelength: (f64, f64)) -> Texture {
        let waves = (0..count)
            .map(|_| {
                let d = unit_vector(rng);
                let k = std::f64::consts::TAU / rng.gen_range(wavelength.0..wavelength.1);
                (
                    [d[0] * k, d[1] * k, d[2] * k],
                    rng.gen_range(0.0..std::f64::consts::TAU),
                )
            })
            .collect();
        Texture {
            waves,
            norm: (2.0 / count as f64).sqrt(),
        }
    }

    /// Texture value at `p`, mean about 0, in -1.5..=1.5.
    #[inline]
    pub fn at(&self, p: [f64; 3]) -> f64 {
        let s: f64 = self
            .waves
            .iter()
            .map(|(k, ph)| (k[0] * p[0] + k[1] * p[1] + k[2] * p[2] + ph).cos())
            .sum();
        (s * self.norm).clamp(-1.5, 1.5)
    }
}

/// The geometric and texture model of one phantom, before rendering.
/// Coordinates are continuous voxel units: voxel (i, j, k) has its centre at
/// (i + 0.5, j + 0.5, k + 0.5).
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// The cell surface.
    pub cell: StarShape,
    /// The nucleus surface (inside the cell).
    pub nucleus: StarShape,
    /// The nucleoli (inside the nucleus, disjoint).
    pub nucleoli: Vec<StarShape>,
    /// Low-frequency cytoplasm texture.
    pub cytoplasm_texture: Texture,
    /// Chromatin texture (about 1–2 µm grain).
    pub chromatin_texture: Texture,
}

fn unit_vector(rng: &mut ChaCha8Rng) -> [f64; 3] {
    let z: f64 = rng.gen_range(-1.0..1.0);
    let phi: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
    let r = (1.0 - z * z).sqrt();
    [r * phi.cos(), r * phi.sin(), z]
}

/// A magnitude in `lo..hi` with a random sign.
fn signed(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let m = rng.gen_range(lo..hi);
    if rng.gen_bool(0.5) { m } else { -m }
}

fn harmonic(rng: &mut ChaCha8Rng, degree: u8, lo: f64, hi: f64) -> Harmonic {
    Harmonic {
        axis: unit_vector(rng),
        degree,
        amplitude: signed(rng, lo, hi),
    }
}

fn add(p: [f64; 3], d: [f64; 3], s: f64) -> [f64; 3] {
    [p[0] + s * d[0], p[1] + s * d[1], p[2] + s * d[2]]
}

/// True when `inner` grown by `margin` voxels is inside `outer` (checked along
/// `dirs`; rendering also nests the tests, so labels nest whatever happens between them).
fn fits(inner: &StarShape, outer: &StarShape, margin: f64, dirs: &[[f64; 3]]) -> bool {
    dirs.iter().all(|&d| {
        let r = inner.radius_at(d) + margin;
        outer.contains(add(inner.centre, d, r))
    })
}

/// Smallest nucleolus radius in voxels (0.7 µm). Large enough that the blur
/// leaves its core at the nucleolus level, and that it always holds voxel
/// centres (a ball of radius >= 0.87 does), so no nucleolus label is empty.
const MIN_NUCLEOLUS_RADIUS: f64 = 2.0;

/// Draw 1..=3 nucleoli inside the nucleus, disjoint and at least one voxel
/// apart. The count is drawn first; the first nucleolus is always placed
/// (falling back to a small one at the nucleus centre, which is always inside),
/// a further one that finds no room after many attempts is left out, so small
/// volumes get fewer nucleoli instead of an error.
fn place_nucleoli(rng: &mut ChaCha8Rng, nucleus: &StarShape) -> Vec<StarShape> {
    let count = rng.gen_range(1..=3);
    let dirs = sphere_directions(120);
    let mut nucleoli: Vec<StarShape> = Vec::with_capacity(count);
    for _ in 0..count {
        let mut placed = None;
        for attempt in 0..600 {
            let shrink = 0.99f64.powi((attempt - 100).max(0));
            let radius =
                (nucleus.radius * rng.gen_range(0.13..0.21) * shrink).max(MIN_NUCLEOLUS_RADIUS);
            let offset = unit_vector(rng);
            let dist = rng.gen_range(0.0..0.6) * nucleus.radius;
            let candidate = StarShape {
                centre: add(nucleus.centre, offset, dist),
                radius,
                harmonics: vec![harmonic(rng, 2, 0.05, 0.15)],
                dents: vec![],
            };
            let apart = nucleoli.iter().all(|o| {
                let d: f64 = (0..3)
                    .map(|a| (o.centre[a] - candidate.centre[a]).powi(2))
                    .sum();
                d.sqrt() > o.max_radius() + candidate.max_radius() + 1.0
            });
            if apart && fits(&candidate, nucleus, 0.75, &dirs) {
                placed = Some(candidate);
                break;
            }
        }
        match placed {
            Some(p) => nucleoli.push(p),
            None if nucleoli.is_empty() => {
                // The centre of a star shape is inside it; shrink until it fits.
                let mut radius = (0.15 * nucleus.radius).max(MIN_NUCLEOLUS_RADIUS);
                let mut c = StarShape {
                    centre: nucleus.centre,
                    radius,
                    harmonics: vec![],
                    dents: vec![],
                };
                while radius > MIN_NUCLEOLUS_RADIUS && !fits(&c, nucleus, 0.75, &dirs) {
                    radius = (radius * 0.9).max(MIN_NUCLEOLUS_RADIUS);
                    c.radius = radius;
                }
                nucleoli.push(c);
            }
            None => break,
        }
    }
    nucleoli
}

/// Draw the model of a phantom (no rendering). Deterministic for the parameters.
pub fn model(params: &PhantomParams) -> Result<Model, CoreError> {
    params.validate()?;
    let n = params.size as f64;
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let dirs = sphere_directions(400);

    // Cell: mean radius a third of the side; harmonics of degree 2 (elongation,
    // flattening) to 4 (bumps) and one shallow dent. Max radius <= 0.449 n.
    let jitter = 0.015 * n;
    let cell = StarShape {
        centre: std::array::from_fn(|_| n / 2.0 + rng.gen_range(-jitter..jitter)),
        radius: 0.34 * n * rng.gen_range(0.95..1.0),
        harmonics: vec![
            harmonic(&mut rng, 2, 0.04, 0.09),
            harmonic(&mut rng, 2, 0.04, 0.09),
            harmonic(&mut rng, 3, 0.015, 0.04),
            harmonic(&mut rng, 3, 0.015, 0.04),
            harmonic(&mut rng, 4, 0.01, 0.03),
            harmonic(&mut rng, 4, 0.01, 0.03),
        ],
        dents: vec![Dent {
            axis: unit_vector(&mut rng),
            depth: rng.gen_range(0.04..0.1),
            width: rng.gen_range(0.2..0.4),
        }],
    };

    // Nucleus: about half the cell's radius, lobed (harmonics of degree 3-4)
    // and indented. A dent makes the surface concave only when it is deep for
    // its width: a Gaussian dip of width w flattens a sphere by about 2w at its
    // rim, so depth 0.37 with width 0.2 merely flattens it (the rim lies on the
    // plane through the bottom of the dip); depth >= 0.45 with width <= 0.15
    // gives a true indentation. Redrawn (and shrunk after a while) until it
    // fits in the cell with a margin.
    let margin = 1.5 + 0.03 * cell.radius;
    let mut nucleus = None;
    for attempt in 0..400 {
        let shrink = 0.97f64.powi((attempt - 20).max(0));
        let offset = unit_vector(&mut rng);
        let dist = rng.gen_range(0.0..0.1) * cell.radius;
        let radius = 0.55 * cell.radius * rng.gen_range(0.92..1.05) * shrink;
        let harmonics = vec![
            harmonic(&mut rng, 2, 0.04, 0.1),
            harmonic(&mut rng, 3, 0.05, 0.1),
            harmonic(&mut rng, 4, 0.05, 0.1),
        ];
        // One broad, deep indentation (a kidney-shaped nucleus), sometimes a
        // second, narrower one.
        let mut dents = vec![Dent {
            axis: unit_vector(&mut rng),
            depth: rng.gen_range(0.45..0.6),
            width: rng.gen_range(0.08..0.15),
        }];
        if rng.gen_bool(0.5) {
            dents.push(Dent {
                axis: unit_vector(&mut rng),
                depth: rng.gen_range(0.2..0.35),
                width: rng.gen_range(0.04..0.08),
            });
        }
        let candidate = StarShape {
            centre: add(cell.centre, offset, dist),
            radius,
            harmonics,
            dents,
        };
        if fits(&candidate, &cell, margin, &dirs) {
            nucleus = Some(candidate);
            break;
        }
    }
    let nucleus =
        nucleus.ok_or_else(|| CoreError::Invalid("phantom: could not fit the nucleus".into()))?;

    let nucleoli = place_nucleoli(&mut rng, &nucleus);

    let cytoplasm_texture = Texture::new(&mut rng, 8, (8.0, 20.0));
    let chromatin_texture = Texture::new(&mut rng, 12, (2.5, 6.0));
    Ok(Model {
        cell,
        nucleus,
        nucleoli,
        cytoplasm_texture,
        chromatin_texture,
    })
}

impl Model {
    /// Label and noise-free, unblurred relative intensity (0..1) at `p`.
    #[inline]
    pub fn sample(&self, p: [f64; 3]) -> (u16, f32) {
        if !self.cell.contains(p) {
            return (0, LEVEL_BACKGROUND as f32);
        }
        let inner = if self.nucleus.contains(p) {
            self.nucleoli.iter().position(|o| o.contains(p))
        } else {
            let c = LEVEL_CYTOPLASM * (1.0 + 0.15 * self.cytoplasm_texture.at(p));
            return (1, c as f32);
        };
        let chromatin = self.chromatin_texture.at(p);
        match inner {
            Some(t) => (
                3 + t as u16,
                (LEVEL_NUCLEOLUS * (1.0 + 0.05 * chromatin)) as f32,
            ),
            None => {
                // Heterochromatin lines the nuclear envelope: a brighter rim.
                let rim = 0.06 * (-self.nucleus.depth(p).max(0.0) / 1.5).exp();
                (2, (LEVEL_NUCLEUS * (1.0 + 0.16 * chromatin) + rim) as f32)
            }
        }
    }
}

/// Normalised Gaussian kernel of standard deviation `sigma` (radius ceil(3σ)).
fn gaussian_kernel(sigma: f64) -> Vec<f32> {
    let r = (3.0 * sigma).ceil() as i64;
    let w: Vec<f64> = (-r..=r)
        .map(|x| (-(x * x) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let s: f64 = w.iter().sum();
    w.into_iter().map(|x| (x / s) as f32).collect()
}

/// Generate a phantom: the model, rendered in parallel over z slabs, blurred,
/// with noise, quantised to 8 or 16 bits. Identical bytes for identical params.
pub fn generate(params: &PhantomParams) -> Result<Phantom, CoreError> {
    let model = model(params)?;
    let n = params.size;
    let geometry = Geometry::new([n; 3], [SPACING_UM; 3], LengthUnit::Micrometre)?;
    let slab = n * n;
    let mut labels = vec![0u16; n * n * n];
    let mut field = vec![0f32; n * n * n];

    // 1. Labels and clean intensities at voxel centres.
    labels
        .par_chunks_mut(slab)
        .zip(field.par_chunks_mut(slab))
        .enumerate()
        .for_each(|(k, (ls, fs))| {
            let z = k as f64 + 0.5;
            for j in 0..n {
                let y = j as f64 + 0.5;
                for i in 0..n {
                    let (l, f) = model.sample([i as f64 + 0.5, y, z]);
                    ls[i + n * j] = l;
                    fs[i + n * j] = f;
                }
            }
        });

    // 2. Separable Gaussian blur along x and y in place (edges replicated).
    let kernel = gaussian_kernel(BLUR_SIGMA);
    let r = (kernel.len() / 2) as i64;
    let clamp = |x: i64| x.clamp(0, n as i64 - 1) as usize;
    field.par_chunks_mut(n).for_each(|row| {
        let src = row.to_vec();
        for (i, out) in row.iter_mut().enumerate() {
            *out = kernel
                .iter()
                .enumerate()
                .map(|(t, w)| w * src[clamp(i as i64 + t as i64 - r)])
                .sum();
        }
    });
    field.par_chunks_mut(slab).for_each(|s| {
        let src = s.to_vec();
        for j in 0..n {
            let out = &mut s[n * j..n * (j + 1)];
            out.fill(0.0);
            for (t, w) in kernel.iter().enumerate() {
                let jj = clamp(j as i64 + t as i64 - r);
                for (o, v) in out.iter_mut().zip(&src[n * jj..n * (jj + 1)]) {
                    *o += w * v;
                }
            }
        }
    });

    // 3. Blur along z, add noise (one ChaCha stream per slab), quantise.
    let full = if params.bits == 8 { 255.0 } else { 65535.0 };
    let field = &field;
    let kernel = &kernel;
    let render_slab = |k: usize, out: &mut [f64]| {
        out.fill(0.0);
        for (t, w) in kernel.iter().enumerate() {
            let kk = clamp(k as i64 + t as i64 - r);
            for (o, v) in out.iter_mut().zip(&field[slab * kk..slab * (kk + 1)]) {
                *o += f64::from(w * v);
            }
        }
        if params.noise > 0.0 {
            let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
            rng.set_stream(1 + k as u64);
            for o in out.iter_mut() {
                let e: f64 = rng.sample(StandardNormal);
                *o += params.noise * e;
            }
        }
        for o in out.iter_mut() {
            *o = (*o * full).round().clamp(0.0, full);
        }
    };
    let intensity = if params.bits == 8 {
        let mut data = vec![0u8; n * n * n];
        data.par_chunks_mut(slab).enumerate().for_each(|(k, s)| {
            let mut buf = vec![0.0; slab];
            render_slab(k, &mut buf);
            for (d, v) in s.iter_mut().zip(&buf) {
                *d = *v as u8;
            }
        });
        AnyVolume::U8(Volume::from_vec(geometry.clone(), data)?)
    } else {
        let mut data = vec![0u16; n * n * n];
        data.par_chunks_mut(slab).enumerate().for_each(|(k, s)| {
            let mut buf = vec![0.0; slab];
            render_slab(k, &mut buf);
            for (d, v) in s.iter_mut().zip(&buf) {
                *d = *v as u16;
            }
        });
        AnyVolume::U16(Volume::from_vec(geometry.clone(), data)?)
    };

    let labels = Volume::from_vec(geometry, labels)?;
    let structures = structures(&labels, model.nucleoli.len());
    Ok(Phantom {
        intensity,
        labels,
        structures,
    })
}

/// Cell, nucleus and nucleoli with full-structure and painted voxel counts.
fn structures(labels: &LabelVolume, nucleoli: usize) -> Vec<StructureInfo> {
    let counts = labels.label_counts();
    let count = |l: u16| counts.iter().find(|c| c.0 == l).map_or(0, |c| c.1);
    let at_least = |l: u16| counts.iter().filter(|c| c.0 >= l).map(|c| c.1).sum::<u64>();
    let voxel = labels.geometry().voxel_volume();
    let names = default_labels();
    (1..=2 + nucleoli as u16)
        .map(|l| {
            let voxels = if l <= 2 { at_least(l) } else { count(l) };
            StructureInfo {
                name: names
                    .iter()
                    .find(|x| x.id == l)
                    .map_or_else(|| format!("Nucleolus {}", l - 2), |x| x.name.clone()),
                label: l,
                voxels,
                label_voxels: count(l),
                volume: voxels as f64 * voxel,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests;
