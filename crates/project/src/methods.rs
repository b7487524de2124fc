//! Interpolation methods by name: the slice-wise ones of `interslice_interp`
//! and the mesh ones, as the server's `/api/methods` lists them and every
//! `method` parameter or `--method` option names them.
use crate::error::ProjectError;
use interslice_interp::Interpolator;

/// The interpolator called `name` (slice-wise or mesh), or the default.
pub fn method_by_name(name: Option<&str>) -> Result<Box<dyn Interpolator>, ProjectError> {
    let name = name.unwrap_or(interslice_interp::DEFAULT_METHOD);
    interslice_interp::by_name(name).map_err(ProjectError::from)
}

/// Every method as (name, one-line description), the default first (the
/// registry holds the slice-wise and the mesh methods).
pub fn method_list() -> Vec<(String, String)> {
    interslice_interp::methods()
        .iter()
        .map(|m| (m.name().to_string(), m.description().to_string()))
        .collect()
}
