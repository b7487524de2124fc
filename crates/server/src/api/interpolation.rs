//! `POST /api/cells/{cell}/interpolate` (the preview of one label) and the stored results with their meshes.
use super::*;

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
    /// A live preview: kept in memory for this user (a negative `result_id`,
    /// its mesh served while it is among their latest previews), not stored
    /// as a result.
    #[serde(default)]
    pub preview: bool,
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

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/interpolate",
    tag = "interpolation",
    summary = "Interpolate a label; preview contours per slice",
    request_body = InterpolateBody,
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json", body = InterpolateAnswer),
        ApiErrors,
    ),
)]
pub(super) async fn interpolate(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<InterpolateBody>,
) -> Result<Json<InterpolateAnswer>, ApiError> {
    let axis = parse_axis(&body.axis)?;
    check_label(&state, body.label)?;
    let c = state.cell(&cell).await?;
    let method = method_for_cell(body.method.as_deref(), &c)?;
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
        // A preview lives in memory; an asked-for result is stored.
        let result_id = if body.preview {
            st.previews
                .insert(me.id, &cell, body.label, axis, method.name(), mask)
        } else {
            st.store
                .save_result(&cell, me.id, body.label, axis, method.name(), &mask)?
        };
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
pub(super) struct UserQuery {
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

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/results",
    tag = "interpolation",
    summary = "The user's stored interpolation results, newest first (reviewers: ?user=)",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json", body = Vec<ResultInfo>),
        ApiErrors,
    ),
)]
pub(super) async fn list_results(
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

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/results/{result}/mesh",
    tag = "interpolation",
    summary = "Surface mesh of a result, physical units",
    params(
        CellPath,
        ("result" = i64, Path, description = "result id"),
    ),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn result_mesh(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath((cell, result)): ApiPath<(String, String)>,
) -> Result<Response, ApiError> {
    state.cell_path(&cell)?;
    let st = state.clone();
    let body = blocking(move || {
        let mask = match result.parse::<i64>() {
            Ok(id) if id < 0 => st
                .previews
                .get(me.id, &cell, id)
                .map(|p| p.mask)
                .ok_or_else(|| {
                    ApiError::not_found(format!(
                        "no preview {id} on cell '{cell}' (kept: the latest)"
                    ))
                })?,
            _ => Arc::new(readable_result(&st.store, &me, &cell, &result)?.1),
        };
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

#[derive(Deserialize)]
pub(super) struct AdviceQuery {
    label: u16,
    #[serde(default)]
    axis: Option<String>,
    #[serde(default)]
    count: Option<usize>,
    #[serde(default)]
    method: Option<String>,
}

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/advice",
    tag = "interpolation",
    summary = "The slices of a label to trace next, best first, and the predicted Dice",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn advice(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiQuery(q): ApiQuery<AdviceQuery>,
) -> Result<Response, ApiError> {
    let axis = parse_axis(q.axis.as_deref().unwrap_or("z"))?;
    check_label(&state, q.label)?;
    let count = crate::limits::advice_count(q.count.unwrap_or(3))?;
    let c = state.cell(&cell).await?;
    // The method is checked here so a bad name is a 400 before any work.
    method_for_cell(q.method.as_deref(), &c)?;
    let image =
        (q.method.as_deref() == Some(interslice_interp::IMAGE_METHOD)).then(|| c.intensity());
    let st = state.clone();
    let advice = job(&state, move |cancel| {
        cancel.check()?;
        let tracing = groundtruth::StoredTracing {
            store: &st.store,
            cell: &cell,
            user_id: me.id,
        };
        Ok(groundtruth::advise_label(
            &tracing,
            c.volume.geometry(),
            q.label,
            axis,
            count,
            q.method.as_deref(),
            image,
        )?)
    })
    .await?;
    Ok(Json(advice).into_response())
}
