//! `POST /api/cells/{cell}/interpolate` (the preview of one label) and the stored results with their meshes.
use super::*;
use interslice_project::methods;

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
    /// Also outline, on each skipped slice, where the result is unsure
    /// (`PreviewSlice.uncertain`).
    #[serde(default)]
    pub confidence: bool,
    /// Also say which method leave-one-out recommends for this label and
    /// axis (`recommended_method`, `image_weight`); with no `method`, the
    /// result is the recommended method's.
    #[serde(default)]
    pub recommend: bool,
}

/// Voxels whose confidence ([`interslice_interp::confidence`]) is below this
/// are outlined as uncertain. Confidence is the (for the image-guided
/// method, calibrated on held-out drawn slices) probability that a voxel is
/// on the side of the boundary the result put it on; below 0.75 it is wrong
/// at least one time in four, which is where a second look pays. For the
/// shape methods, `σ(|φ| / τ) < 0.75` is the band `|φ| < ln 3 · τ ≈ 1.1 τ`
/// around the preview contour, `τ` the shape's expected boundary error at
/// that distance from the drawn slices: a band that widens towards the
/// middle of a gap and closes at the drawn slices.
pub const UNCERTAIN_BELOW: f32 = 0.75;

/// One slice of the preview.
#[derive(Serialize, utoipa::ToSchema)]
pub struct PreviewSlice {
    /// Slice index.
    pub index: usize,
    /// Whether the user drew it.
    pub drawn: bool,
    /// Contours of the interpolated mask on it.
    pub contours: Vec<Vec<[f64; 2]>>,
    /// With `confidence`, on a slice not drawn: the outlines (same
    /// coordinates as `contours`) of the pixels whose confidence is below
    /// 0.75 (`UNCERTAIN_BELOW`), empty where the result is sure everywhere.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncertain: Option<Vec<Vec<[f64; 2]>>>,
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
    /// With `recommend`: `image-guided` when its leave-one-out on the drawn
    /// slices uses the cell's image, else the shape default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub recommended_method: Option<String>,
    /// With `recommend`: the weight of the image in the fusion leave-one-out
    /// chose (0: the image did not help, or the recommended image-guided
    /// method reads it by its random walk instead).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image_weight: Option<f32>,
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
    // A named method is checked here so a bad name is a 400 before any work.
    let named = match body.method.as_deref() {
        Some(name) => Some(method_for_cell(Some(name), &c)?),
        None => None,
    };
    let st = state.clone();
    let answer = job(&state, move |cancel| {
        let g = c.volume.geometry().clone();
        let tracing = groundtruth::StoredTracing {
            store: &st.store,
            cell: &cell,
            user_id: me.id,
        };
        let rec = if body.recommend {
            Some(methods::recommend(
                &tracing, &g, body.label, axis, &c, cancel,
            )?)
        } else {
            None
        };
        let answer_rec = rec.as_ref().map(|r| (r.method, r.image_weight));
        // The recommended method comes planned: leave-one-out runs once.
        let method = match (named, rec) {
            (Some(m), _) => m,
            (None, Some(r)) => r.interpolator,
            (None, None) => method_for_cell(None, &c)?,
        };
        let (mask, drawn, confidence) = groundtruth::interpolate_label_with_confidence(
            &tracing,
            &g,
            body.label,
            axis,
            method.as_ref(),
            body.confidence,
            cancel,
        )?;
        let voxels = mask.data().iter().filter(|&&b| b).count() as u64;
        let slices = preview_slices(&mask, axis, &drawn, confidence.as_ref(), cancel)?;
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
            recommended_method: answer_rec.map(|r| r.0.to_string()),
            image_weight: answer_rec.map(|r| r.1),
        })
    })
    .await?;
    Ok(Json(answer))
}

/// Every slice of `mask` along `axis`: its contours and, with `confidence`,
/// the outlines of its uncertain pixels on the slices not `drawn`. Slices
/// run in parallel; a cancelled request stops within one slice's tracing.
fn preview_slices(
    mask: &interslice_core::Mask,
    axis: Axis,
    drawn: &[usize],
    confidence: Option<&interslice_core::Volume<f32>>,
    cancel: &Cancel,
) -> Result<Vec<PreviewSlice>, ApiError> {
    use interslice_core::trace::mask_polygons;
    use rayon::prelude::*;
    let (w, h) = mask.slice_shape(axis);
    let slices: Vec<PreviewSlice> = (0..mask.slice_count(axis))
        .into_par_iter()
        .map(|i| {
            let is_drawn = drawn.binary_search(&i).is_ok();
            if cancel.is_cancelled() {
                return PreviewSlice {
                    index: i,
                    drawn: is_drawn,
                    contours: Vec::new(),
                    uncertain: None,
                };
            }
            let s = mask.slice(axis, i).expect("index in range");
            let uncertain = confidence.filter(|_| !is_drawn).map(|c| {
                let low: Vec<bool> = c
                    .slice(axis, i)
                    .expect("index in range")
                    .iter()
                    .map(|&x| x < UNCERTAIN_BELOW)
                    .collect();
                mask_polygons(&low, w, h)
            });
            PreviewSlice {
                index: i,
                drawn: is_drawn,
                contours: mask_polygons(&s, w, h),
                uncertain,
            }
        })
        .collect();
    cancel.check()?;
    Ok(slices)
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
