//! The error type of the io crate: every message is one line that names the file.
use std::path::{Path, PathBuf};
use thiserror::Error;

/// What can go wrong reading or writing a volume file.
///
/// Display is always one line and starts with the path, so a command-line
/// tool can print it as is.
#[derive(Debug, Error)]
pub enum IoError {
    /// The operating system refused to read the file (missing, permissions, ...).
    #[error("cannot read {}: {cause}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The cause (part of the message, so not also reported as a source:
        /// `anyhow`'s `{:#}` would print it twice).
        cause: std::io::Error,
    },
    /// The operating system refused to write the file (or its temporary file).
    #[error("cannot write {}: {cause}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The cause (part of the message).
        cause: std::io::Error,
    },
    /// The file is not a valid file of its format (truncated, inconsistent header, garbage).
    #[error("{}: {msg}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, one line.
        msg: String,
    },
    /// The file is valid but uses something we do not support (4D data, RGB,
    /// an unknown encoding, an unknown extension), or a write would lose data.
    #[error("{}: {msg}", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What is not supported, one line.
        msg: String,
    },
}

impl IoError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            IoError::Read { path, .. }
            | IoError::Write { path, .. }
            | IoError::Invalid { path, .. }
            | IoError::Unsupported { path, .. } => path,
        }
    }

    pub(crate) fn invalid(path: &Path, msg: impl Into<String>) -> IoError {
        IoError::Invalid {
            path: path.to_path_buf(),
            msg: one_line(msg.into()),
        }
    }

    pub(crate) fn unsupported(path: &Path, msg: impl Into<String>) -> IoError {
        IoError::Unsupported {
            path: path.to_path_buf(),
            msg: one_line(msg.into()),
        }
    }

    pub(crate) fn read(path: &Path, source: std::io::Error) -> IoError {
        // A decoder that runs out of input reports UnexpectedEof: that is a
        // truncated file, not an operating-system failure.
        if source.kind() == std::io::ErrorKind::UnexpectedEof {
            return IoError::invalid(path, "file is truncated (unexpected end of data)");
        }
        if source.kind() == std::io::ErrorKind::InvalidData
            || source.kind() == std::io::ErrorKind::InvalidInput
        {
            return IoError::invalid(path, format!("corrupt data: {source}"));
        }
        IoError::Read {
            path: path.to_path_buf(),
            cause: source,
        }
    }

    pub(crate) fn write(path: &Path, source: std::io::Error) -> IoError {
        IoError::Write {
            path: path.to_path_buf(),
            cause: source,
        }
    }
}

/// Longest message kept, in characters: a library may format a whole
/// hostile header into its error (a TIFF's 65535 bits-per-sample values).
const MAX_MESSAGE: usize = 300;

/// Collapse line breaks so a message from a library stays on one line, and
/// cut it to [`MAX_MESSAGE`] characters.
fn one_line(s: String) -> String {
    let s = if s.contains(['\n', '\r']) {
        s.split(['\n', '\r'])
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .collect::<Vec<_>>()
            .join("; ")
    } else {
        s
    };
    match s.char_indices().nth(MAX_MESSAGE) {
        Some((cut, _)) => format!("{}...", &s[..cut]),
        None => s,
    }
}
