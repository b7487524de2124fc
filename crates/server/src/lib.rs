//! The tracing server: the HTTP API of `docs/API.md` over a project folder and
//! its annotation database, plus the embedded web UI.
//!
//! A project folder holds the cells (volume files or folders of slices); the
//! database lives at `DIR/.interslice/annotations.sqlite`. Volumes are read
//! lazily and kept in a small LRU ([`cell_cache::CellCache`]); slices are served as
//! raw little-endian bytes straight from memory.
//!
//! Users: on a loopback bind a name is enough (the user is created on first
//! login); on any other bind, accounts with argon2 passwords are required
//! (`interslice user add`). Sessions are random 256-bit tokens in an HttpOnly,
//! SameSite=Strict cookie; a session remembers whether a password opened it,
//! and a server that requires passwords refuses the others. A loopback server
//! answers only loopback `Host` names ([`host`]). A user reads and writes only
//! their own tracings; a reviewer also reads everyone's. Long computations
//! stop when their request is gone ([`jobs`]).
#![deny(missing_docs)]

pub mod api;
pub mod auth;
pub mod cell_cache;
pub mod error;
pub mod host;
pub mod jobs;
pub mod limits;
pub mod openapi;
pub mod web;

use anyhow::Context as _;
use axum::Router;
use interslice_project::cells::LoadedCell;
use interslice_store::Store;
use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, RwLock};
use std::time::Duration;

/// How the server runs.
#[derive(Debug, Clone)]
pub struct Config {
    /// The project folder.
    pub dir: PathBuf,
    /// Address to listen on (port 0 picks a free port).
    pub bind: SocketAddr,
    /// The database file (default `DIR/.interslice/annotations.sqlite`).
    pub db: Option<PathBuf>,
    /// Force login with passwords even on loopback (default: only off loopback).
    pub require_login: bool,
    /// Volumes kept in memory.
    pub cache_cells: usize,
    /// Largest request body accepted, bytes (larger → 413).
    pub body_limit: usize,
    /// Time limit of one request (interpolation of a large cell included);
    /// its computation is stopped when it runs out.
    pub timeout: Duration,
    /// The components to trace: written to the project file and made the
    /// project's labels. None: the project file's, else the database's
    /// (a new database starts with the cell-CT set).
    pub components: Option<interslice_core::components::Components>,
    /// URLs a reverse proxy serves this server under (`--public-url`): their
    /// host names are answered besides the loopback ones on a loopback bind.
    pub public_urls: Vec<String>,
}

impl Config {
    /// Defaults for a project folder: 127.0.0.1:8080, 4 cached volumes, 16 MiB
    /// bodies, 300 s per request.
    pub fn new(dir: impl Into<PathBuf>) -> Config {
        Config {
            dir: dir.into(),
            bind: SocketAddr::from(([127, 0, 0, 1], 8080)),
            db: None,
            require_login: false,
            cache_cells: 4,
            body_limit: 16 << 20,
            timeout: Duration::from_secs(300),
            components: None,
            public_urls: Vec::new(),
        }
    }
}

/// Shared state of the handlers.
pub struct AppState {
    /// The project folder.
    pub dir: PathBuf,
    /// The annotation database.
    pub store: Arc<Store>,
    /// Cells found in the folder, by id.
    pub cells: RwLock<BTreeMap<String, PathBuf>>,
    /// Loaded volumes.
    pub cache: cell_cache::CellCache,
    /// Whether passwords are required.
    pub auth_required: bool,
    /// Interpolated ground truths, for overlays and evaluation.
    pub gt_cache: interslice_project::groundtruth::GtCache,
    /// Live previews of interpolations, in memory per user.
    pub previews: interslice_project::previews::PreviewCache,
    /// Running computations; cancelled on shutdown.
    pub jobs: Arc<jobs::Jobs>,
    /// Which `Host` names are answered.
    pub hosts: Arc<host::HostPolicy>,
}

/// The state as handlers get it.
pub type SharedState = Arc<AppState>;

impl AppState {
    /// Open the database and register the cells of `config.dir`.
    pub fn open(config: &Config) -> anyhow::Result<SharedState> {
        let dir = config.dir.clone();
        let store =
            interslice_project::open_store(&dir, config.db.as_deref(), config.components.as_ref())?;
        let auth_required = config.require_login || !config.bind.ip().is_loopback();
        let extra = config
            .public_urls
            .iter()
            .map(|u| host::public_url_host(u))
            .collect::<Result<Vec<_>, _>>()
            .map_err(anyhow::Error::msg)?;
        let hosts = Arc::new(host::HostPolicy {
            loopback_only: config.bind.ip().is_loopback(),
            extra,
        });
        let state = Arc::new(AppState {
            dir,
            store: Arc::new(store),
            cells: RwLock::new(BTreeMap::new()),
            cache: cell_cache::CellCache::new(config.cache_cells),
            auth_required,
            gt_cache: interslice_project::groundtruth::GtCache::new(4),
            previews: Default::default(),
            jobs: Arc::new(jobs::Jobs::default()),
            hosts,
        });
        state.rescan().context("cannot list the project folder")?;
        Ok(state)
    }

    /// Re-read the folder's cells and register new ones in the database.
    pub fn rescan(&self) -> anyhow::Result<()> {
        let known = self.cells.read().unwrap_or_else(|e| e.into_inner()).clone();
        let found = interslice_project::register_cells(&self.store, &self.dir, &known)?;
        *self.cells.write().unwrap_or_else(|e| e.into_inner()) = found;
        Ok(())
    }

    /// The ids of the cells found at the last scan, in order.
    pub fn cell_ids(&self) -> Vec<String> {
        let cells = self.cells.read().unwrap_or_else(|e| e.into_inner());
        cells.keys().cloned().collect()
    }

    /// The path of a cell, or 400 for an unsafe id and 404 for an unknown one.
    pub fn cell_path(&self, id: &str) -> Result<PathBuf, error::ApiError> {
        let cells = self.cells.read().unwrap_or_else(|e| e.into_inner());
        Ok(interslice_project::cell_path(&cells, id)?)
    }

    /// The loaded volume of a cell.
    pub async fn cell(&self, id: &str) -> Result<Arc<LoadedCell>, error::ApiError> {
        let path = self.cell_path(id)?;
        let store = self.store.clone();
        let cid = id.to_string();
        self.cache
            .get(id, move || {
                let loaded = LoadedCell::load(&path)?;
                // Remember what the cell is; a changed hash means the file was
                // replaced under existing tracings (kept, but worth a warning).
                if let Ok(Some(old)) = store.set_cell_content(
                    &cid,
                    &loaded.content_hash,
                    loaded.volume.geometry(),
                    loaded.dtype(),
                ) {
                    eprintln!(
                        "warning: cell '{cid}' changed on disk (content hash {old} -> {})",
                        loaded.content_hash
                    );
                }
                Ok(loaded)
            })
            .await
    }
}

/// The full application: API, OpenAPI document and web UI, with the body
/// limit, request timeout (408, its computation stopped), `Host` check and
/// panic catcher.
pub fn app(state: SharedState, config: &Config) -> Router {
    use tower_http::catch_panic::CatchPanicLayer;
    let limit = config.timeout;
    let hosts = state.hosts.clone();
    api::router()
        .0
        .merge(web::router())
        .layer(axum::extract::DefaultBodyLimit::max(config.body_limit))
        .layer(axum::middleware::from_fn(move |req, next| {
            jobs::timeout(limit, req, next)
        }))
        .layer(axum::middleware::from_fn(close_after_refused_body))
        .layer(axum::middleware::from_fn(move |req, next| {
            host::check(hosts.clone(), req, next)
        }))
        .layer(CatchPanicLayer::custom(
            |_err: Box<dyn std::any::Any + Send>| {
                error::error_response(
                    axum::http::StatusCode::INTERNAL_SERVER_ERROR,
                    "internal error (a bug; the request was not applied)",
                )
            },
        ))
        .with_state(state)
}

/// An error answered to a request that carried a body may leave that body
/// unread (a 401 from the sign-in check, a 413): the connection then cannot
/// carry another request, so say `Connection: close` and a keep-alive client
/// opens a fresh one instead of sending its next request into a closed socket.
async fn close_after_refused_body(
    req: axum::extract::Request,
    next: axum::middleware::Next,
) -> axum::response::Response {
    use axum::http::header::{CONNECTION, CONTENT_LENGTH, TRANSFER_ENCODING};
    let headers = req.headers();
    let has_body = headers.contains_key(TRANSFER_ENCODING)
        || headers
            .get(CONTENT_LENGTH)
            .is_some_and(|v| v.as_bytes() != b"0");
    let mut resp = next.run(req).await;
    let status = resp.status();
    if has_body && (status.is_client_error() || status.is_server_error()) {
        resp.headers_mut()
            .insert(CONNECTION, axum::http::HeaderValue::from_static("close"));
    }
    resp
}

/// How long a stopping server waits for its requests to end.
pub const SHUTDOWN_GRACE: Duration = Duration::from_secs(3);

/// Bind, call `ready` with the bound address, and serve until Ctrl-C /
/// SIGTERM. On the signal the server stops accepting, cancels every running
/// computation and returns once its requests have ended, or after
/// [`SHUTDOWN_GRACE`] whatever still runs (the caller then ends the process
/// without waiting for blocking threads).
pub async fn run(config: Config, ready: impl FnOnce(SocketAddr, &AppState)) -> anyhow::Result<()> {
    let state = AppState::open(&config)?;
    let listener = tokio::net::TcpListener::bind(config.bind)
        .await
        .with_context(|| format!("cannot listen on {}", config.bind))?;
    let addr = listener.local_addr()?;
    ready(addr, &state);
    let jobs = state.jobs.clone();
    let app = app(state, &config);
    let stopping = Arc::new(tokio::sync::Notify::new());
    let told = stopping.clone();
    let server = axum::serve(listener, app).with_graceful_shutdown(async move {
        shutdown_signal().await;
        jobs.shutdown();
        told.notify_one();
    });
    tokio::select! {
        r = server => r.context("server failed"),
        _ = async {
            stopping.notified().await;
            tokio::time::sleep(SHUTDOWN_GRACE).await;
        } => {
            eprintln!("interslice: stopped with requests still running");
            Ok(())
        }
    }
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! { _ = ctrl_c => {}, _ = term => {} }
}

/// A server running on its own thread (tests, benchmarks); stops when dropped.
pub struct RunningServer {
    /// The bound address.
    pub addr: SocketAddr,
    /// The state (database access for checks).
    pub state: SharedState,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl RunningServer {
    /// `http://ADDR`.
    pub fn url(&self) -> String {
        format!("http://{}", self.addr)
    }
}

impl Drop for RunningServer {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Start a server on a background thread with its own runtime.
pub fn spawn(config: Config) -> anyhow::Result<RunningServer> {
    let state = AppState::open(&config)?;
    let std_listener = std::net::TcpListener::bind(config.bind)
        .with_context(|| format!("cannot listen on {}", config.bind))?;
    std_listener.set_nonblocking(true)?;
    let addr = std_listener.local_addr()?;
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let app = app(state.clone(), &config);
    let jobs = state.jobs.clone();
    let thread = std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .expect("tokio runtime");
        rt.block_on(async move {
            let listener = tokio::net::TcpListener::from_std(std_listener).expect("listener");
            let _ = axum::serve(listener, app)
                .with_graceful_shutdown(async move {
                    let _ = rx.await;
                    jobs.shutdown();
                })
                .await;
        });
    });
    Ok(RunningServer {
        addr,
        state,
        stop: Some(tx),
        thread: Some(thread),
    })
}

/// The project folder's default database path.
pub fn default_db(dir: &Path) -> PathBuf {
    interslice_store::default_db_path(dir)
}
