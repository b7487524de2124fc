//! The OpenAPI 3.1 document at `/api/openapi.json`. It is collected by
//! utoipa-axum from the `#[utoipa::path]` declaration on each handler while
//! [`crate::api::router`] is built, so the route table exists once: a route is
//! documented exactly when it is served.
use axum::response::{IntoResponse, Response};
use std::sync::OnceLock;
use utoipa::openapi::{InfoBuilder, OpenApi};

/// What every route may answer besides success, for the document.
#[derive(utoipa::IntoResponses)]
#[response(
    status = "4XX",
    description = "{\"error\": \"one line\"}: 400 malformed, 401 not signed in, 403 not yours, 404 unknown, 413 too large"
)]
pub(crate) struct ApiErrors;

/// The `{cell}` of a cell's routes, for the document (handlers take it with
/// `ApiPath<String>`).
#[derive(utoipa::IntoParams)]
#[into_params(parameter_in = Path)]
#[allow(dead_code)]
pub(crate) struct CellPath {
    /// Cell id (`GET /api/cells`).
    cell: String,
}

/// The document's title block.
pub(crate) fn info() -> utoipa::openapi::Info {
    InfoBuilder::new()
        .title("interslice")
        .version(env!("CARGO_PKG_VERSION"))
        .description(Some(
            "Tracing server: cells, slices, contours, interpolation, export and evaluation. \
             See docs/API.md.",
        ))
        .build()
}

/// The document, built once from the router's declarations.
pub fn document() -> &'static OpenApi {
    static DOC: OnceLock<OpenApi> = OnceLock::new();
    DOC.get_or_init(|| crate::api::router().1)
}

/// `GET /api/openapi.json`: [`document`].
#[utoipa::path(
    get,
    path = "/api/openapi.json",
    tag = "meta",
    summary = "This document",
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub async fn serve() -> Response {
    axum::Json(document()).into_response()
}
