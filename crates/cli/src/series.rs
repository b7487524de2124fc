//! `--series UID`: the one definition of the option that chooses a DICOM
//! series, flattened into every command that reads volumes.
use interslice_core::{AnyVolume, LabelVolume};
use interslice_io::{Format, IoError};
use std::path::Path;

/// Chooses the series of a DICOM folder that holds several.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SeriesArg {
    /// The SeriesInstanceUID to read when an input is a DICOM folder holding
    /// several series (`interslice info DIR` lists them).
    #[arg(long, value_name = "UID")]
    pub series: Option<String>,
}

impl SeriesArg {
    /// Read a volume (the chosen series of a DICOM input).
    pub fn read_volume(&self, path: &Path) -> Result<AnyVolume, IoError> {
        interslice_io::read_volume_series(path, self.series.as_deref())
    }

    /// Read a label volume (the chosen series of a DICOM input).
    pub fn read_labels(&self, path: &Path) -> Result<LabelVolume, IoError> {
        interslice_io::read_labels_series(path, self.series.as_deref())
    }

    /// For commands with several inputs: the series applies to the DICOM
    /// ones; errs when `--series` is given and none of `paths` is DICOM.
    pub fn for_inputs(&self, paths: &[&Path]) -> anyhow::Result<Vec<SeriesArg>> {
        let is_dicom = |p: &&Path| matches!(Format::of_path(p), Ok(Format::Dicom));
        if self.series.is_some() && !paths.iter().any(is_dicom) {
            anyhow::bail!("--series chooses a DICOM series, but no input is a DICOM folder");
        }
        Ok(paths
            .iter()
            .map(|p| {
                if is_dicom(p) {
                    self.clone()
                } else {
                    SeriesArg::default()
                }
            })
            .collect())
    }
}
