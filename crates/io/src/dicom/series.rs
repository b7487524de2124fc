//! Arranging the image planes of one series into a volume: every plane must
//! have one size, pixel format, orientation and pixel spacing; planes are
//! sorted by their position along the slice normal (never by file name or
//! InstanceNumber) and the z spacing is measured from the positions (never
//! taken from SpacingBetweenSlices, which scanners fill in differently).
//! Missing slices, repeated positions, uneven spacing and sheared stacks
//! (gantry tilt) are errors that name the files involved.
use super::header::{FileHeader, PixelFormat};
use crate::IoError;
use interslice_core::geometry::IDENTITY_DIRECTION;
use interslice_core::{Geometry, LengthUnit};
use std::path::Path;

/// Relative tolerance on a step between slices (of the median step).
const STEP_TOLERANCE: f64 = 0.05;
/// Absolute tolerance on a step between slices, in mm (positions are
/// often written with one or two decimals).
const STEP_TOLERANCE_MM: f64 = 0.01;
/// Largest sideways offset of a slice from the line through the first slice
/// along the normal, as a fraction of the smaller pixel spacing.
const SHEAR_TOLERANCE: f64 = 0.5;
/// Largest difference between two slices' direction cosines.
const ORIENTATION_TOLERANCE: f64 = 1e-4;

/// One plane of the volume: which frame of which file, and its rescale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Plane {
    /// Index of the file in the series' headers.
    pub file: usize,
    /// Frame within the file.
    pub frame: usize,
    /// RescaleSlope.
    pub slope: f64,
    /// RescaleIntercept.
    pub intercept: f64,
}

/// A series arranged into a volume: its geometry and its planes in z order.
#[derive(Debug, Clone)]
pub(crate) struct Arranged {
    /// Dims, spacing (mm), origin and direction (LPS, as ITK reports them).
    pub geometry: Geometry,
    /// The planes in z order (`geometry.dims[2]` of them).
    pub planes: Vec<Plane>,
    /// Stored value layout, the same for every plane.
    pub pixel: PixelFormat,
}

fn name(h: &FileHeader) -> String {
    h.path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| h.path.display().to_string())
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A number for an error message (at most 4 decimals, no float noise).
fn mm(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

fn point(p: [f64; 3]) -> String {
    format!("({}, {}, {})", mm(p[0]), mm(p[1]), mm(p[2]))
}

/// The row, column and normal unit vectors of an ImageOrientationPatient,
/// normalised as ITK does; errs unless the two vectors are orthogonal.
pub(crate) fn axes(iop: [f64; 6]) -> Result<[[f64; 3]; 3], String> {
    let r = [iop[0], iop[1], iop[2]];
    let c = [iop[3], iop[4], iop[5]];
    let (nr, nc) = (norm(r), norm(c));
    if (nr - 1.0).abs() > 0.01 || (nc - 1.0).abs() > 0.01 || (dot(r, c) / (nr * nc)).abs() > 1e-3 {
        return Err(format!(
            "ImageOrientationPatient {iop:?} is not two orthogonal unit vectors"
        ));
    }
    let r = r.map(|x| x / nr);
    let c = c.map(|x| x / nc);
    let n = cross(r, c);
    let nn = norm(n);
    Ok([r, c, n.map(|x| x / nn)])
}

/// Arrange the image files of one series (already grouped by
/// SeriesInstanceUID) into a volume. `dir` names the folder in errors.
pub(crate) fn arrange(dir: &Path, files: &[FileHeader]) -> Result<Arranged, IoError> {
    let Some(first) = files.first() else {
        return Err(IoError::invalid(dir, "no DICOM images"));
    };
    for h in files {
        if (h.cols, h.rows) != (first.cols, first.rows) {
            return Err(IoError::invalid(
                dir,
                format!(
                    "mixed image sizes in one series: {} is {} x {} but {} is {} x {}",
                    name(h),
                    h.cols,
                    h.rows,
                    name(first),
                    first.cols,
                    first.rows
                ),
            ));
        }
        if h.pixel != first.pixel {
            return Err(IoError::invalid(
                dir,
                format!(
                    "mixed pixel formats in one series: {} is {} but {} is {}",
                    name(h),
                    h.pixel,
                    name(first),
                    first.pixel
                ),
            ));
        }
    }
    // Every frame of every file, with the file it comes from.
    let frames: Vec<(usize, usize)> = files
        .iter()
        .enumerate()
        .flat_map(|(i, h)| (0..h.frames.len()).map(move |k| (i, k)))
        .collect();
    let frame = |&(i, k): &(usize, usize)| &files[i].frames[k];
    let label = |&(i, k): &(usize, usize)| {
        if files[i].frames.len() > 1 {
            format!("{} frame {}", name(&files[i]), k + 1)
        } else {
            name(&files[i])
        }
    };
    // Pixel spacing and orientation: one for the whole series.
    let f0 = &frames[0];
    let spacing = frame(f0).spacing.unwrap_or([1.0, 1.0]);
    let orientation = frame(f0).orientation;
    for f in &frames {
        let s = frame(f).spacing.unwrap_or([1.0, 1.0]);
        if (0..2).any(|a| (s[a] - spacing[a]).abs() > 1e-6 * spacing[a].max(1.0)) {
            return Err(IoError::invalid(
                dir,
                format!(
                    "mixed pixel spacings in one series: {} has {} x {} mm but {} has {} x {} mm",
                    label(f),
                    mm(s[0]),
                    mm(s[1]),
                    label(f0),
                    mm(spacing[0]),
                    mm(spacing[1])
                ),
            ));
        }
        let o = frame(f).orientation;
        let same = match (o, orientation) {
            (Some(a), Some(b)) => (0..6).all(|i| (a[i] - b[i]).abs() <= ORIENTATION_TOLERANCE),
            (None, None) => true,
            _ => false,
        };
        if !same {
            let show = |o: Option<[f64; 6]>| match o {
                Some(o) => format!("[{}]", o.map(mm).join(", ")),
                None => "none".into(),
            };
            return Err(IoError::invalid(
                dir,
                format!(
                    "mixed orientations in one series: {} has ImageOrientationPatient {} but {} has {}",
                    label(f),
                    show(o),
                    label(f0),
                    show(orientation)
                ),
            ));
        }
    }
    let pixel = first.pixel;
    let plane = |&(i, k): &(usize, usize)| Plane {
        file: i,
        frame: k,
        slope: files[i].frames[k].slope,
        intercept: files[i].frames[k].intercept,
    };
    let [nx, ny] = [first.cols, first.rows];
    let axes = match orientation {
        Some(o) => axes(o).map_err(|e| IoError::invalid(&first.path, e))?,
        None => IDENTITY_DIRECTION,
    };
    let direction = [0, 1, 2].map(|r| [axes[0][r], axes[1][r], axes[2][r]]);
    if frames.len() == 1 {
        // No second position to measure from: the z spacing ITK (GDCM)
        // reports for a single slice.
        let z = first
            .spacing_between_slices
            .filter(|&t| t > 0.0)
            .or(first.slice_thickness.filter(|&t| t > 0.0))
            .unwrap_or(1.0);
        let geometry = Geometry {
            dims: [nx, ny, 1],
            spacing: [spacing[0], spacing[1], z],
            unit: LengthUnit::Millimetre,
            origin: frame(f0).position.unwrap_or([0.0; 3]),
            direction,
        };
        geometry
            .validate()
            .map_err(|e| IoError::invalid(dir, e.to_string()))?;
        return Ok(Arranged {
            geometry,
            planes: vec![plane(f0)],
            pixel,
        });
    }
    if orientation.is_none() {
        return Err(IoError::invalid(
            dir,
            format!(
                "{} has no ImageOrientationPatient: its slices cannot be placed in 3D",
                label(f0)
            ),
        ));
    }
    let normal = axes[2];
    let mut placed = Vec::with_capacity(frames.len());
    for f in &frames {
        let Some(p) = frame(f).position else {
            return Err(IoError::invalid(
                dir,
                format!(
                    "{} has no ImagePositionPatient: its slices cannot be placed in 3D",
                    label(f)
                ),
            ));
        };
        placed.push((dot(p, normal), p, *f));
    }
    placed.sort_by(|a, b| a.0.total_cmp(&b.0));
    check_spacing(dir, &placed, &label, spacing)?;
    let (p0, pn) = (placed[0].1, placed[placed.len() - 1].1);
    // ITK's ImageSeriesReader: the distance from the first to the last
    // slice over the number of steps.
    let z = norm(sub(pn, p0)) / (placed.len() - 1) as f64;
    let geometry = Geometry {
        dims: [nx, ny, placed.len()],
        spacing: [spacing[0], spacing[1], z],
        unit: LengthUnit::Millimetre,
        origin: p0,
        direction,
    };
    geometry
        .validate()
        .map_err(|e| IoError::invalid(dir, e.to_string()))?;
    Ok(Arranged {
        geometry,
        planes: placed.iter().map(|(_, _, f)| plane(f)).collect(),
        pixel,
    })
}

type Placed = (f64, [f64; 3], (usize, usize));

/// Err unless the sorted slices are evenly spaced along the normal and
/// stacked straight along it: names a repeated position, the slices around
/// a gap (and where the first missing slice would be), an uneven step, or a
/// slice off the normal.
fn check_spacing(
    dir: &Path,
    placed: &[Placed],
    label: &dyn Fn(&(usize, usize)) -> String,
    pixel_spacing: [f64; 2],
) -> Result<(), IoError> {
    let steps: Vec<f64> = placed.windows(2).map(|w| w[1].0 - w[0].0).collect();
    let mut sorted = steps.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let tol = STEP_TOLERANCE * median + STEP_TOLERANCE_MM;
    for (w, &step) in placed.windows(2).zip(&steps) {
        let (a, b) = (&w[0], &w[1]);
        if step <= STEP_TOLERANCE_MM || step < 0.5 * median {
            return Err(IoError::invalid(
                dir,
                format!(
                    "{} and {} are at the same position ({} mm apart along the slice normal): several volumes in one series (echoes, phases, time points) are not supported",
                    label(&a.2),
                    label(&b.2),
                    mm(step)
                ),
            ));
        }
        if (step - median).abs() <= tol {
            continue;
        }
        let m = (step / median).round();
        if m >= 2.0 && (step - m * median).abs() <= tol * m {
            let unit = sub(b.1, a.1).map(|x| x / norm(sub(b.1, a.1)));
            let first_missing = [0, 1, 2].map(|i| a.1[i] + unit[i] * median);
            return Err(IoError::invalid(
                dir,
                format!(
                    "slice missing between {} and {}: they are {} mm apart where the other slices are {} mm apart ({} missing, the first at {})",
                    label(&a.2),
                    label(&b.2),
                    mm(step),
                    mm(median),
                    m as usize - 1,
                    point(first_missing)
                ),
            ));
        }
        return Err(IoError::invalid(
            dir,
            format!(
                "uneven slice spacing: {} and {} are {} mm apart where the other slices are {} mm apart",
                label(&a.2),
                label(&b.2),
                mm(step),
                mm(median)
            ),
        ));
    }
    let (d0, p0) = (placed[0].0, placed[0].1);
    let limit = SHEAR_TOLERANCE * pixel_spacing[0].min(pixel_spacing[1]);
    for (d, p, f) in placed {
        let along = d - d0;
        let off = sub(*p, p0);
        // The part of the offset that is not along the normal.
        let normal_len = norm(off);
        let side = (normal_len * normal_len - along * along).max(0.0).sqrt();
        if side > limit {
            return Err(IoError::unsupported(
                dir,
                format!(
                    "slices are not stacked along the slice normal ({} is {} mm to the side of the first slice; gantry tilt?): sheared volumes are not supported",
                    label(f),
                    mm(side)
                ),
            ));
        }
    }
    Ok(())
}
