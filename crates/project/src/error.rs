//! The error of project operations. It says what went wrong, not how to
//! answer it: the HTTP layer maps each kind to a status, the CLI prints it.
use interslice_core::CoreError;
use interslice_interp::InterpError;
use interslice_io::IoError;
use interslice_store::StoreError;

/// Why a project operation failed; every message is one line.
#[derive(Debug, thiserror::Error)]
pub enum ProjectError {
    /// The request is invalid (an unknown format, too few drawn slices, an
    /// unsafe path...).
    #[error("{0}")]
    Invalid(String),
    /// The thing asked for does not exist (an unknown cell, nothing traced).
    #[error("{0}")]
    NotFound(String),
    /// The user may not read it (the consensus is for reviewers).
    #[error("{0}")]
    Forbidden(String),
    /// A failure that is not the caller's (a temporary file, a reader bug).
    #[error("{0}")]
    Internal(String),
    /// The annotation database.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A volume, contour or metric computation (including a cancelled one).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// An interpolation method.
    #[error(transparent)]
    Interp(#[from] InterpError),
    /// Reading or writing a file format.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A file or folder of the project (creating an output folder...).
    #[error(transparent)]
    File(#[from] std::io::Error),
    /// An error with what was being done ("writing results.csv: ...").
    #[error("{context}: {cause}")]
    Context {
        /// What was being done.
        context: String,
        /// What went wrong.
        cause: Box<ProjectError>,
    },
}

impl ProjectError {
    /// An invalid request, its message kept on one line.
    pub fn invalid(m: impl Into<String>) -> ProjectError {
        ProjectError::Invalid(one_line(m))
    }
    /// Something missing.
    pub fn not_found(m: impl Into<String>) -> ProjectError {
        ProjectError::NotFound(one_line(m))
    }
    /// Something the user may not read.
    pub fn forbidden(m: impl Into<String>) -> ProjectError {
        ProjectError::Forbidden(one_line(m))
    }
    /// A failure that is not the caller's.
    pub fn internal(m: impl Into<String>) -> ProjectError {
        ProjectError::Internal(one_line(m))
    }
}

fn one_line(m: impl Into<String>) -> String {
    m.into().replace(['\n', '\r'], " ")
}

/// The result of project operations.
pub type Result<T, E = ProjectError> = std::result::Result<T, E>;

/// Say what was being done when an error happened (the library's
/// counterpart of `anyhow::Context`).
pub trait ResultExt<T> {
    /// Prefix the error with `context()`.
    fn context_with(self, context: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: Into<ProjectError>> ResultExt<T> for std::result::Result<T, E> {
    fn context_with(self, context: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| ProjectError::Context {
            context: context(),
            cause: Box::new(e.into()),
        })
    }
}
