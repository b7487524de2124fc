//! The OpenAPI 3.1 document at `/api/openapi.json`, built with utoipa from the
//! route table below (kept next to `api::router`, and checked against it by a
//! test) and the request/answer types.
use axum::response::{IntoResponse, Response};
use utoipa::openapi::path::{HttpMethod, OperationBuilder, ParameterBuilder, ParameterIn};
use utoipa::openapi::request_body::RequestBodyBuilder;
use utoipa::openapi::{
    ComponentsBuilder, ContentBuilder, InfoBuilder, OpenApi, OpenApiBuilder, Paths, Ref, Required,
    ResponseBuilder,
};

/// One documented route.
#[derive(Debug, Clone, Copy)]
pub struct Route {
    /// "GET", "POST", "PUT" or "DELETE".
    pub method: &'static str,
    /// Path with `{param}` placeholders, as in `api::router`.
    pub path: &'static str,
    /// Group in the document.
    pub tag: &'static str,
    /// One line.
    pub summary: &'static str,
    /// Schema name of the JSON request body, if any.
    pub body: Option<&'static str>,
    /// Content type of a success answer (empty: 204 without body).
    pub answer: &'static str,
}

const fn r(
    method: &'static str,
    path: &'static str,
    tag: &'static str,
    summary: &'static str,
    body: Option<&'static str>,
    answer: &'static str,
) -> Route {
    Route {
        method,
        path,
        tag,
        summary,
        body,
        answer,
    }
}

/// Every route of the API, in the order of `api::router`.
#[rustfmt::skip]
pub const ROUTES: &[Route] = &[
    r("POST", "/api/login", "session", "Sign in; sets the interslice_session cookie", Some("LoginBody"), "application/json"),
    r("POST", "/api/logout", "session", "Sign out", None, ""),
    r("GET", "/api/me", "session", "The signed-in user", None, "application/json"),
    r("GET", "/api/openapi.json", "meta", "This document", None, "application/json"),
    r("GET", "/api/methods", "interpolation", "Interpolation methods, the default first", None, "application/json"),
    r("GET", "/api/labels", "labels", "The project's labels", None, "application/json"),
    r("POST", "/api/labels", "labels", "Add a label", Some("NewLabel"), "application/json"),
    r("GET", "/api/cells", "cells", "Cells with the user's status (queue=true hides finished ones)", None, "application/json"),
    r("GET", "/api/progress", "cells", "Each user's status, seconds and contour count per cell (reviewers: everyone; tracers: their own)", None, "application/json"),
    r("GET", "/api/cells/{cell}", "cells", "A cell's metadata, range and labels", None, "application/json"),
    r("PUT", "/api/cells/{cell}/status", "cells", "Set the user's status of a cell", None, "application/json"),
    r("GET", "/api/cells/{cell}/histogram", "cells", "256-bin intensity histogram", None, "application/json"),
    r("POST", "/api/cells/{cell}/time", "cells", "Add tracing time (seconds)", None, "application/json"),
    r("GET", "/api/cells/{cell}/slices/{axis}/{index}", "cells", "Raw little-endian slice pixels (X-Width, X-Height, X-Dtype)", None, "application/octet-stream"),
    r("GET", "/api/cells/{cell}/contours", "contours", "The user's contours (reviewers: ?user=)", None, "application/json"),
    r("POST", "/api/cells/{cell}/contours", "contours", "Add a contour (client_id makes retries idempotent)", Some("AddContour"), "application/json"),
    r("DELETE", "/api/cells/{cell}/contours/{id}", "contours", "Delete one of the user's contours", None, ""),
    r("PUT", "/api/cells/{cell}/slices/{axis}/{index}/contours", "contours", "Replace a label's contours on a slice", Some("ReplaceSlice"), "application/json"),
    r("POST", "/api/cells/{cell}/slices/{axis}/{index}/empty", "contours", "Mark a slice drawn with no contour for a label", None, "application/json"),
    r("GET", "/api/cells/{cell}/drawn", "contours", "Drawn slices of a label along an axis", None, "application/json"),
    r("POST", "/api/cells/{cell}/undo", "contours", "Undo the user's last change", None, "application/json"),
    r("POST", "/api/cells/{cell}/redo", "contours", "Redo the user's last undone change", None, "application/json"),
    r("POST", "/api/cells/{cell}/interpolate", "interpolation", "Interpolate a label; preview contours per slice", Some("InterpolateBody"), "application/json"),
    r("GET", "/api/cells/{cell}/results", "interpolation", "The user's stored interpolation results, newest first (reviewers: ?user=)", None, "application/json"),
    r("GET", "/api/cells/{cell}/results/{result}/mesh", "interpolation", "Surface mesh of a result, physical units", None, "application/json"),
    r("GET", "/api/cells/{cell}/export", "interpolation", "Download the interpolated label volume or the contours", None, "application/octet-stream"),
    r("POST", "/api/cells/{cell}/evaluate", "evaluation", "Metrics of a test against a reference", Some("EvaluateBody"), "application/json"),
    r("GET", "/api/cells/{cell}/segmentations", "evaluation", "Computed segmentations and files under segmentations/<cell>/", None, "application/json"),
    r("POST", "/api/cells/{cell}/segmentations", "evaluation", "Compute a threshold segmentation", Some("SegmentBody"), "application/json"),
    r("POST", "/api/cells/{cell}/segmentations/upload", "evaluation", "Upload a label volume file (body; format from ?name=) as a segmentation", None, "application/json"),
    r("GET", "/api/cells/{cell}/overlay/{axis}/{index}", "evaluation", "u8 per pixel: 0 TN, 1 TP, 2 FP, 3 FN", None, "application/octet-stream"),
    r("GET", "/api/cells/{cell}/ratings", "evaluation", "Ratings of the cell's segmentations", None, "application/json"),
    r("POST", "/api/cells/{cell}/ratings", "evaluation", "Rate a segmentation 1..5", Some("RatingBody"), "application/json"),
];

fn method(m: &str) -> HttpMethod {
    match m {
        "POST" => HttpMethod::Post,
        "PUT" => HttpMethod::Put,
        "DELETE" => HttpMethod::Delete,
        _ => HttpMethod::Get,
    }
}

/// Build the document.
pub fn document() -> OpenApi {
    let mut paths = Paths::new();
    for &Route {
        method: m,
        path,
        tag,
        summary,
        body,
        answer,
    } in ROUTES
    {
        let mut op = OperationBuilder::new()
            .summary(Some(summary))
            .tag(tag)
            .operation_id(Some(format!(
                "{}_{}",
                m.to_ascii_lowercase(),
                path.trim_start_matches("/api/")
                    .replace(['/', '{', '}', '.'], "_")
            )));
        for seg in path.split('/') {
            if let Some(name) = seg.strip_prefix('{').and_then(|s| s.strip_suffix('}')) {
                op = op.parameter(
                    ParameterBuilder::new()
                        .name(name)
                        .parameter_in(ParameterIn::Path)
                        .required(Required::True),
                );
            }
        }
        if let Some(schema) = body {
            op = op.request_body(Some(
                RequestBodyBuilder::new()
                    .content(
                        "application/json",
                        ContentBuilder::new()
                            .schema(Some(Ref::from_schema_name(schema)))
                            .build(),
                    )
                    .required(Some(Required::True))
                    .build(),
            ));
        }
        let ok = if answer.is_empty() {
            ResponseBuilder::new().description("done").build()
        } else {
            ResponseBuilder::new()
                .description("success")
                .content(answer, ContentBuilder::new().build())
                .build()
        };
        let err = ResponseBuilder::new()
            .description("{\"error\": \"one line\"}: 400 malformed, 401 not signed in, 403 not yours, 404 unknown, 413 too large")
            .build();
        let op = op
            .response(if answer.is_empty() { "204" } else { "200" }, ok)
            .response("4XX", err)
            .build();
        paths.add_path_operation(path, vec![method(m)], op);
    }
    let components = ComponentsBuilder::new()
        .schema_from::<crate::auth::LoginBody>()
        .schema_from::<crate::auth::Me>()
        .schema_from::<crate::api::NewLabel>()
        .schema_from::<crate::api::CellSummary>()
        .schema_from::<crate::api::AddContour>()
        .schema_from::<crate::api::ReplaceSlice>()
        .schema_from::<crate::api::InterpolateBody>()
        .schema_from::<crate::api::InterpolateAnswer>()
        .schema_from::<crate::api::PreviewSlice>()
        .schema_from::<crate::api::ResultInfo>()
        .schema_from::<crate::api::EvaluateBody>()
        .schema_from::<crate::api::Source>()
        .schema_from::<crate::api::SegmentBody>()
        .schema_from::<crate::api::SegmentationInfo>()
        .schema_from::<crate::api::RatingBody>()
        .schema_from::<crate::api::MethodInfo>()
        .build();
    OpenApiBuilder::new()
        .info(
            InfoBuilder::new()
                .title("interslice")
                .version(env!("CARGO_PKG_VERSION"))
                .description(Some(
                    "Tracing server: cells, slices, contours, interpolation, export and evaluation. \
                     See docs/API.md.",
                ))
                .build(),
        )
        .paths(paths)
        .components(Some(components))
        .build()
}

/// `GET /api/openapi.json`.
pub async fn serve() -> Response {
    axum::Json(document()).into_response()
}
