//! `GET /api/cells/{cell}/export`: a user's label volume, a stored result, the consensus or the contours file (`interslice_project::export`).
use super::*;

#[derive(Deserialize)]
pub(super) struct ExportQuery {
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

#[utoipa::path(
    get,
    path = "/api/cells/{cell}/export",
    tag = "interpolation",
    summary = "Download the interpolated label volume or the contours",
    params(CellPath),
    responses(
        (status = 200, description = "success", content_type = "application/octet-stream"),
        ApiErrors,
    ),
)]
pub(super) async fn export(
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
            return Ok(interslice_project::export::result_bytes(
                &st.store, &me, &cell, id, &format,
            )?);
        }
        if consensus {
            let m = method_for_cell(q.method.as_deref(), &c)?;
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
        Ok(interslice_project::export::export_bytes(
            &st.store,
            Some(&st.gt_cache),
            &cell,
            c.volume.geometry(),
            &target,
            &format,
            method_for_cell(q.method.as_deref(), &c)?.as_ref(),
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
