//! `interslice export DIR --cell NAME --user U [--label L] [--method M] --out FILE`:
//! a user's interpolated label volume of one cell, from the command line.
//!
//! The same computation as the server's export: each label the user traced is
//! interpolated from its drawn slices of every orientation, then painted in
//! ascending label order. `--out` ending in `.contours.json` writes the user's
//! contours instead.
use anyhow::{Context, Result, bail};
use interslice_project::cells::LoadedCell;
use std::path::PathBuf;

/// Arguments of `export`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub project: crate::project::ProjectArgs,
    /// The cell id (its file name without extension, as the server lists it).
    #[arg(long)]
    pub cell: String,
    /// Whose tracing.
    #[arg(long)]
    pub user: String,
    /// Only this label (default: every label the user traced). A number or a component's name.
    #[arg(long = "label", value_name = "L")]
    pub label_arg: Option<crate::label::LabelArg>,
    /// Interpolation method (`interslice interpolate --list`; default the best).
    #[arg(long)]
    pub method: Option<String>,
    /// Output file: a label volume (.nii.gz, .nii, .nrrd, .mha, .tif; an ITK-SNAP
    /// label description NAME.label.txt is written beside it), a 3D Slicer
    /// segmentation (.seg.nrrd, with segment names and colours) or `.contours.json`.
    #[arg(long)]
    pub out: PathBuf,
}

/// Run the command.
pub fn run(a: Args) -> Result<()> {
    let store = a.project.open()?;
    let cells = interslice_project::register_cells(&store, &a.project.dir, &Default::default())
        .context("cannot list the project folder")?;
    let label = crate::project::resolve_label(&store, a.label_arg.as_ref())?;
    let path = interslice_project::cell_path(&cells, &a.cell)?;
    let user = store
        .user(&a.user)?
        .with_context(|| format!("no user '{}' in this project", a.user))?;
    let cell = LoadedCell::load(&path).with_context(|| format!("reading {}", path.display()))?;
    let geometry = cell.volume.geometry();
    let name = a.out.to_string_lossy().to_ascii_lowercase();
    if name.ends_with(".contours.json") || name.ends_with(".json") {
        let text = interslice_project::export::contours_json(&store, &a.cell, geometry, &user)?;
        interslice_io::raw::write_atomic(&a.out, |w| {
            use std::io::Write as _;
            w.write_all(text.as_bytes())
        })
        .with_context(|| format!("writing {}", a.out.display()))?;
    } else {
        let method = interslice_project::methods::method_by_name(a.method.as_deref())?;
        let labels = interslice_project::groundtruth::user_label_volume(
            &store,
            geometry,
            &a.cell,
            user.id,
            method.as_ref(),
            label,
            &interslice_core::Cancel::new(),
        )?;
        if labels.data().iter().all(|&v| v == 0) {
            bail!("the interpolated volume is empty");
        }
        // A .seg.nrrd carries the component table; any other label volume
        // gets an ITK-SNAP label description file beside it.
        let written =
            interslice_io::segmentation::write_segmentation(&a.out, &labels, &store.components()?)
                .with_context(|| format!("writing {}", a.out.display()))?;
        for f in written.iter().skip(1) {
            eprintln!("wrote {}", f.display());
        }
    }
    eprintln!("wrote {}", a.out.display());
    Ok(())
}
