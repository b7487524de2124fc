//! Where a reader's bytes come from: a file on disk, or bytes in memory (an
//! upload), and the rule for the data files a detached header names.
//!
//! A detached header (NRRD `data file:`, MetaImage `ElementDataFile`) may only
//! name a file inside the header's own folder: no absolute path, no `..`, no
//! symbolic link that leads out of the folder. The refusal is the same
//! whether or not the outside file exists, so an error never tells what is
//! outside. Bytes in memory have no folder: every external reference is
//! refused.
use crate::IoError;
use std::io::{BufRead, Cursor};
use std::path::{Component, Path, PathBuf};

/// The input of one read.
#[derive(Clone, Copy)]
pub(crate) struct Source<'a> {
    /// The file, or for bytes the name they were given (used in messages and
    /// to pick the format; never opened).
    pub name: &'a Path,
    /// The bytes, when reading from memory.
    pub bytes: Option<&'a [u8]>,
}

impl<'a> Source<'a> {
    /// A file on disk.
    pub fn file(path: &'a Path) -> Source<'a> {
        Source {
            name: path,
            bytes: None,
        }
    }

    /// Bytes in memory named `name`.
    pub fn memory(name: &'a Path, bytes: &'a [u8]) -> Source<'a> {
        Source {
            name,
            bytes: Some(bytes),
        }
    }

    /// A buffered reader over the whole input and its length in bytes.
    pub fn open(&self) -> Result<(Box<dyn BufRead + 'a>, u64), IoError> {
        match self.bytes {
            Some(b) => Ok((Box::new(Cursor::new(b)), b.len() as u64)),
            None => {
                let f = std::fs::File::open(self.name).map_err(|e| IoError::read(self.name, e))?;
                let len = f.metadata().map_err(|e| IoError::read(self.name, e))?.len();
                Ok((Box::new(std::io::BufReader::with_capacity(1 << 20, f)), len))
            }
        }
    }

    /// The data file a detached header names, opened: refused for bytes in
    /// memory and for anything outside the header's folder.
    pub fn data_file(
        &self,
        reference: &str,
    ) -> Result<(PathBuf, Box<dyn BufRead + 'a>, u64), IoError> {
        if self.bytes.is_some() {
            return Err(IoError::unsupported(
                self.name,
                format!(
                    "the header names a separate data file ('{reference}'); only a self-contained file can be read here (data attached to the header)"
                ),
            ));
        }
        let p = inside_folder(self.name, reference)?;
        let f = std::fs::File::open(&p).map_err(|e| IoError::read(&p, e))?;
        let meta = f.metadata().map_err(|e| IoError::read(&p, e))?;
        if !meta.is_file() {
            return Err(IoError::invalid(&p, "the data file is not a regular file"));
        }
        Ok((
            p,
            Box::new(std::io::BufReader::with_capacity(1 << 20, f)),
            meta.len(),
        ))
    }
}

/// The folder a file is in (`.` for a bare name).
pub(crate) fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// `reference` resolved against the folder of `header`, when it stays inside
/// that folder (symbolic links followed); else an error that says only that
/// the reference is outside.
pub(crate) fn inside_folder(header: &Path, reference: &str) -> Result<PathBuf, IoError> {
    let outside = || {
        IoError::unsupported(
            header,
            format!(
                "data file '{reference}' is not inside the header's folder (a detached data file must be beside the header or below it)"
            ),
        )
    };
    let rel = Path::new(reference);
    if reference.is_empty()
        || reference.contains('\0')
        || !rel
            .components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
        || !rel.components().any(|c| matches!(c, Component::Normal(_)))
    {
        return Err(outside());
    }
    let folder = folder_of(header);
    let candidate = folder.join(rel);
    confine(folder, &candidate, rel).ok_or_else(outside)?
}

/// `candidate` (= `folder` / `rel`) canonicalised when it is inside the
/// canonical `folder`; `None` when it leads outside (or, through a link,
/// to something that cannot be resolved); `Some(Err)` for an ordinary read
/// error of a path that is inside (a missing data file beside the header).
fn confine(folder: &Path, candidate: &Path, rel: &Path) -> Option<Result<PathBuf, IoError>> {
    let root = match std::fs::canonicalize(folder) {
        Ok(r) => r,
        Err(e) => return Some(Err(IoError::read(folder, e))),
    };
    match std::fs::canonicalize(candidate) {
        Ok(c) if c.starts_with(&root) && c != root => Some(Ok(c)),
        Ok(_) => None,
        Err(e) => {
            // A link on the way (to somewhere that does not exist) is not
            // followed, and not reported: only a plain missing file is.
            let mut p = folder.to_path_buf();
            for c in rel.components() {
                p.push(c);
                if std::fs::symlink_metadata(&p).is_ok_and(|m| m.file_type().is_symlink()) {
                    return None;
                }
            }
            Some(Err(IoError::read(candidate, e)))
        }
    }
}

/// True when the file `name` of `folder` resolves to a file inside `folder`
/// (a slice that is a link to somewhere else is not).
pub(crate) fn stays_inside(folder: &Path, name: &str) -> bool {
    matches!(
        confine(folder, &folder.join(name), Path::new(name)),
        Some(Ok(_))
    )
}
