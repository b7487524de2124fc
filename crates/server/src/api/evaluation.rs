//! `POST /api/cells/{cell}/evaluate`: the metrics of one side against the other (a user's tracing, a file, a segmentation).
use super::*;
use interslice_interp::Interpolator;

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
pub(super) fn as_label(mut v: LabelVolume, label: u16) -> LabelVolume {
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
pub(super) fn resolve_source(
    state: &SharedState,
    me: &User,
    cell: &str,
    geometry: &Geometry,
    src: &Source,
    label: u16,
    m: &dyn Interpolator,
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
        if u.eq_ignore_ascii_case(interslice_store::CONSENSUS) {
            // The STAPLE consensus of everyone's tracing (reviewers only).
            return Ok(Arc::new(interslice_project::consensus::consensus_for(
                &state.store,
                me,
                geometry,
                cell,
                m,
                Some(label),
                cancel,
            )?));
        }
        let target = reader_target(state, me, Some(u))?;
        let tracing = interslice_project::groundtruth::StoredTracing {
            store: &state.store,
            cell,
            user_id: target.id,
        };
        return Ok(state
            .gt_cache
            .get(&tracing, geometry, m, Some(label), cancel)?);
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

#[utoipa::path(
    post,
    path = "/api/cells/{cell}/evaluate",
    tag = "evaluation",
    summary = "Metrics of a test against a reference",
    request_body = EvaluateBody,
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub(super) async fn evaluate(
    State(state): State<SharedState>,
    Auth(me): Auth,
    ApiPath(cell): ApiPath<String>,
    ApiJson(body): ApiJson<EvaluateBody>,
) -> Result<Response, ApiError> {
    let c = state.cell(&cell).await?;
    let method = method_for_cell(body.method.as_deref(), &c)?;
    let st = state.clone();
    let metrics = job(&state, move |cancel| {
        let g = c.volume.geometry();
        let m = method.as_ref();
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
