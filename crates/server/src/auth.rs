//! Sign-in: the session cookie, the current-user extractor, login/logout/me.
use crate::SharedState;
use crate::error::{ApiError, ApiJson};
use crate::openapi::ApiErrors;
use axum::extract::{FromRequestParts, State};
use axum::http::header::{COOKIE, SET_COOKIE};
use axum::http::request::Parts;
use axum::http::{HeaderMap, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use interslice_store::{Role, User};
use serde::{Deserialize, Serialize};

/// Name of the session cookie.
pub const COOKIE_NAME: &str = "interslice_session";

/// The session token in the request's cookies, if any.
pub fn session_token(headers: &HeaderMap) -> Option<String> {
    headers
        .get_all(COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .filter_map(|kv| kv.trim().split_once('='))
        .find(|(k, _)| *k == COOKIE_NAME)
        .map(|(_, v)| v.to_string())
}

/// The signed-in user; rejects with 401 when there is no valid session.
pub struct Auth(pub User);

impl FromRequestParts<SharedState> for Auth {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &SharedState) -> Result<Self, ApiError> {
        let token = session_token(&parts.headers)
            .ok_or_else(|| ApiError::unauthorized("not signed in (POST /api/login)"))?;
        // Tokens are 64 hex characters; anything else cannot be a session.
        if token.len() != 64 || !token.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(ApiError::unauthorized("not signed in (POST /api/login)"));
        }
        let (user, with_password) = state
            .store
            .session_user(&token)?
            .ok_or_else(|| ApiError::unauthorized("session expired; sign in again"))?;
        // On a password-protected server a password-less account (created on a
        // loopback run) cannot act, even with an old cookie.
        if state.auth_required && !user.has_password {
            return Err(ApiError::unauthorized(
                "this account has no password; ask for one with `interslice user add`",
            ));
        }
        // Nor can a session opened by name alone on a loopback run of the
        // same project: a name is not a proof of who is asking.
        if state.auth_required && !with_password {
            return Err(ApiError::unauthorized(
                "this session was opened without a password; sign in again",
            ));
        }
        Ok(Auth(user))
    }
}

/// Body of `POST /api/login`.
#[derive(Debug, Deserialize, utoipa::ToSchema)]
pub struct LoginBody {
    /// User name.
    pub name: String,
    /// Password (required when the server is not on loopback).
    #[serde(default)]
    pub password: Option<String>,
}

/// Who is signed in.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct Me {
    /// User name.
    pub name: String,
    /// "tracer" or "reviewer".
    pub role: String,
    /// Whether this server requires passwords.
    pub auth_required: bool,
}

fn cookie(token: &str, max_age: i64) -> HeaderValue {
    HeaderValue::from_str(&format!(
        "{COOKIE_NAME}={token}; Path=/; HttpOnly; SameSite=Strict; Max-Age={max_age}"
    ))
    .expect("cookie is ASCII")
}

/// `POST /api/login`.
#[utoipa::path(
    post,
    path = "/api/login",
    tag = "session",
    summary = "Sign in; sets the interslice_session cookie",
    request_body = LoginBody,
    responses(
        (status = 200, description = "success", content_type = "application/json"),
        ApiErrors,
    ),
)]
pub async fn login(
    State(state): State<SharedState>,
    ApiJson(body): ApiJson<LoginBody>,
) -> Result<Response, ApiError> {
    let st = state.clone();
    let user = tokio::task::spawn_blocking(move || -> Result<User, ApiError> {
        if st.auth_required {
            let pw = body
                .password
                .as_deref()
                .ok_or_else(|| ApiError::unauthorized("this server requires a password"))?;
            crate::limits::password(pw)?;
            Ok(st.store.verify_password(&body.name, pw)?)
        } else {
            Ok(st.store.ensure_user(&body.name)?)
        }
    })
    .await??;
    let token = state.store.create_session(user.id, state.auth_required)?;
    let mut resp = axum::Json(serde_json::json!({"name": user.name, "role": user.role.as_str()}))
        .into_response();
    resp.headers_mut()
        .insert(SET_COOKIE, cookie(&token, 30 * 24 * 3600));
    Ok(resp)
}

/// `POST /api/logout`.
#[utoipa::path(
    post,
    path = "/api/logout",
    tag = "session",
    summary = "Sign out",
    responses(
        (status = 204, description = "done"),
        ApiErrors,
    ),
)]
pub async fn logout(
    State(state): State<SharedState>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    if let Some(t) = session_token(&headers) {
        state.store.delete_session(&t)?;
    }
    let mut resp = StatusCode::NO_CONTENT.into_response();
    resp.headers_mut().insert(SET_COOKIE, cookie("", 0));
    Ok(resp)
}

/// `GET /api/me`.
#[utoipa::path(
    get,
    path = "/api/me",
    tag = "session",
    summary = "The signed-in user",
    responses(
        (status = 200, description = "success", content_type = "application/json", body = Me),
        ApiErrors,
    ),
)]
pub async fn me(State(state): State<SharedState>, Auth(user): Auth) -> axum::Json<Me> {
    axum::Json(Me {
        name: user.name,
        role: user.role.as_str().to_string(),
        auth_required: state.auth_required,
    })
}

/// The user whose tracings to read: the signed-in user, or with `?user=` another
/// user (reviewers only; 403 otherwise, 404 if unknown).
pub fn reader_target(
    state: &SharedState,
    me: &User,
    other: Option<&str>,
) -> Result<User, ApiError> {
    match other {
        None => Ok(me.clone()),
        Some(name) if name == me.name => Ok(me.clone()),
        Some(name) => {
            if me.role != Role::Reviewer {
                return Err(ApiError::forbidden(format!(
                    "only reviewers may read another user's tracings ('{name}')"
                )));
            }
            state
                .store
                .user(name)?
                .ok_or_else(|| ApiError::not_found(format!("unknown user '{name}'")))
        }
    }
}
