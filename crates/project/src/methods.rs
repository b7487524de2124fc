//! Interpolation methods by name: the slice-wise ones of `interslice_interp`
//! and the mesh ones, as the server's `/api/methods` lists them and every
//! `method` parameter or `--method` option names them; on a cell, also the
//! image-guided method, which reads the cell's own intensities, and which of
//! the two a tracing should use ([`recommend`]).
use crate::cells::LoadedCell;
use crate::error::ProjectError;
use crate::groundtruth::{Tracing, sparse_mask};
use interslice_core::{Axis, Cancel, Geometry};
use interslice_interp::image::ImageGuided;
use interslice_interp::{DEFAULT_METHOD, IMAGE_METHOD, Interpolator, SparseMask};

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

/// Which method a tracing of one label along one axis is best interpolated
/// with on its cell, as leave-one-out on the drawn slices decides it.
pub struct Recommendation {
    /// [`IMAGE_METHOD`] when the image-guided method's leave-one-out uses
    /// the image, else the shape default ([`interslice_interp::DEFAULT_METHOD`]),
    /// which is then the image-guided result bit for bit and cheaper.
    pub method: &'static str,
    /// The weight of the image in the fusion that leave-one-out chose (0:
    /// shape only, or the image read by the walk instead, `Plan::walk`;
    /// `method` says whether the image is read).
    pub image_weight: f32,
    /// The method itself, ready to interpolate the tracing (the
    /// image-guided one keeps its plan, so leave-one-out runs once).
    pub interpolator: Box<dyn Interpolator>,
}

/// The [`Recommendation`] for `label` along `axis` of `tracing` on `cell`
/// (its intensities, [`LoadedCell::intensity`]): the image-guided method's plan
/// ([`ImageGuided::plan`]), which interpolates the held-out drawn slices
/// (and walks once in the band of the label's shape prior, and where that
/// comes close once on its whole box), not the volume. With two drawn
/// slices nothing can be held out: the image is read only where the
/// outlines lie on a clear intensity edge (`image::EDGE_SEPARATION`).
pub fn recommend(
    tracing: &dyn Tracing,
    geometry: &Geometry,
    label: u16,
    axis: Axis,
    cell: &LoadedCell,
    cancel: &Cancel,
) -> Result<Recommendation, ProjectError> {
    cancel.check()?;
    let (mask, drawn) = sparse_mask(tracing, geometry, label, axis)?;
    let shape = || -> Result<Recommendation, ProjectError> {
        Ok(Recommendation {
            method: DEFAULT_METHOD,
            image_weight: 0.0,
            interpolator: method_by_name(None)?,
        })
    };
    if drawn.len() < 2 {
        return shape();
    }
    let input = SparseMask::new(&mask, axis, &drawn).with_cancel(cancel);
    let guided = ImageGuided::new(cell.intensity());
    let plan = guided.plan(&input)?;
    cancel.check()?;
    if !plan.uses_image() {
        return shape();
    }
    Ok(Recommendation {
        method: IMAGE_METHOD,
        image_weight: plan.params.w,
        interpolator: Box::new(guided.with_plan(&input, plan)),
    })
}
