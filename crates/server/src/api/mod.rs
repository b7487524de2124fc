//! The handlers of `docs/API.md`.
use crate::SharedState;
use crate::auth::{self, Auth, reader_target};
use crate::error::{ApiError, ApiJson, ApiPath, ApiQuery};
use crate::openapi::{self, ApiErrors, CellPath};
use axum::Router;
use axum::extract::State;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use interslice_core::{AnyVolume, Axis, Cancel, Geometry, LabelVolume};
use interslice_project::cells::{LoadedCell, safe_relative_path};
use interslice_project::export::readable_result;
use interslice_project::groundtruth;
use interslice_project::methods::method_for_cell;
use interslice_store::{CellStatus, ContourQuery, NewContour, SliceKey, StoredContour, User};
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use utoipa::openapi::{OpenApi, OpenApiBuilder};
use utoipa_axum::{router::OpenApiRouter, routes};

use axum::Json;

mod cells;
mod contours;
mod evaluation;
mod export;
mod interpolation;
mod labels;
mod segmentations;

pub use cells::*;
pub use contours::*;
pub use evaluation::*;
use export::*;
pub use interpolation::*;
pub use labels::*;
pub use segmentations::*;

/// Every API route, and the OpenAPI document collected from their
/// `#[utoipa::path]` declarations ([`crate::openapi`]).
pub fn router() -> (Router<SharedState>, OpenApi) {
    let (router, doc) =
        OpenApiRouter::with_openapi(OpenApiBuilder::new().info(openapi::info()).build())
            .routes(routes!(auth::login))
            .routes(routes!(auth::logout))
            .routes(routes!(auth::me))
            .routes(routes!(openapi::serve))
            .routes(routes!(methods))
            .routes(routes!(labels, add_label))
            .routes(routes!(list_cells))
            .routes(routes!(progress))
            .routes(routes!(cell_detail))
            .routes(routes!(set_status))
            .routes(routes!(histogram))
            .routes(routes!(add_time))
            .routes(routes!(tracing_summary))
            .routes(routes!(slice))
            .routes(routes!(list_contours, add_contour))
            .routes(routes!(delete_contour))
            .routes(routes!(replace_slice))
            .routes(routes!(mark_empty))
            .routes(routes!(drawn))
            .routes(routes!(undo))
            .routes(routes!(redo))
            .routes(routes!(interpolate))
            .routes(routes!(advice))
            .routes(routes!(list_results))
            .routes(routes!(result_mesh))
            .routes(routes!(export))
            .routes(routes!(evaluate))
            .routes(routes!(list_segmentations, add_segmentation))
            .routes(routes!(upload_segmentation))
            .routes(routes!(overlay))
            .routes(routes!(list_ratings, add_rating))
            .split_for_parts();
    let router = router
        .route("/api", get(api_not_found))
        .route("/api/{*rest}", axum::routing::any(api_not_found));
    (router, doc)
}

async fn api_not_found() -> ApiError {
    ApiError::not_found("no such API endpoint (see /api/openapi.json)")
}

fn parse_axis(s: &str) -> Result<Axis, ApiError> {
    Axis::parse(s).map_err(|e| ApiError::bad_request(e.to_string()))
}

/// A slice index from the path: anything that is not a valid index names no
/// slice (404).
fn parse_index(s: &str) -> Result<usize, ApiError> {
    s.parse::<usize>().map_err(|_| {
        ApiError::not_found(format!("no slice '{s}' (slice indices are 0, 1, 2, ...)"))
    })
}

/// The `{cell}`, `{axis}` and `{index}` of a slice route, as given; handlers
/// parse them in their own order ([`SlicePath::parse`], then the cell).
#[derive(utoipa::IntoParams)]
#[into_params(parameter_in = Path)]
struct SlicePath {
    /// Cell id (`GET /api/cells`).
    cell: String,
    /// `x`, `y` or `z`.
    axis: String,
    /// Slice index along the axis.
    #[param(value_type = usize)]
    index: String,
}

impl<S: Send + Sync> axum::extract::FromRequestParts<S> for SlicePath {
    type Rejection = ApiError;

    async fn from_request_parts(
        parts: &mut axum::http::request::Parts,
        state: &S,
    ) -> Result<Self, Self::Rejection> {
        let ApiPath((cell, axis, index)) =
            ApiPath::<(String, String, String)>::from_request_parts(parts, state).await?;
        Ok(SlicePath { cell, axis, index })
    }
}

impl SlicePath {
    /// The axis (a bad one is 400) and the index (one that is not a number
    /// names no slice: 404).
    fn parse(&self) -> Result<(Axis, usize), ApiError> {
        Ok((parse_axis(&self.axis)?, parse_index(&self.index)?))
    }

    /// Parse, load the cell and check the slice lies in it: the opening
    /// steps of every slice route.
    async fn open(self, state: &SharedState) -> Result<OpenSlice, ApiError> {
        let (axis, index) = self.parse()?;
        let loaded = cell_with_slice(state, &self.cell, axis, index).await?;
        Ok(OpenSlice {
            cell: self.cell,
            loaded,
            axis,
            index,
        })
    }
}

/// A slice route's cell, loaded, and its slice, in range.
struct OpenSlice {
    cell: String,
    loaded: Arc<LoadedCell>,
    axis: Axis,
    index: usize,
}

/// The loaded cell, or 404 when slice `index` along `axis` is not in it.
async fn cell_with_slice(
    state: &SharedState,
    cell: &str,
    axis: Axis,
    index: usize,
) -> Result<Arc<LoadedCell>, ApiError> {
    let c = state.cell(cell).await?;
    check_slice(c.volume.geometry(), axis, index)?;
    Ok(c)
}

/// Raw slice bytes as the UI reads them: `application/octet-stream` with
/// the slice's width, height and voxel type in `x-width`, `x-height`,
/// `x-dtype`.
fn slice_response(bytes: Vec<u8>, w: usize, h: usize, dtype: &'static str) -> Response {
    let mut resp = bytes.into_response();
    let hd = resp.headers_mut();
    hd.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/octet-stream"),
    );
    hd.insert("x-width", HeaderValue::from(w));
    hd.insert("x-height", HeaderValue::from(h));
    hd.insert("x-dtype", HeaderValue::from_static(dtype));
    resp
}

fn check_slice(geometry: &Geometry, axis: Axis, index: usize) -> Result<(), ApiError> {
    let n = geometry.dims[axis.dim()];
    if index >= n {
        return Err(ApiError::not_found(format!(
            "slice {axis}={index} is out of range (0..{n})"
        )));
    }
    Ok(())
}

fn check_label(state: &SharedState, label: u16) -> Result<(), ApiError> {
    if state.store.labels()?.iter().any(|l| l.id == label) {
        Ok(())
    } else {
        Err(ApiError::bad_request(format!(
            "unknown label {label} (GET /api/labels)"
        )))
    }
}

async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f).await?
}

/// Long work: on the blocking pool, stopped through its token when the
/// request is gone or the server stops ([`crate::jobs`]).
async fn job<T: Send + 'static>(
    state: &SharedState,
    f: impl FnOnce(&Cancel) -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    state.jobs.run(f).await
}
