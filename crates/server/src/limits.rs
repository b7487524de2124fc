//! The bounds of the numbers and names a client sends, checked before any
//! work: a value out of range is a 400 that states the allowed range. The
//! store bounds what it keeps (points per contour, seconds, score, comment
//! and name lengths); these are the bounds of the routes' own parameters.
//! `docs/API.md` lists every one.
use crate::error::ApiError;
use interslice_core::Geometry;
use std::path::PathBuf;

/// Largest Gaussian σ of `POST .../segmentations`, in voxels of the cell's
/// finest spacing: the kernel reaches 4 σ, so 20 voxels already spans 161
/// voxels, and the cost grows with σ (about 12 ms per voxel of σ on a 64³ cell).
pub const MAX_SMOOTH_VOXELS: f64 = 20.0;

/// Longest name of an uploaded segmentation, in characters.
pub const MAX_UPLOAD_NAME: usize = 128;

/// Most contours of one label on one slice in one `PUT .../contours`.
pub const MAX_SLICE_CONTOURS: usize = 1000;

/// Longest password, in bytes (the hash reads all of it).
pub const MAX_PASSWORD_BYTES: usize = 1024;

/// Longest segmentation id a client may name (ids are numbers or
/// `file:NAME`).
pub const MAX_SEGMENTATION_ID: usize = 256;

/// The segmentation's smoothing σ (physical units) if it is within
/// `0..=MAX_SMOOTH_VOXELS` voxels of the cell's finest spacing.
pub fn smooth(sigma: f64, geometry: &Geometry) -> Result<f64, ApiError> {
    let finest = geometry
        .spacing
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    // Rounded to what a person reads (20 × 0.35 is 7.000000000000001).
    let max = (MAX_SMOOTH_VOXELS * finest * 1e6).round() / 1e6;
    if sigma.is_finite() && (0.0..=max).contains(&sigma) {
        Ok(sigma)
    } else {
        Err(ApiError::bad_request(format!(
            "smooth must be between 0 and {max} {} ({MAX_SMOOTH_VOXELS} voxels of this cell), not {sigma}",
            geometry.unit.symbol()
        )))
    }
}

/// The file name of an uploaded segmentation: one name (never a path) of at
/// most [`MAX_UPLOAD_NAME`] characters, in a format whose data is in the one
/// file. A `.mhd` or `.nhdr` header names another file for its data, and a
/// folder of slices is many files: an upload can carry neither.
pub fn upload_name(name: &str) -> Result<PathBuf, ApiError> {
    use interslice_io::Format;
    let n = name.chars().count();
    if n > MAX_UPLOAD_NAME {
        return Err(ApiError::bad_request(format!(
            "the upload name has {n} characters; at most {MAX_UPLOAD_NAME}"
        )));
    }
    let rel = interslice_project::cells::safe_relative_path(name)?;
    if rel.components().count() != 1 {
        return Err(ApiError::bad_request(format!(
            "name '{name}' must be a file name, not a path"
        )));
    }
    let single = "name the upload .nii, .nii.gz, .nrrd, .mha or .tif";
    // Only an extension decides: the name does not exist here.
    let lower = name.to_ascii_lowercase();
    let format = if lower.contains('.') {
        Format::of_path(&rel).map_err(|_| {
            ApiError::bad_request(format!("'{name}' is not a label volume format: {single}"))
        })?
    } else {
        Format::SliceFolder
    };
    match format {
        Format::Nifti | Format::NiftiGz | Format::Nrrd | Format::Mha | Format::Tiff => Ok(rel),
        Format::Mhd | Format::Nhdr => Err(ApiError::bad_request(format!(
            "'{name}' is a header whose data lives in another file, which an upload cannot carry: {single}"
        ))),
        _ => Err(ApiError::bad_request(format!(
            "an upload is one file: {single}"
        ))),
    }
}

/// At most [`MAX_SLICE_CONTOURS`] contours on one slice.
pub fn slice_contours(n: usize) -> Result<(), ApiError> {
    if n > MAX_SLICE_CONTOURS {
        return Err(ApiError::bad_request(format!(
            "{n} contours on one slice; at most {MAX_SLICE_CONTOURS}"
        )));
    }
    Ok(())
}

/// Most slices one advice request may suggest.
pub const MAX_ADVICE_COUNT: usize = 50;

/// The number of suggested slices asked for: 1..=[`MAX_ADVICE_COUNT`].
pub fn advice_count(n: usize) -> Result<usize, ApiError> {
    if (1..=MAX_ADVICE_COUNT).contains(&n) {
        Ok(n)
    } else {
        Err(ApiError::bad_request(format!(
            "count {n} is out of range (1..={MAX_ADVICE_COUNT})"
        )))
    }
}

/// A password of at most [`MAX_PASSWORD_BYTES`] bytes.
pub fn password(pw: &str) -> Result<(), ApiError> {
    if pw.len() > MAX_PASSWORD_BYTES {
        return Err(ApiError::bad_request(format!(
            "the password is {} bytes long; at most {MAX_PASSWORD_BYTES}",
            pw.len()
        )));
    }
    Ok(())
}

/// A segmentation id of at most [`MAX_SEGMENTATION_ID`] characters.
pub fn segmentation_id(id: &str) -> Result<(), ApiError> {
    let n = id.chars().count();
    if n > MAX_SEGMENTATION_ID {
        return Err(ApiError::bad_request(format!(
            "the segmentation id has {n} characters; at most {MAX_SEGMENTATION_ID}"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::LengthUnit;

    #[test]
    fn upload_names_name_one_file_of_a_known_format() {
        for ok in [
            "a.nii",
            "a.nii.gz",
            "b.seg.nrrd",
            "c.mha",
            "d.tif",
            "E.TIFF",
        ] {
            assert!(upload_name(ok).is_ok(), "{ok}");
        }
        for bad in [
            "x.mhd", "x.nhdr", "x.raw", "x", "x.exe", "../x.nii", "a/b.nii",
        ] {
            assert!(upload_name(bad).is_err(), "{bad}");
        }
        let long = format!("{}.nii", "a".repeat(5000));
        let e = upload_name(&long).unwrap_err().message;
        assert!(e.contains("at most 128"), "{e}");
    }

    #[test]
    fn smoothing_is_bounded_in_voxels_of_the_finest_spacing() {
        let g = Geometry::new([8, 8, 8], [0.5, 0.5, 2.0], LengthUnit::Micrometre).unwrap();
        assert_eq!(smooth(10.0, &g).unwrap(), 10.0);
        assert_eq!(smooth(0.0, &g).unwrap(), 0.0);
        for bad in [10.5, -1.0, f64::NAN, f64::INFINITY] {
            let e = smooth(bad, &g).unwrap_err().message;
            assert!(e.contains("between 0 and 10 µm"), "{e}");
        }
    }
}
