//! `--label` on the command line: a label value (`2`) or a component's name
//! (`Nucleus`, `"Nucleolus 1"`, case-insensitive). Names are looked up in the
//! component table the files declare (a `.seg.nrrd`'s segments, or the
//! ITK-SNAP label description file beside a label volume), or in a project's
//! components for the commands that work on a project folder.
use anyhow::{Context, Result, bail};
use interslice_core::components::{Components, MAX_NAME_CHARS};
use std::path::Path;
use std::str::FromStr;

/// A label as typed: a number or a name, resolved to a value later, once
/// the files that name components are known.
#[derive(Debug, Clone)]
pub struct LabelArg(String);

impl FromStr for LabelArg {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim();
        if t.is_empty() || t.chars().count() > MAX_NAME_CHARS {
            return Err(format!(
                "a label is a number or a component name of 1 to {MAX_NAME_CHARS} characters"
            ));
        }
        if t.chars().all(|c| c.is_ascii_digit()) && t.parse::<u16>().is_err() {
            return Err(format!("label {t} is out of range (0..=65535)"));
        }
        Ok(LabelArg(t.to_string()))
    }
}

impl LabelArg {
    /// The number, when the label was given as one.
    fn number(&self) -> Option<u16> {
        self.0.parse().ok()
    }

    /// Resolve against a known component table.
    pub fn resolve_in(&self, components: &Components) -> Result<u16> {
        Ok(components.resolve(&self.0)?)
    }

    /// Resolve a name against the components declared by the first of
    /// `files` that names it (numbers need no file).
    pub fn resolve(&self, files: &[&Path]) -> Result<u16> {
        if let Some(n) = self.number() {
            return Ok(n);
        }
        let mut declared = Components::default();
        for f in files {
            let c = interslice_io::segmentation::read_components(f)
                .with_context(|| format!("resolving --label '{}'", self.0))?;
            if let Some(hit) = c.by_name(&self.0) {
                return Ok(hit.value);
            }
            if declared.is_empty() {
                declared = c;
            }
        }
        if declared.is_empty() {
            bail!(
                "--label '{}': these files name no components (a .seg.nrrd or a NAME.label.txt beside the volume names them); give the label's number",
                self.0
            );
        }
        Ok(declared.resolve(&self.0)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_names_parse_and_bad_ones_do_not() {
        assert_eq!(LabelArg::from_str("2").unwrap().number(), Some(2));
        assert_eq!(LabelArg::from_str(" Nucleus ").unwrap().0, "Nucleus");
        assert!(LabelArg::from_str("70000").is_err());
        assert!(LabelArg::from_str("").is_err());
        let c = Components::cell_ct();
        assert_eq!(
            LabelArg::from_str("nucleolus 1")
                .unwrap()
                .resolve_in(&c)
                .unwrap(),
            3
        );
    }
}
