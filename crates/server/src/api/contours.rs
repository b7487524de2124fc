//! A user's contours of a cell: list, add, delete, replace a slice, mark it empty, drawn slices, undo and redo.
use super::*;

#[derive(Deserialize)]
pub(super) struct ContoursQuery {
    axis: Option<String>,
    index: Option<usize>,
    label: Option<u16>,
    user: Option<String>,
}

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/contours",
    tag = "contours",
    summary = "The user's contours (reviewers: ?user=)",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn list_contours(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiQuery(q): ApiQuery<ContoursQuery>,
) -> Result<Json<Vec<StoredContour>>, ApiError> {
    state.cell_path(&cell)?;
    let target = reader_target(&state, &me, q.user.as_deref())?;
    let axis = q.axis.as_deref().map(parse_axis).transpose()?;
    Ok(Json(state.store.contours(&ContourQuery {
        cell,
        user_id: target.id,
        axis,
        index: q.index,
        label: q.label,
    })?))
}

/// Body of `POST /api/cells/{cell}/contours`.
#[derive(Deserialize, utoipa::ToSchema)]
pub struct AddContour {
    /// Label id.
    pub label: u16,
    /// "x", "y" or "z".
    pub axis: String,
    /// Slice index.
    pub index: usize,
    /// The contour itself.
    #[serde(flatten)]
    pub contour: NewContour,
    /// Idempotency key: a retry with the same key returns the stored contour.
    #[serde(default)]
    pub client_id: Option<String>,
}

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/contours",
    tag = "contours",
    summary = "Add a contour (client_id makes retries idempotent)",
    request_body = AddContour,
    params(CellPath),
    responses(
        (status = 201, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn add_contour(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<AddContour>,
) -> Result<Response, ApiError> {
    let axis = parse_axis(&body.axis)?;
    cell_with_slice(&state, &cell, axis, body.index).await?;
    let key = SliceKey {
        cell,
        user_id: me.id,
        label: body.label,
        axis,
        index: body.index,
    };
    let (stored, created) = state
        .store
        .add_contour(&key, body.contour, body.client_id)?;
    let status = if created {
        StatusCode::CREATED
    } else {
        StatusCode::OK
    };
    Ok((status, Json(stored)).into_response())
}

/// Body of `PUT .../slices/{axis}/{index}/contours`.
#[derive(Deserialize, utoipa::ToSchema)]
pub struct ReplaceSlice {
    /// Label id.
    pub label: u16,
    /// The new contours of the label on the slice (empty = clear).
    pub contours: Vec<NewContour>,
}

#[utoipa::path(
    put,
    path = "/api/cells/{cell}/slices/{axis}/{index}/contours",
    tag = "contours",
    summary = "Replace a label's contours on a slice",
    request_body = ReplaceSlice,
    params(SlicePath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn replace_slice(
    State(state): State<SharedState>,
    Auth(me): Auth,
    path: SlicePath,
    ApiJson(body): ApiJson<ReplaceSlice>,
) -> Result<Json<Vec<StoredContour>>, ApiError> {
    let (axis, index) = path.parse()?;
    crate::limits::slice_contours(body.contours.len())?;
    cell_with_slice(&state, &path.cell, axis, index).await?;
    let key = SliceKey {
        cell: path.cell,
        user_id: me.id,
        label: body.label,
        axis,
        index,
    };
    Ok(Json(state.store.replace_slice(&key, body.contours)?))
}

#[utoipa::path(
    delete,
    path = "/api/cells/{cell}/contours/{id}",
    tag = "contours",
    summary = "Delete one of the user's contours",
    params(
        CellPath,
        ("id" = i64, Path, description = "contour id"),
    ),
    responses(
        (status = 204, description = "done"),
        ApiErrors,
    ),
)]
pub(super) async fn delete_contour(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath((cell, id)): ApiPath<(String, String)>,
) -> Result<StatusCode, ApiError> {
    state.cell_path(&cell)?;
    let id: i64 = id
        .parse()
        .map_err(|_| ApiError::not_found(format!("no contour '{id}'")))?;
    state.store.delete_contour(&cell, me.id, id)?;
    Ok(StatusCode::NO_CONTENT)
}

#[derive(Deserialize)]
pub(super) struct LabelBody {
    label: u16,
}

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/slices/{axis}/{index}/empty",
    tag = "contours",
    summary = "Mark a slice drawn with no contour for a label",
    params(SlicePath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn mark_empty(
    State(state): State<SharedState>,
    Auth(me): Auth,
    path: SlicePath,
    ApiJson(body): ApiJson<LabelBody>,
) -> Result<Response, ApiError> {
    let OpenSlice {
        cell, axis, index, ..
    } = path.open(&state).await?;
    state.store.mark_empty(&SliceKey {
        cell,
        user_id: me.id,
        label: body.label,
        axis,
        index,
    })?;
    Ok(Json(serde_json::json!({"index": index, "empty": true})).into_response())
}

#[derive(Deserialize)]
pub(super) struct DrawnQuery {
    label: u16,
    #[serde(default)]
    axis: Option<String>,
    #[serde(default)]
    user: Option<String>,
}

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/drawn",
    tag = "contours",
    summary = "Drawn slices of a label along an axis",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn drawn(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiQuery(q): ApiQuery<DrawnQuery>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let target = reader_target(&state, &me, q.user.as_deref())?;
    let axis = parse_axis(q.axis.as_deref().unwrap_or("z"))?;
    Ok(Json(state.store.drawn(&cell, target.id, q.label, axis)?).into_response())
}

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/undo",
    tag = "contours",
    summary = "Undo the user's last change",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn undo(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let o = state.store.undo(&cell, me.id)?;
    Ok(undo_json(o))
}

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/redo",
    tag = "contours",
    summary = "Redo the user's last undone change",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn redo(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let o = state.store.redo(&cell, me.id)?;
    Ok(undo_json(o))
}

pub(super) fn undo_json(o: interslice_store::UndoOutcome) -> Response {
    let slice = o.slice.map(
        |(label, axis, index)| serde_json::json!({"label": label, "axis": axis, "index": index}),
    );
    Json(serde_json::json!({"changed": o.changed, "slice": slice})).into_response()
}
