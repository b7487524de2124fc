//! API errors: every failure is `{"error": "one line"}` with a 4xx/5xx status.
use axum::extract::rejection::BytesRejection;
use axum::extract::{FromRequest, Request};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use interslice_store::StoreError;
use serde::de::DeserializeOwned;

/// An error answered to the client.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct ApiError {
    /// HTTP status.
    pub status: StatusCode,
    /// One line for the user.
    pub message: String,
}

impl ApiError {
    /// An error with a status and message.
    pub fn new(status: StatusCode, message: impl Into<String>) -> ApiError {
        let message: String = message.into();
        // Keep it one line.
        let message = message.replace(['\n', '\r'], " ");
        ApiError { status, message }
    }
    /// 400 Bad Request.
    pub fn bad_request(m: impl Into<String>) -> ApiError {
        ApiError::new(StatusCode::BAD_REQUEST, m)
    }
    /// 401 Unauthorized.
    pub fn unauthorized(m: impl Into<String>) -> ApiError {
        ApiError::new(StatusCode::UNAUTHORIZED, m)
    }
    /// 403 Forbidden.
    pub fn forbidden(m: impl Into<String>) -> ApiError {
        ApiError::new(StatusCode::FORBIDDEN, m)
    }
    /// 404 Not Found.
    pub fn not_found(m: impl Into<String>) -> ApiError {
        ApiError::new(StatusCode::NOT_FOUND, m)
    }
    /// 500 Internal Server Error.
    pub fn internal(m: impl Into<String>) -> ApiError {
        ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, m)
    }
}

/// The JSON error body.
pub fn error_response(status: StatusCode, message: &str) -> Response {
    (status, axum::Json(serde_json::json!({ "error": message }))).into_response()
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        error_response(self.status, &self.message)
    }
}

impl From<StoreError> for ApiError {
    fn from(e: StoreError) -> ApiError {
        let status = match &e {
            StoreError::NotFound(_) => StatusCode::NOT_FOUND,
            StoreError::Forbidden(_) => StatusCode::FORBIDDEN,
            StoreError::Invalid(_) => StatusCode::BAD_REQUEST,
            StoreError::BadCredentials => StatusCode::UNAUTHORIZED,
            _ => StatusCode::INTERNAL_SERVER_ERROR,
        };
        ApiError::new(status, e.to_string())
    }
}

impl From<interslice_core::CoreError> for ApiError {
    fn from(e: interslice_core::CoreError) -> ApiError {
        match e {
            interslice_core::CoreError::SliceOutOfRange { .. } => {
                ApiError::not_found(e.to_string())
            }
            // Only a job whose request is gone or whose server is stopping
            // is cancelled; whoever still listens learns it is not a bug.
            interslice_core::CoreError::Cancelled => ApiError::new(
                StatusCode::SERVICE_UNAVAILABLE,
                "the request was stopped (the server is shutting down or the request timed out)",
            ),
            _ => ApiError::bad_request(e.to_string()),
        }
    }
}

impl From<interslice_interp::InterpError> for ApiError {
    fn from(e: interslice_interp::InterpError) -> ApiError {
        match e {
            interslice_interp::InterpError::Core(c @ interslice_core::CoreError::Cancelled) => {
                ApiError::from(c)
            }
            other => ApiError::bad_request(other.to_string()),
        }
    }
}

impl From<interslice_io::IoError> for ApiError {
    fn from(e: interslice_io::IoError) -> ApiError {
        ApiError::bad_request(e.to_string())
    }
}

/// A project error answered: invalid 400, not found 404, forbidden 403, the
/// wrapped errors as they map on their own.
impl From<interslice_project::ProjectError> for ApiError {
    fn from(e: interslice_project::ProjectError) -> ApiError {
        use interslice_project::ProjectError as P;
        match e {
            P::Invalid(m) => ApiError::bad_request(m),
            P::NotFound(m) => ApiError::not_found(m),
            P::Forbidden(m) => ApiError::forbidden(m),
            P::Internal(m) => ApiError::internal(m),
            P::Store(e) => e.into(),
            P::Core(e) => e.into(),
            P::Interp(e) => e.into(),
            P::Io(e) => e.into(),
            P::File(e) => ApiError::internal(e.to_string()),
            P::Context { context, cause } => {
                let message = format!("{context}: {cause}");
                ApiError::new(ApiError::from(*cause).status, message)
            }
        }
    }
}

impl From<tokio::task::JoinError> for ApiError {
    fn from(e: tokio::task::JoinError) -> ApiError {
        ApiError::internal(format!("internal error: {e}"))
    }
}

/// A body that could not be read: 413 over the limit, else the reason.
pub fn body_rejection(e: BytesRejection) -> ApiError {
    let status = e.status();
    if status == StatusCode::PAYLOAD_TOO_LARGE {
        ApiError::new(status, "request body is too large")
    } else {
        ApiError::new(status, e.body_text())
    }
}

/// A JSON body: the request must say `Content-Type: application/json` (else
/// 415: a cross-site form or `text/plain` fetch cannot send that without the
/// browser asking first), a body over the limit is 413, anything unparsable
/// 400 with serde's one-line reason.
pub struct ApiJson<T>(pub T);

/// Whether a `Content-Type` value is JSON (`application/json`, any
/// parameters, or an `application/*+json` type).
fn is_json(value: &str) -> bool {
    let essence = value
        .split(';')
        .next()
        .unwrap_or("")
        .trim()
        .to_ascii_lowercase();
    essence == "application/json"
        || essence.starts_with("application/") && essence.ends_with("+json")
}

impl<S: Send + Sync, T: DeserializeOwned> FromRequest<S> for ApiJson<T> {
    type Rejection = ApiError;

    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        let json = req
            .headers()
            .get(axum::http::header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok())
            .is_some_and(is_json);
        if !json {
            return Err(ApiError::new(
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "the body must be JSON sent with Content-Type: application/json",
            ));
        }
        let bytes = axum::body::Bytes::from_request(req, state)
            .await
            .map_err(body_rejection)?;
        serde_json::from_slice(&bytes)
            .map(ApiJson)
            .map_err(|e| ApiError::bad_request(format!("malformed JSON body: {e}")))
    }
}

/// Query parameters; a malformed query is 400 with a JSON message.
pub struct ApiQuery<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned> axum::extract::FromRequestParts<S> for ApiQuery<T> {
    type Rejection = ApiError;

    async fn from_request_parts(
        parts: &mut axum::http::request::Parts,
        _state: &S,
    ) -> Result<Self, Self::Rejection> {
        axum::extract::Query::<T>::try_from_uri(&parts.uri)
            .map(|q| ApiQuery(q.0))
            .map_err(|e| ApiError::bad_request(format!("bad query: {}", e.body_text())))
    }
}

/// Path parameters; a malformed one is 400 (an unparsable slice index is 404:
/// no such slice).
pub struct ApiPath<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned + Send> axum::extract::FromRequestParts<S> for ApiPath<T> {
    type Rejection = ApiError;

    async fn from_request_parts(
        parts: &mut axum::http::request::Parts,
        state: &S,
    ) -> Result<Self, Self::Rejection> {
        axum::extract::Path::<T>::from_request_parts(parts, state)
            .await
            .map(|p| ApiPath(p.0))
            .map_err(|e| ApiError::bad_request(format!("bad path: {}", e.body_text())))
    }
}
