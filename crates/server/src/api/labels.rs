//! `/api/methods` and `/api/labels`: the interpolation methods and the project's labels.
use super::*;

/// One interpolation method.
#[derive(Serialize, utoipa::ToSchema)]
pub struct MethodInfo {
    /// `--method` name.
    pub name: String,
    /// One line.
    pub description: String,
}

#[utoipa::path(
    get,
    path = "/api/methods",
    tag = "interpolation",
    summary = "Interpolation methods, the default first",
    responses(
        (status = 200, description = "success", content_type = "application/json", body = Vec<MethodInfo>),
        ApiErrors,
    ),
)]
pub(super) async fn methods() -> Json<Vec<MethodInfo>> {
    Json(
        interslice_project::methods::method_list()
            .into_iter()
            .map(|(name, description)| MethodInfo { name, description })
            .collect(),
    )
}

#[utoipa::path(
    get,
    path = "/api/labels",
    tag = "labels",
    summary = "The project's labels",
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn labels(
    State(state): State<SharedState>,
    _a: Auth,
) -> Result<Response, ApiError> {
    Ok(Json(state.store.labels()?).into_response())
}

/// Body of `POST /api/labels`.
#[derive(Deserialize, utoipa::ToSchema)]
pub struct NewLabel {
    /// Display name.
    pub name: String,
    /// `#rrggbb` (a palette colour if omitted).
    #[serde(default)]
    pub color: Option<String>,
}

#[utoipa::path(
    post,
    path = "/api/labels",
    tag = "labels",
    summary = "Add a label",
    request_body = NewLabel,
    responses(
        (status = 201, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn add_label(
    State(state): State<SharedState>,
    Auth(user): Auth,
    ApiJson(body): ApiJson<NewLabel>,
) -> Result<Response, ApiError> {
    let l = state
        .store
        .add_label(&body.name, body.color.as_deref(), Some(user.id))?;
    Ok((StatusCode::CREATED, Json(l)).into_response())
}
