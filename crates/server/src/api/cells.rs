//! `/api/cells`, `/api/progress` and a cell's detail, status, histogram, time, tracing summary and slices.
use super::*;
use interslice_core::le::encode_le;

/// A cell in the list.
#[derive(Serialize, utoipa::ToSchema)]
pub struct CellSummary {
    /// URL-safe id.
    pub id: String,
    /// File or folder name.
    pub name: String,
    /// `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// `[sx, sy, sz]`.
    pub spacing: [f64; 3],
    /// Length unit ("µm", "mm", ...).
    pub unit: String,
    /// "u8", "u16" (or "i16", "f32" for volumes that bring them).
    pub dtype: String,
    /// "not_started", "in_progress" or "done" for the signed-in user;
    /// "unreadable" when the file cannot be read (see `error`).
    pub status: String,
    /// Seconds the user spent tracing it.
    pub seconds: f64,
    /// Why the cell's file cannot be read (then `dims` are 0 and the cell
    /// cannot be opened); absent for a readable cell.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

#[derive(Deserialize)]
pub(super) struct CellsQuery {
    #[serde(default)]
    queue: Option<bool>,
}

/// The list entry of a cell; `statuses` are the user's (one query for a
/// whole list, not one per cell).
pub(super) async fn summary(
    state: &SharedState,
    id: &str,
    user: &User,
    statuses: &std::collections::HashMap<String, CellStatus>,
) -> Result<CellSummary, ApiError> {
    let path = state.cell_path(id)?;
    let name = interslice_project::cells::display_name(&path);
    let rec = state.store.cell(id)?;
    let (geometry, dtype) = match rec.and_then(|r| Some((r.geometry?, r.dtype?))) {
        Some((g, d)) => (
            serde_json::from_str::<Geometry>(&g)
                .map_err(|e| ApiError::internal(format!("stored geometry: {e}")))?,
            d,
        ),
        None => {
            let c = state.cell(id).await?;
            (c.volume.geometry().clone(), c.dtype().to_string())
        }
    };
    let status = statuses.get(id).copied().unwrap_or(CellStatus::NotStarted);
    Ok(CellSummary {
        id: id.to_string(),
        name,
        dims: geometry.dims,
        spacing: geometry.spacing,
        unit: geometry.unit.symbol().to_string(),
        dtype,
        status: status.as_str().to_string(),
        seconds: state.store.time_spent(id, user.id)?,
        error: None,
    })
}

#[utoipa::path(
    get,
    path = "/api/cells",
    tag = "cells",
    summary = "Cells with the user's status (queue=true hides finished ones)",
    responses(
        (status = 200, description = "success", content_type = "application/json", body = Vec<CellSummary>),
        ApiErrors,
    ),
)]
pub(super) async fn list_cells(
    State(state): State<SharedState>,
    Auth(user): Auth,
    ApiQuery(q): ApiQuery<CellsQuery>,
) -> Result<Json<Vec<CellSummary>>, ApiError> {
    let st = state.clone();
    blocking(move || {
        st.rescan()
            .map_err(|e| ApiError::internal(format!("{e:#}")))
    })
    .await?;
    let ids = state.cell_ids();
    let statuses = state.store.statuses(user.id)?;
    let mut out = Vec::new();
    for id in ids {
        match summary(&state, &id, &user, &statuses).await {
            Ok(s) => {
                if q.queue == Some(true) && s.status == "done" {
                    continue;
                }
                out.push(s)
            }
            // A file that cannot be read is listed with its reason (it
            // cannot be opened), so the project's owner sees what to fix.
            Err(e) => {
                if q.queue == Some(true) {
                    continue;
                }
                let name = state
                    .cells
                    .read()
                    .unwrap_or_else(|p| p.into_inner())
                    .get(&id)
                    .map(|p| interslice_project::cells::display_name(p))
                    .unwrap_or_default();
                out.push(CellSummary {
                    id,
                    name,
                    dims: [0; 3],
                    spacing: [0.0; 3],
                    unit: String::new(),
                    dtype: String::new(),
                    status: "unreadable".into(),
                    seconds: 0.0,
                    error: Some(e.message),
                });
            }
        }
    }
    Ok(Json(out))
}

/// The campaign at a glance: each user's status, time and contour count per
/// cell. Reviewers see every user; a tracer sees their own rows.
#[utoipa::path(
    get,
    path = "/api/progress",
    tag = "cells",
    summary = "Each user's status, seconds and contour count per cell (reviewers: everyone; tracers: their own)",
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn progress(
    State(state): State<SharedState>,
    Auth(me): Auth,
) -> Result<Json<Vec<interslice_store::Progress>>, ApiError> {
    let only = (me.role != interslice_store::Role::Reviewer).then_some(me.id);
    Ok(Json(state.store.progress(only)?))
}

/// A cell with its intensity range and the labels.
#[derive(Serialize, utoipa::ToSchema)]
pub struct CellDetail {
    /// The list entry.
    #[serde(flatten)]
    pub summary: CellSummary,
    /// Smallest intensity.
    pub min: f64,
    /// Largest intensity.
    pub max: f64,
    /// The project's labels.
    #[schema(value_type = Vec<Object>)]
    pub labels: Vec<interslice_store::Label>,
    /// Physical origin of voxel (0,0,0).
    pub origin: [f64; 3],
}

#[utoipa::path(
    get,
    path = "/api/cells/{cell}",
    tag = "cells",
    summary = "A cell's metadata, range and labels",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn cell_detail(
    State(state): State<SharedState>,
    Auth(user): Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Json<CellDetail>, ApiError> {
    let c = state.cell(&cell).await?;
    let statuses = state.store.statuses(user.id)?;
    let summary = summary(&state, &cell, &user, &statuses).await?;
    Ok(Json(CellDetail {
        summary,
        min: c.min,
        max: c.max,
        labels: state.store.labels()?,
        origin: c.volume.geometry().origin,
    }))
}

#[derive(Deserialize, utoipa::ToSchema)]
pub(super) struct StatusBody {
    status: String,
}

#[utoipa::path(
    put,
    path = "/api/cells/{cell}/status",
    tag = "cells",
    summary = "Set the user's status of a cell",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn set_status(
    State(state): State<SharedState>,
    Auth(user): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<StatusBody>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let s = CellStatus::parse(&body.status)
        .ok_or_else(|| ApiError::bad_request("status must be not_started, in_progress or done"))?;
    state.store.set_status(&cell, user.id, s)?;
    Ok(Json(serde_json::json!({"status": s.as_str()})).into_response())
}

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/histogram",
    tag = "cells",
    summary = "256-bin intensity histogram",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn histogram(
    State(state): State<SharedState>,
    _a: Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Response, ApiError> {
    let c = state.cell(&cell).await?;
    Ok(Json(serde_json::json!({
        "min": c.min, "max": c.max, "bin_width": c.bin_width, "counts": c.counts,
    }))
    .into_response())
}

#[derive(Deserialize)]
pub(super) struct TimeBody {
    seconds: f64,
}

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/time",
    tag = "cells",
    summary = "Add tracing time (seconds)",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn add_time(
    State(state): State<SharedState>,
    Auth(user): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<TimeBody>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let total = state.store.add_time(&cell, user.id, body.seconds)?;
    Ok(Json(serde_json::json!({"total_seconds": total})).into_response())
}

/// The query of a cell's tracing summary.
#[derive(Deserialize, utoipa::IntoParams)]
#[into_params(parameter_in = Query)]
pub(super) struct SummaryQuery {
    /// The label summarised.
    label: u16,
    /// Whose tracing (reviewers: anyone's; default: the signed-in user's).
    #[serde(default)]
    user: Option<String>,
    /// The interpolation method the result is predicted for (default: the default method).
    #[serde(default)]
    method: Option<String>,
}

/// What one user's tracing of one label cost and is expected to give
/// (`interslice_project::report::effort`).
#[derive(Serialize, utoipa::ToSchema)]
pub struct TracingSummary {
    /// The label.
    pub label: u16,
    /// The axis the result is interpolated along (most drawn slices).
    pub axis: String,
    /// Slices with contours of the label, every axis.
    pub traced_slices: usize,
    /// Slices of the label marked empty, every axis.
    pub empty_slices: usize,
    /// Time spent: the user's recorded time on the cell, or the contours'
    /// drawing time when none was recorded (seconds).
    pub seconds: f64,
    /// Sum of the drawing times of the label's contours (seconds).
    pub contour_seconds: f64,
    /// Leave-one-out predicted Dice of the interpolated result; null with
    /// fewer than three drawn slices along `axis`.
    pub predicted_dice: Option<f64>,
}

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/summary",
    tag = "cells",
    summary = "Traced slices, time spent and the predicted Dice of a label's tracing (reviewers: ?user=)",
    params(CellPath, SummaryQuery),
    responses(
        (status = 200, description = "success", content_type = "application/json", body = TracingSummary),
        ApiErrors,
    ),
)]
pub(super) async fn tracing_summary(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiQuery(q): ApiQuery<SummaryQuery>,
) -> Result<Json<TracingSummary>, ApiError> {
    let target = reader_target(&state, &me, q.user.as_deref())?;
    check_label(&state, q.label)?;
    let c = state.cell(&cell).await?;
    let method = method_for_cell(q.method.as_deref(), &c)?;
    let st = state.clone();
    let e = job(&state, move |cancel| {
        let g = c.volume.geometry();
        Ok(interslice_project::report::effort::tracing_effort(
            &st.store,
            g,
            &cell,
            target.id,
            q.label,
            method.as_ref(),
            cancel,
        )?)
    })
    .await?;
    Ok(Json(TracingSummary {
        label: e.label,
        axis: e.axis.to_string(),
        traced_slices: e.traced_slices,
        empty_slices: e.empty_slices,
        seconds: e.seconds(),
        contour_seconds: e.contour_seconds,
        predicted_dice: e.predicted_dice(),
    }))
}

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/slices/{axis}/{index}",
    tag = "cells",
    summary = "Raw little-endian slice pixels (X-Width, X-Height, X-Dtype)",
    params(SlicePath),
    responses(
        (status = 200, description = "success", content_type = "application/octet-stream"),
        ApiErrors,
    ),
)]
pub(super) async fn slice(
    State(state): State<SharedState>,
    _a: Auth,
    path: SlicePath,
) -> Result<Response, ApiError> {
    let OpenSlice {
        loaded: c,
        axis,
        index,
        ..
    } = path.open(&state).await?;
    let g = c.volume.geometry();
    let (a, b) = axis.in_plane();
    let (w, h) = (g.dims[a], g.dims[b]);
    let bytes = match &c.volume {
        AnyVolume::U8(v) if axis == Axis::Z => {
            let n = w * h;
            v.data()[n * index..n * (index + 1)].to_vec()
        }
        AnyVolume::U16(_) if axis == Axis::Z => {
            let n = w * h;
            c.volume.le_bytes(n * index..n * (index + 1))
        }
        AnyVolume::U8(v) => v.slice(axis, index)?,
        AnyVolume::U16(v) => encode_le(&v.slice(axis, index)?),
        AnyVolume::I16(v) => encode_le(&v.slice(axis, index)?),
        AnyVolume::F32(v) => encode_le(&v.slice(axis, index)?),
    };
    let mut resp = slice_response(bytes, w, h, c.dtype());
    resp.headers_mut().insert(
        header::CACHE_CONTROL,
        HeaderValue::from_static("private, max-age=60"),
    );
    Ok(resp)
}
