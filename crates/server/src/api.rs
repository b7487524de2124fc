//! The handlers of `docs/API.md`.
use crate::auth::{self, Auth, reader_target};
use crate::error::{ApiError, ApiJson, ApiPath, ApiQuery};
use crate::{SharedState, openapi};
use axum::Router;
use axum::extract::State;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{delete, get, post, put};
use interslice_core::{AnyVolume, Axis, Cancel, Geometry, LabelVolume};
use interslice_project::cells::{le_bytes, safe_relative_path};
use interslice_project::export::{self, readable_result};
use interslice_project::groundtruth;
use interslice_project::methods::method_by_name;
use interslice_store::{CellStatus, ContourQuery, NewContour, SliceKey, StoredContour, User};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

use axum::Json;

/// Every API route.
pub fn router() -> Router<SharedState> {
    Router::new()
        .route("/api/login", post(auth::login))
        .route("/api/logout", post(auth::logout))
        .route("/api/me", get(auth::me))
        .route("/api/openapi.json", get(openapi::serve))
        .route("/api/methods", get(methods))
        .route("/api/labels", get(labels).post(add_label))
        .route("/api/cells", get(list_cells))
        .route("/api/progress", get(progress))
        .route("/api/cells/{cell}", get(cell_detail))
        .route("/api/cells/{cell}/status", put(set_status))
        .route("/api/cells/{cell}/histogram", get(histogram))
        .route("/api/cells/{cell}/time", post(add_time))
        .route("/api/cells/{cell}/slices/{axis}/{index}", get(slice))
        .route(
            "/api/cells/{cell}/contours",
            get(list_contours).post(add_contour),
        )
        .route("/api/cells/{cell}/contours/{id}", delete(delete_contour))
        .route(
            "/api/cells/{cell}/slices/{axis}/{index}/contours",
            put(replace_slice),
        )
        .route(
            "/api/cells/{cell}/slices/{axis}/{index}/empty",
            post(mark_empty),
        )
        .route("/api/cells/{cell}/drawn", get(drawn))
        .route("/api/cells/{cell}/undo", post(undo))
        .route("/api/cells/{cell}/redo", post(redo))
        .route("/api/cells/{cell}/interpolate", post(interpolate))
        .route("/api/cells/{cell}/results", get(list_results))
        .route("/api/cells/{cell}/results/{result}/mesh", get(result_mesh))
        .route("/api/cells/{cell}/export", get(export))
        .route("/api/cells/{cell}/evaluate", post(evaluate))
        .route(
            "/api/cells/{cell}/segmentations",
            get(list_segmentations).post(add_segmentation),
        )
        .route(
            "/api/cells/{cell}/segmentations/upload",
            post(upload_segmentation),
        )
        .route("/api/cells/{cell}/overlay/{axis}/{index}", get(overlay))
        .route(
            "/api/cells/{cell}/ratings",
            get(list_ratings).post(add_rating),
        )
        .route("/api", get(api_not_found))
        .route("/api/{*rest}", axum::routing::any(api_not_found))
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

// ------------------------------------------------------------------ methods, labels

/// One interpolation method.
#[derive(Serialize, utoipa::ToSchema)]
pub struct MethodInfo {
    /// `--method` name.
    pub name: String,
    /// One line.
    pub description: String,
}

async fn methods() -> Json<Vec<MethodInfo>> {
    Json(
        interslice_project::methods::method_list()
            .into_iter()
            .map(|(name, description)| MethodInfo { name, description })
            .collect(),
    )
}

async fn labels(State(state): State<SharedState>, _a: Auth) -> Result<Response, ApiError> {
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

async fn add_label(
    State(state): State<SharedState>,
    Auth(user): Auth,
    ApiJson(body): ApiJson<NewLabel>,
) -> Result<Response, ApiError> {
    let l = state
        .store
        .add_label(&body.name, body.color.as_deref(), Some(user.id))?;
    Ok((StatusCode::CREATED, Json(l)).into_response())
}

// ------------------------------------------------------------------ cells

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
struct CellsQuery {
    #[serde(default)]
    queue: Option<bool>,
}

/// The list entry of a cell; `statuses` are the user's (one query for a
/// whole list, not one per cell).
async fn summary(
    state: &SharedState,
    id: &str,
    user: &User,
    statuses: &std::collections::HashMap<String, CellStatus>,
) -> Result<CellSummary, ApiError> {
    let path = state.cell_path(id)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_else(|| id.to_string());
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

async fn list_cells(
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
    let ids: Vec<String> = state
        .cells
        .read()
        .unwrap_or_else(|e| e.into_inner())
        .keys()
        .cloned()
        .collect();
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
                    .and_then(|p| p.file_name())
                    .map(|n| n.to_string_lossy().into_owned())
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
async fn progress(
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

async fn cell_detail(
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
struct StatusBody {
    status: String,
}

async fn set_status(
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

async fn histogram(
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
struct TimeBody {
    seconds: f64,
}

async fn add_time(
    State(state): State<SharedState>,
    Auth(user): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<TimeBody>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let total = state.store.add_time(&cell, user.id, body.seconds)?;
    Ok(Json(serde_json::json!({"total_seconds": total})).into_response())
}

async fn slice(
    State(state): State<SharedState>,
    _a: Auth,
    ApiPath((cell, axis, index)): ApiPath<(String, String, String)>,
) -> Result<Response, ApiError> {
    let axis = parse_axis(&axis)?;
    let index = parse_index(&index)?;
    let c = state.cell(&cell).await?;
    let g = c.volume.geometry();
    check_slice(g, axis, index)?;
    let (a, b) = axis.in_plane();
    let (w, h) = (g.dims[a], g.dims[b]);
    let bytes = match &c.volume {
        AnyVolume::U8(v) if axis == Axis::Z => {
            let n = w * h;
            v.data()[n * index..n * (index + 1)].to_vec()
        }
        AnyVolume::U16(_) if axis == Axis::Z => {
            let n = w * h;
            le_bytes(&c.volume, n * index..n * (index + 1))
        }
        AnyVolume::U8(v) => v.slice(axis, index)?,
        AnyVolume::U16(v) => v
            .slice(axis, index)?
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect(),
        AnyVolume::I16(v) => v
            .slice(axis, index)?
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect(),
        AnyVolume::F32(v) => v
            .slice(axis, index)?
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect(),
    };
    let mut resp = bytes.into_response();
    let hd = resp.headers_mut();
    hd.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/octet-stream"),
    );
    hd.insert("x-width", HeaderValue::from(w));
    hd.insert("x-height", HeaderValue::from(h));
    hd.insert("x-dtype", HeaderValue::from_static(c.dtype()));
    hd.insert(
        header::CACHE_CONTROL,
        HeaderValue::from_static("private, max-age=60"),
    );
    Ok(resp)
}

// ------------------------------------------------------------------ contours

#[derive(Deserialize)]
struct ContoursQuery {
    axis: Option<String>,
    index: Option<usize>,
    label: Option<u16>,
    user: Option<String>,
}

async fn list_contours(
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
    /// `[[u, v], ...]`, at least 3.
    pub points: Vec<[f64; 2]>,
    /// Pen pressure per point.
    #[serde(default)]
    pub pressure: Option<Vec<f32>>,
    /// Milliseconds since the stroke began, per point.
    #[serde(default)]
    pub times_ms: Option<Vec<f64>>,
    /// "pen", "mouse", ...
    #[serde(default)]
    pub tool: Option<String>,
    /// Time spent drawing it in ms (default: the last of `times_ms`).
    #[serde(default)]
    pub duration_ms: Option<f64>,
    /// Idempotency key: a retry with the same key returns the stored contour.
    #[serde(default)]
    pub client_id: Option<String>,
}

async fn add_contour(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<AddContour>,
) -> Result<Response, ApiError> {
    let axis = parse_axis(&body.axis)?;
    let c = state.cell(&cell).await?;
    check_slice(c.volume.geometry(), axis, body.index)?;
    let key = SliceKey {
        cell,
        user_id: me.id,
        label: body.label,
        axis,
        index: body.index,
    };
    let (stored, created) = state.store.add_contour(
        &key,
        NewContour {
            points: body.points,
            pressure: body.pressure,
            times_ms: body.times_ms,
            tool: body.tool,
            duration_ms: body.duration_ms,
        },
        body.client_id,
    )?;
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
    #[schema(value_type = Vec<Object>)]
    pub contours: Vec<NewContour>,
}

async fn replace_slice(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath((cell, axis, index)): ApiPath<(String, String, String)>,
    ApiJson(body): ApiJson<ReplaceSlice>,
) -> Result<Json<Vec<StoredContour>>, ApiError> {
    let axis = parse_axis(&axis)?;
    let index = parse_index(&index)?;
    crate::limits::slice_contours(body.contours.len())?;
    let c = state.cell(&cell).await?;
    check_slice(c.volume.geometry(), axis, index)?;
    let key = SliceKey {
        cell,
        user_id: me.id,
        label: body.label,
        axis,
        index,
    };
    Ok(Json(state.store.replace_slice(&key, body.contours)?))
}

async fn delete_contour(
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
struct LabelBody {
    label: u16,
}

async fn mark_empty(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath((cell, axis, index)): ApiPath<(String, String, String)>,
    ApiJson(body): ApiJson<LabelBody>,
) -> Result<Response, ApiError> {
    let axis = parse_axis(&axis)?;
    let index = parse_index(&index)?;
    let c = state.cell(&cell).await?;
    check_slice(c.volume.geometry(), axis, index)?;
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
struct DrawnQuery {
    label: u16,
    #[serde(default)]
    axis: Option<String>,
    #[serde(default)]
    user: Option<String>,
}

async fn drawn(
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

async fn undo(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let o = state.store.undo(&cell, me.id)?;
    Ok(undo_json(o))
}

async fn redo(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let o = state.store.redo(&cell, me.id)?;
    Ok(undo_json(o))
}

fn undo_json(o: interslice_store::UndoOutcome) -> Response {
    let slice = o.slice.map(
        |(label, axis, index)| serde_json::json!({"label": label, "axis": axis, "index": index}),
    );
    Json(serde_json::json!({"changed": o.changed, "slice": slice})).into_response()
}

// ------------------------------------------------------------------ interpolation

/// Body of `POST /api/cells/{cell}/interpolate`.
#[derive(Deserialize, utoipa::ToSchema)]
pub struct InterpolateBody {
    /// Label id.
    pub label: u16,
    /// Axis of the drawn slices.
    pub axis: String,
    /// Method name (default first in `/api/methods`).
    #[serde(default)]
    pub method: Option<String>,
}

/// One slice of the preview.
#[derive(Serialize, utoipa::ToSchema)]
pub struct PreviewSlice {
    /// Slice index.
    pub index: usize,
    /// Whether the user drew it.
    pub drawn: bool,
    /// Contours of the interpolated mask on it.
    pub contours: Vec<Vec<[f64; 2]>>,
}

/// Answer of `POST /api/cells/{cell}/interpolate`.
#[derive(Serialize, utoipa::ToSchema)]
pub struct InterpolateAnswer {
    /// Id of the stored result (for the mesh).
    pub result_id: i64,
    /// Method used.
    pub method: String,
    /// Label id.
    pub label: u16,
    /// Axis.
    pub axis: String,
    /// Every slice along `axis`.
    pub slices: Vec<PreviewSlice>,
    /// Physical volume of the interpolated mask.
    pub volume: f64,
    /// Its unit (cubed).
    pub unit: String,
    /// Foreground voxels.
    pub voxels: u64,
}

async fn interpolate(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<InterpolateBody>,
) -> Result<Json<InterpolateAnswer>, ApiError> {
    let axis = parse_axis(&body.axis)?;
    check_label(&state, body.label)?;
    let method = method_by_name(body.method.as_deref())?;
    let c = state.cell(&cell).await?;
    let st = state.clone();
    let answer = job(&state, move |cancel| {
        let g = c.volume.geometry().clone();
        let tracing = groundtruth::StoredTracing {
            store: &st.store,
            cell: &cell,
            user_id: me.id,
        };
        let (mask, drawn) = groundtruth::interpolate_label(
            &tracing,
            &g,
            body.label,
            axis,
            method.as_ref(),
            cancel,
        )?;
        let voxels = mask.data().iter().filter(|&&b| b).count() as u64;
        let result_id =
            st.store
                .save_result(&cell, me.id, body.label, axis, method.name(), &mask)?;
        let (w, h) = mask.slice_shape(axis);
        use rayon::prelude::*;
        let slices: Vec<PreviewSlice> = (0..mask.slice_count(axis))
            .into_par_iter()
            .map(|i| {
                let s = mask.slice(axis, i).expect("index in range");
                PreviewSlice {
                    index: i,
                    drawn: drawn.binary_search(&i).is_ok(),
                    contours: interslice_core::trace::mask_polygons(&s, w, h),
                }
            })
            .collect();
        Ok(InterpolateAnswer {
            result_id,
            method: method.name().to_string(),
            label: body.label,
            axis: axis.to_string(),
            slices,
            volume: voxels as f64 * g.voxel_volume(),
            unit: format!("{}³", g.unit.symbol()),
            voxels,
        })
    })
    .await?;
    Ok(Json(answer))
}

#[derive(Deserialize)]
struct UserQuery {
    #[serde(default)]
    user: Option<String>,
}

/// A stored interpolation result.
#[derive(Serialize, utoipa::ToSchema)]
pub struct ResultInfo {
    /// Id (for the mesh and `export?result=`).
    pub id: i64,
    /// Label id.
    pub label: u16,
    /// Axis of the drawn slices.
    pub axis: String,
    /// Interpolation method.
    pub method: String,
    /// Foreground voxels.
    pub voxels: u64,
    /// When computed (RFC 3339).
    pub created: String,
}

async fn list_results(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiQuery(q): ApiQuery<UserQuery>,
) -> Result<Json<Vec<ResultInfo>>, ApiError> {
    state.cell_path(&cell)?;
    let target = reader_target(&state, &me, q.user.as_deref())?;
    Ok(Json(
        state
            .store
            .results(&cell, target.id)?
            .into_iter()
            .map(|r| ResultInfo {
                id: r.id,
                label: r.label,
                axis: r.axis.to_string(),
                method: r.method,
                voxels: r.voxels,
                created: r.created,
            })
            .collect(),
    ))
}

async fn result_mesh(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath((cell, result)): ApiPath<(String, String)>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let st = state.clone();
    let body = blocking(move || {
        let (_, mask) = readable_result(&st.store, &me, &cell, &result)?;
        let mesh = interslice_interp::mesh::mask_surface(&mask);
        let vertices: Vec<f64> = mesh.vertices.iter().flatten().copied().collect();
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        serde_json::to_vec(&serde_json::json!({"vertices": vertices, "indices": indices}))
            .map_err(|e| ApiError::internal(e.to_string()))
    })
    .await?;
    let mut resp = body.into_response();
    resp.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    Ok(resp)
}

// ------------------------------------------------------------------ export

#[derive(Deserialize)]
struct ExportQuery {
    #[serde(default)]
    format: Option<String>,
    /// A stored interpolation result instead of a fresh interpolation.
    #[serde(default)]
    result: Option<String>,
    #[serde(default)]
    user: Option<String>,
    #[serde(default)]
    method: Option<String>,
    #[serde(default)]
    label: Option<u16>,
}

async fn export(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiQuery(q): ApiQuery<ExportQuery>,
) -> Result<Response, ApiError> {
    let c = state.cell(&cell).await?;
    // The STAPLE consensus of every user's tracing (reviewers only).
    let consensus = q
        .user
        .as_deref()
        .is_some_and(|u| u.eq_ignore_ascii_case(interslice_store::CONSENSUS));
    let target = if consensus {
        me.clone()
    } else {
        reader_target(&state, &me, q.user.as_deref())?
    };
    let format = q.format.unwrap_or_else(|| "nii.gz".to_string());
    let st = state.clone();
    let (bytes, name) = job(&state, move |cancel| {
        if let Some(id) = &q.result {
            return Ok(export::result_bytes(&st.store, &me, &cell, id, &format)?);
        }
        if consensus {
            let m = method_by_name(q.method.as_deref())?;
            let g = c.volume.geometry();
            return Ok(interslice_project::consensus::export_bytes(
                &st.store,
                &target,
                &cell,
                g,
                &format,
                m.as_ref(),
                q.label,
                cancel,
            )?);
        }
        Ok(export::export_bytes(
            &st.store,
            &cell,
            c.volume.geometry(),
            &target,
            &format,
            q.method.as_deref(),
            q.label,
            cancel,
        )?)
    })
    .await?;
    let mut resp = bytes.into_response();
    let ct = if name.ends_with(".json") {
        "application/json"
    } else {
        "application/octet-stream"
    };
    resp.headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static(ct));
    resp.headers_mut().insert(
        header::CONTENT_DISPOSITION,
        HeaderValue::from_str(&format!("attachment; filename=\"{name}\""))
            .map_err(|e| ApiError::internal(e.to_string()))?,
    );
    Ok(resp)
}

// ------------------------------------------------------------------ evaluation

/// One side of an evaluation: a user's interpolated tracing, a file under the
/// project folder, or a stored segmentation.
#[derive(Deserialize, utoipa::ToSchema, Default)]
pub struct Source {
    /// A user's interpolated ground truth.
    #[serde(default)]
    pub user: Option<String>,
    /// A label volume, relative to the project folder.
    #[serde(default)]
    pub path: Option<String>,
    /// A segmentation id from `GET .../segmentations`.
    #[serde(default)]
    pub segmentation: Option<String>,
}

/// Body of `POST /api/cells/{cell}/evaluate`.
#[derive(Deserialize, utoipa::ToSchema)]
pub struct EvaluateBody {
    /// Label id.
    pub label: u16,
    /// The ground truth.
    pub reference: Source,
    /// What is measured.
    pub test: Source,
    /// Interpolation method for user sources.
    #[serde(default)]
    pub method: Option<String>,
    /// NSD tolerance (physical units, default 1).
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// A segmentation as a label volume where `label` is foreground: a binary
/// (0/1) segmentation's 1 stands for whatever label is asked.
fn as_label(mut v: LabelVolume, label: u16) -> LabelVolume {
    let max = v.data().iter().copied().max().unwrap_or(0);
    if max == 1 && label != 1 {
        v.data_mut().iter_mut().for_each(|x| {
            if *x == 1 {
                *x = label
            }
        });
    }
    v
}

#[allow(clippy::too_many_arguments)]
fn resolve_source(
    state: &SharedState,
    me: &User,
    cell: &str,
    geometry: &Geometry,
    src: &Source,
    label: u16,
    method: Option<&str>,
    cancel: &Cancel,
) -> Result<Arc<LabelVolume>, ApiError> {
    let given = [
        src.user.is_some(),
        src.path.is_some(),
        src.segmentation.is_some(),
    ]
    .iter()
    .filter(|&&b| b)
    .count();
    if given != 1 {
        return Err(ApiError::bad_request(
            "each side names exactly one of user, path or segmentation",
        ));
    }
    if let Some(u) = &src.user {
        // A tracing is measured as the whole structure of `label` (the cell
        // with its nucleus inside, the nucleus with its nucleoli), not the
        // painted remainder: a threshold's foreground covers the whole cell.
        let m = method_by_name(method)?;
        if u.eq_ignore_ascii_case(interslice_store::CONSENSUS) {
            // The STAPLE consensus of everyone's tracing (reviewers only).
            return Ok(Arc::new(interslice_project::consensus::consensus_for(
                &state.store,
                me,
                geometry,
                cell,
                m.as_ref(),
                Some(label),
                cancel,
            )?));
        }
        let target = reader_target(state, me, Some(u))?;
        return Ok(state.gt_cache.get(
            &state.store,
            geometry,
            cell,
            target.id,
            m.as_ref(),
            Some(label),
            cancel,
        )?);
    }
    let v = if let Some(p) = &src.path {
        let rel = safe_relative_path(p)?;
        let full = state.dir.join(rel);
        if !full.exists() {
            return Err(ApiError::not_found(format!("no file '{p}' in the project")));
        }
        // A symbolic link inside the project must not lead out of it.
        let inside = match (full.canonicalize(), state.dir.canonicalize()) {
            (Ok(f), Ok(d)) => f.starts_with(d),
            _ => false,
        };
        if !inside {
            return Err(ApiError::bad_request(format!(
                "path '{p}' leads outside the project folder"
            )));
        }
        interslice_io::read_labels(&full)?
    } else {
        let id = src.segmentation.as_deref().unwrap_or_default();
        crate::limits::segmentation_id(id)?;
        load_segmentation(state, cell, id)?
    };
    v.geometry().ensure_same_grid(geometry).map_err(|e| {
        ApiError::bad_request(format!("the segmentation is not on the cell's grid: {e}"))
    })?;
    Ok(Arc::new(as_label(v, label)))
}

async fn evaluate(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<EvaluateBody>,
) -> Result<Response, ApiError> {
    let c = state.cell(&cell).await?;
    let st = state.clone();
    let metrics = job(&state, move |cancel| {
        let g = c.volume.geometry();
        let m = body.method.as_deref();
        let r = resolve_source(&st, &me, &cell, g, &body.reference, body.label, m, cancel)?;
        let t = resolve_source(&st, &me, &cell, g, &body.test, body.label, m, cancel)?;
        cancel.check()?;
        let tol = body
            .tolerance
            .unwrap_or(interslice_core::metrics::DEFAULT_TOLERANCE);
        Ok(interslice_core::metrics::evaluate_label(
            &r, &t, body.label, tol,
        )?)
    })
    .await?;
    Ok(Json(metrics).into_response())
}

// ------------------------------------------------------------------ segmentations

/// A segmentation of a cell: computed (numeric id) or a file under
/// `segmentations/<cell>/` (id `file:<name>`).
#[derive(Serialize, utoipa::ToSchema)]
pub struct SegmentationInfo {
    /// Id for overlays, evaluation and ratings.
    pub id: String,
    /// Display name.
    pub name: String,
    /// "otsu", "rosin", "kmeans", "multi-otsu" or "file".
    pub method: String,
    /// Parameters.
    #[schema(value_type = Object)]
    pub params: serde_json::Value,
    /// When computed (files: empty).
    pub created: String,
}

fn segmentation_files(state: &SharedState, cell: &str) -> Vec<String> {
    let dir = state.dir.join("segmentations").join(cell);
    let mut out: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .filter(|e| e.path().is_file())
                .map(|e| e.file_name().to_string_lossy().to_string())
                .filter(|n| {
                    !n.starts_with('.')
                        && interslice_io::Format::of_path(std::path::Path::new(n)).is_ok()
                })
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

fn load_segmentation(state: &SharedState, cell: &str, id: &str) -> Result<LabelVolume, ApiError> {
    if let Some(name) = id.strip_prefix("file:") {
        if !segmentation_files(state, cell).iter().any(|n| n == name) {
            return Err(ApiError::not_found(format!(
                "no segmentation file '{name}'"
            )));
        }
        let rel = safe_relative_path(name)?;
        return Ok(interslice_io::read_labels(
            &state.dir.join("segmentations").join(cell).join(rel),
        )?);
    }
    let n: i64 = id
        .parse()
        .map_err(|_| ApiError::not_found(format!("no segmentation '{id}'")))?;
    state
        .store
        .segmentation_volume(cell, n)?
        .ok_or_else(|| ApiError::not_found(format!("no segmentation '{id}' on cell '{cell}'")))
}

async fn list_segmentations(
    State(state): State<SharedState>,
    _a: Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Json<Vec<SegmentationInfo>>, ApiError> {
    state.cell_path(&cell)?;
    let mut out: Vec<SegmentationInfo> = state
        .store
        .segmentations(&cell)?
        .into_iter()
        .map(|s| SegmentationInfo {
            id: s.id.to_string(),
            name: s.name,
            method: s.method,
            params: s.params,
            created: s.created,
        })
        .collect();
    for f in segmentation_files(&state, &cell) {
        out.push(SegmentationInfo {
            id: format!("file:{f}"),
            name: f.clone(),
            method: "file".into(),
            params: serde_json::json!({"path": format!("segmentations/{cell}/{f}")}),
            created: String::new(),
        });
    }
    Ok(Json(out))
}

#[derive(Deserialize)]
struct UploadQuery {
    name: String,
}

/// `POST /api/cells/{cell}/segmentations/upload?name=FILE`: the body is a
/// label volume file (its format from `name`'s extension) on the cell's grid;
/// it is stored like a computed segmentation and evaluated or rated by its id.
async fn upload_segmentation(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiQuery(q): ApiQuery<UploadQuery>,
    body: Result<axum::body::Bytes, axum::extract::rejection::BytesRejection>,
) -> Result<Response, ApiError> {
    let body = body.map_err(crate::error::body_rejection)?;
    let rel = crate::limits::upload_name(&q.name)?;
    interslice_io::Format::of_name(&rel)?;
    if body.is_empty() {
        return Err(ApiError::bad_request("the uploaded file is empty"));
    }
    let c = state.cell(&cell).await?;
    let st = state.clone();
    let info = blocking(move || {
        // Read from memory: self-contained formats only (no detached data
        // file), the header checked against the cell's grid before any voxel
        // data is decompressed.
        let limits = interslice_io::ReadLimits::for_grid(c.volume.geometry().dims);
        let labels = interslice_io::read_labels_bytes(&q.name, &body, &limits)?;
        labels
            .geometry()
            .ensure_same_grid(c.volume.geometry())
            .map_err(|e| {
                ApiError::bad_request(format!("the segmentation is not on the cell's grid: {e}"))
            })?;
        let params = serde_json::json!({"file": q.name, "bytes": body.len()});
        let meta =
            st.store
                .save_segmentation(&cell, &q.name, "upload", &params, &labels, Some(me.id))?;
        Ok(SegmentationInfo {
            id: meta.id.to_string(),
            name: meta.name,
            method: meta.method,
            params: meta.params,
            created: meta.created,
        })
    })
    .await?;
    Ok((StatusCode::CREATED, Json(info)).into_response())
}

/// Body of `POST /api/cells/{cell}/segmentations`.
#[derive(Deserialize, utoipa::ToSchema)]
pub struct SegmentBody {
    /// "otsu", "rosin", "kmeans" or "multi-otsu".
    pub method: String,
    /// Classes including background (k-means, multi-Otsu).
    #[serde(default)]
    pub classes: Option<usize>,
    /// Gaussian σ in physical units.
    #[serde(default)]
    pub smooth: Option<f64>,
    /// Keep the largest connected component.
    #[serde(default)]
    pub largest_component: Option<bool>,
    /// Neighbours that connect for `largest_component`: 6 (default) or 26.
    #[serde(default)]
    pub connectivity: Option<u8>,
    /// Fill holes.
    #[serde(default)]
    pub fill_holes: Option<bool>,
}

async fn add_segmentation(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<SegmentBody>,
) -> Result<Response, ApiError> {
    use interslice_core::segment::{SegmentMethod, SegmentParams};
    let method = SegmentMethod::parse(&body.method)?;
    let mut p = SegmentParams {
        method,
        ..Default::default()
    };
    if let Some(k) = body.classes {
        p.classes = k;
    } else if body.method == "multi-otsu" {
        p.classes = 3;
    }
    p.largest_component = body.largest_component.unwrap_or(false);
    if let Some(n) = body.connectivity {
        p.connectivity = interslice_core::morph::Connectivity::parse(&n.to_string())?;
    }
    p.fill_holes = body.fill_holes.unwrap_or(false);
    let c = state.cell(&cell).await?;
    p.smooth_sigma = crate::limits::smooth(body.smooth.unwrap_or(0.0), c.volume.geometry())?;
    p.validate()?;
    let st = state.clone();
    let info = job(&state, move |cancel| {
        let labels = interslice_core::segment::segment(&c.volume, &p, cancel)?;
        let params = serde_json::json!({
            "classes": p.classes, "smooth": p.smooth_sigma,
            "largest_component": p.largest_component, "fill_holes": p.fill_holes,
            "connectivity": p.connectivity.neighbours(),
        });
        let mut name = p.method.name().to_string();
        if p.smooth_sigma > 0.0 {
            name.push_str(&format!(" σ={}", p.smooth_sigma));
        }
        let meta = st.store.save_segmentation(
            &cell,
            &name,
            p.method.name(),
            &params,
            &labels,
            Some(me.id),
        )?;
        Ok(SegmentationInfo {
            id: meta.id.to_string(),
            name: meta.name,
            method: meta.method,
            params: meta.params,
            created: meta.created,
        })
    })
    .await?;
    Ok((StatusCode::CREATED, Json(info)).into_response())
}

#[derive(Deserialize)]
struct OverlayQuery {
    label: u16,
    #[serde(default)]
    reference_user: Option<String>,
    segmentation: String,
    #[serde(default)]
    method: Option<String>,
}

async fn overlay(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath((cell, axis, index)): ApiPath<(String, String, String)>,
    ApiQuery(q): ApiQuery<OverlayQuery>,
) -> Result<Response, ApiError> {
    let axis = parse_axis(&axis)?;
    let index = parse_index(&index)?;
    let c = state.cell(&cell).await?;
    check_slice(c.volume.geometry(), axis, index)?;
    let st = state.clone();
    let (bytes, w, h) = job(&state, move |cancel| {
        let g = c.volume.geometry();
        let reference = Source {
            user: Some(q.reference_user.clone().unwrap_or_else(|| me.name.clone())),
            ..Default::default()
        };
        let test = Source {
            segmentation: Some(q.segmentation.clone()),
            ..Default::default()
        };
        let method = q.method.as_deref();
        let gt = resolve_source(&st, &me, &cell, g, &reference, q.label, method, cancel)?;
        let seg = resolve_source(&st, &me, &cell, g, &test, q.label, None, cancel)?;
        let a = gt.slice(axis, index)?;
        let b = seg.slice(axis, index)?;
        let bytes: Vec<u8> = a
            .iter()
            .zip(&b)
            .map(|(&x, &y)| match (x == q.label, y == q.label) {
                (false, false) => 0,
                (true, true) => 1,
                (false, true) => 2,
                (true, false) => 3,
            })
            .collect();
        let (w, h) = gt.slice_shape(axis);
        Ok((bytes, w, h))
    })
    .await?;
    let mut resp = bytes.into_response();
    let hd = resp.headers_mut();
    hd.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/octet-stream"),
    );
    hd.insert("x-width", HeaderValue::from(w));
    hd.insert("x-height", HeaderValue::from(h));
    hd.insert("x-dtype", HeaderValue::from_static("u8"));
    Ok(resp)
}

/// Body of `POST /api/cells/{cell}/ratings`.
#[derive(Deserialize, utoipa::ToSchema)]
pub struct RatingBody {
    /// Segmentation id.
    pub segmentation: String,
    /// 1..=5.
    pub score: u8,
    /// Free text.
    #[serde(default)]
    pub comment: String,
}

/// A cell's ratings: a rating and its comment belong to their author and the
/// reviewers, so a tracer sees only their own.
async fn list_ratings(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let mut ratings = state.store.ratings(Some(&cell))?;
    if me.role != interslice_store::Role::Reviewer {
        ratings.retain(|r| r.user == me.name);
    }
    Ok(Json(ratings).into_response())
}

async fn add_rating(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<RatingBody>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    crate::limits::segmentation_id(&body.segmentation)?;
    let known = body.segmentation.starts_with("file:")
        && segmentation_files(&state, &cell)
            .iter()
            .any(|f| Some(f.as_str()) == body.segmentation.strip_prefix("file:"))
        || body.segmentation.parse::<i64>().ok().is_some_and(|id| {
            state
                .store
                .segmentations(&cell)
                .map(|s| s.iter().any(|s| s.id == id))
                .unwrap_or(false)
        });
    if !known {
        return Err(ApiError::not_found(format!(
            "no segmentation '{}' on cell '{cell}'",
            body.segmentation
        )));
    }
    let r = state
        .store
        .add_rating(&cell, me.id, &body.segmentation, body.score, &body.comment)?;
    Ok((StatusCode::CREATED, Json(r)).into_response())
}
