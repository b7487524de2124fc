//! Interpolation methods by name: the slice-wise ones of `interslice_interp`
//! and the mesh ones, as the server's `/api/methods` lists them and every
//! `method` parameter or `--method` option names them; on a cell, also the
//! image-guided method, which reads the cell's own intensities.
use crate::cells::LoadedCell;
use crate::error::ProjectError;
use interslice_interp::image::ImageGuided;
use interslice_interp::{IMAGE_METHOD, Interpolator};

/// The interpolator called `name` (slice-wise or mesh), or the default.
pub fn method_by_name(name: Option<&str>) -> Result<Box<dyn Interpolator>, ProjectError> {
    let name = name.unwrap_or(interslice_interp::DEFAULT_METHOD);
    interslice_interp::by_name(name).map_err(ProjectError::from)
}

/// The interpolator called `name` for tracings on `cell`: the image-guided
/// method on the cell's intensities, or [`method_by_name`].
pub fn method_for_cell(
    name: Option<&str>,
    cell: &LoadedCell,
) -> Result<Box<dyn Interpolator>, ProjectError> {
    match name {
        Some(IMAGE_METHOD) => Ok(Box::new(ImageGuided::new(cell.intensity()))),
        other => method_by_name(other),
    }
}

/// Every method as (name, one-line description), the default first (the
/// registry holds the slice-wise and the mesh methods), then the image-guided
/// method, which every cell of a project can use.
pub fn method_list() -> Vec<(String, String)> {
    interslice_interp::methods()
        .iter()
        .map(|m| (m.name().to_string(), m.description().to_string()))
        .chain([(IMAGE_METHOD.to_string(), IMAGE_DESCRIPTION.to_string())])
        .collect()
}

/// The image-guided method's line in [`method_list`].
const IMAGE_DESCRIPTION: &str = "shape prior fused with the cell's intensities, learnt from the drawn slices (leave-one-out falls back to the shape where the image does not help)";
