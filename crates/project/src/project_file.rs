//! The project file, `DIR/interslice.toml`: what a project folder declares
//! about itself. Today that is its components (the structures traced, their
//! label values and colours), so a brain MRI project offers "Tumour, Oedema"
//! and not the cell-CT set:
//!
//! ```toml
//! [[components]]
//! value = 1
//! name = "Tumour"
//! color = "#e6194b"
//! ```
//!
//! `value` and `color` are optional (1, 2, … in order; palette colours).
use crate::error::ProjectError;
use interslice_core::components::{Component, Components, parse_hex_color};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The project file's name inside the project folder.
pub const FILE_NAME: &str = "interslice.toml";
/// Largest project file read.
const MAX_BYTES: u64 = 1 << 20;

/// The file's contents.
#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProjectFile {
    #[serde(default)]
    components: Vec<ComponentEntry>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ComponentEntry {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    value: Option<u16>,
    name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    color: Option<String>,
}

/// The project file of a folder.
pub fn path_in(dir: &Path) -> PathBuf {
    dir.join(FILE_NAME)
}

/// The components a project folder declares, or None when it has no project
/// file (or the file declares none).
pub fn read_components(dir: &Path) -> Result<Option<Components>, ProjectError> {
    use std::io::Read;
    let path = path_in(dir);
    let at = |e: &dyn std::fmt::Display| ProjectError::invalid(format!("{}: {e}", path.display()));
    let cannot_read =
        |e: std::io::Error| ProjectError::invalid(format!("cannot read {}: {e}", path.display()));
    let f = match std::fs::File::open(&path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(cannot_read(e)),
    };
    let mut text = String::new();
    f.take(MAX_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(cannot_read)?;
    if text.len() as u64 > MAX_BYTES {
        return Err(at(&"over 1 MiB"));
    }
    let file: ProjectFile =
        toml::from_str(&text).map_err(|e| at(&e.message().replace('\n', " ")))?;
    if file.components.is_empty() {
        return Ok(None);
    }
    let mut list = Vec::new();
    for (n, c) in file.components.into_iter().enumerate() {
        let value = match c.value {
            Some(v) => v,
            None => u16::try_from(n + 1)
                .map_err(|e| ProjectError::invalid(format!("too many components: {e}")))?,
        };
        let mut comp = Component::new(value, c.name);
        if let Some(col) = c.color {
            comp.color = parse_hex_color(&col).map_err(|e| at(&e))?;
        }
        list.push(comp);
    }
    Ok(Some(Components::new(list).map_err(|e| at(&e))?))
}

/// Write the components into the folder's project file (atomically).
pub fn write_components(dir: &Path, components: &Components) -> Result<(), ProjectError> {
    let file = ProjectFile {
        components: components
            .as_slice()
            .iter()
            .map(|c| ComponentEntry {
                value: Some(c.value),
                name: c.name.clone(),
                color: Some(c.hex_color()),
            })
            .collect(),
    };
    let toml = toml::to_string(&file).map_err(|e| ProjectError::internal(e.to_string()))?;
    let text = format!(
        "# interslice project: the components traced here (label value, name, colour).\n{toml}"
    );
    let path = path_in(dir);
    interslice_io::raw::write_atomic(&path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn components_round_trip_through_the_project_file() {
        let dir = tempfile::tempdir().unwrap();
        assert!(read_components(dir.path()).unwrap().is_none());
        let c = Components::from_names("Tumour,Oedema").unwrap();
        write_components(dir.path(), &c).unwrap();
        assert_eq!(read_components(dir.path()).unwrap().unwrap(), c);
    }

    #[test]
    fn a_hand_written_file_may_omit_values_and_colours() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            path_in(dir.path()),
            "[[components]]\nname = \"Grey matter\"\n[[components]]\nname = \"White matter\"\ncolor = \"#FFFFFF\"\n",
        )
        .unwrap();
        let c = read_components(dir.path()).unwrap().unwrap();
        assert_eq!(c.resolve("white matter").unwrap(), 2);
        assert_eq!(c.by_value(2).unwrap().color, [255, 255, 255]);
    }

    #[test]
    fn bad_files_are_one_line_errors() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(path_in(dir.path()), "[[components]]\nnom = \"x\"\n").unwrap();
        let e = format!("{:#}", read_components(dir.path()).unwrap_err());
        assert!(e.contains("interslice.toml"), "{e}");
        assert_eq!(e.lines().count(), 1, "{e}");
        std::fs::write(
            path_in(dir.path()),
            "[[components]]\nname = \"a\"\n[[components]]\nname = \"A\"\n",
        )
        .unwrap();
        let e = format!("{:#}", read_components(dir.path()).unwrap_err());
        assert!(e.contains("declared twice"), "{e}");
    }
}
