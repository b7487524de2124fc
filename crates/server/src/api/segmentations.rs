//! Automated segmentations of a cell (computed, uploaded, or files), their FP/FN overlay and their ratings.
use super::*;

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

impl From<interslice_store::SegmentationMeta> for SegmentationInfo {
    fn from(s: interslice_store::SegmentationMeta) -> SegmentationInfo {
        SegmentationInfo {
            id: s.id.to_string(),
            name: s.name,
            method: s.method,
            params: s.params,
            created: s.created,
        }
    }
}

pub(super) fn segmentation_files(state: &SharedState, cell: &str) -> Vec<String> {
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

pub(super) fn load_segmentation(
    state: &SharedState,
    cell: &str,
    id: &str,
) -> Result<LabelVolume, ApiError> {
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

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/segmentations",
    tag = "evaluation",
    summary = "Computed segmentations and files under segmentations/<cell>/",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json", body = Vec<SegmentationInfo>),
        ApiErrors,
    ),
)]
pub(super) async fn list_segmentations(
    State(state): State<SharedState>,
    _a: Auth,
    ApiPath(cell): ApiPath<String>,
) -> Result<Json<Vec<SegmentationInfo>>, ApiError> {
    state.cell_path(&cell)?;
    let mut out: Vec<SegmentationInfo> = state
        .store
        .segmentations(&cell)?
        .into_iter()
        .map(SegmentationInfo::from)
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
pub(super) struct UploadQuery {
    name: String,
}

/// `POST /api/cells/{cell}/segmentations/upload?name=FILE`: the body is a
/// label volume file (its format from `name`'s extension) on the cell's grid;
/// it is stored like a computed segmentation and evaluated or rated by its id.
#[utoipa::path(
    post,
    path = "/api/cells/{cell}/segmentations/upload",
    tag = "evaluation",
    summary = "Upload a label volume file (body; format from ?name=) as a segmentation",
    params(CellPath),
    responses(
        (status = 201, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn upload_segmentation(
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
        Ok(SegmentationInfo::from(meta))
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

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/segmentations",
    tag = "evaluation",
    summary = "Compute a threshold segmentation",
    request_body = SegmentBody,
    params(CellPath),
    responses(
        (status = 201, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn add_segmentation(
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
        Ok(SegmentationInfo::from(meta))
    })
    .await?;
    Ok((StatusCode::CREATED, Json(info)).into_response())
}

#[derive(Deserialize)]
pub(super) struct OverlayQuery {
    label: u16,
    #[serde(default)]
    reference_user: Option<String>,
    segmentation: String,
    #[serde(default)]
    method: Option<String>,
}

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/overlay/{axis}/{index}",
    tag = "evaluation",
    summary = "u8 per pixel: 0 TN, 1 TP, 2 FP, 3 FN",
    params(SlicePath),
    responses(
        (status = 200, description = "success", content_type = "application/octet-stream"),
        ApiErrors,
    ),
)]
pub(super) async fn overlay(
    State(state): State<SharedState>,
    Auth(me): Auth,
    path: SlicePath,
    ApiQuery(q): ApiQuery<OverlayQuery>,
) -> Result<Response, ApiError> {
    let OpenSlice {
        cell,
        loaded: c,
        axis,
        index,
    } = path.open(&state).await?;
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
        let method = method_for_cell(q.method.as_deref(), &c)?;
        let m = method.as_ref();
        let gt = resolve_source(&st, &me, &cell, g, &reference, q.label, m, cancel)?;
        let seg = resolve_source(&st, &me, &cell, g, &test, q.label, m, cancel)?;
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
    Ok(slice_response(bytes, w, h, "u8"))
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
#[utoipa::path(
    get,
    path = "/api/cells/{cell}/ratings",
    tag = "evaluation",
    summary = "Ratings of the cell's segmentations",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn list_ratings(
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

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/ratings",
    tag = "evaluation",
    summary = "Rate a segmentation 1..5",
    request_body = RatingBody,
    params(CellPath),
    responses(
        (status = 201, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn add_rating(
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
