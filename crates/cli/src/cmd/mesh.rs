//! `interslice mesh LABELS --out FILE.stl|.ply|.obj [--label N] [--ascii]
//! [--method M [--axis z|y|x] [--drawn FILE]]`
//!
//! Without `--method`: the closed marching-cubes surface of the label
//! volume's voxels equal to `--label N` (every non-zero voxel without it),
//! the iso-surface halfway between voxel centres.
//!
//! With `--method`: LABELS is a sparse label volume (as for `interpolate`)
//! and the mesh is that method's: a mesh-based method (`marching-cubes`,
//! `gaussian-splat`, `delaunay`, `unorganized-points`) writes the surface it
//! builds from the drawn slices (before the drawn slices are restored in
//! its voxel result); any other method writes the marching-cubes surface of
//! its interpolated mask. Every label (or only `--label N`) is meshed on its
//! own and the surfaces are written into one file.
//!
//! Coordinates are physical, in the volume's frame: voxel (0,0,0)'s centre
//! at the origin, axes along the direction cosines, units those of the
//! spacing. `.ply` is written binary unless `--ascii` is given.
use anyhow::{Context, Result, bail};
use interslice_core::mesh::TriMesh;
use interslice_core::{Axis, LabelVolume, Mask};
use interslice_interp::labels::DrawnLabels;
use interslice_interp::mesh::mask_surface;
use interslice_interp::{SparseMask, by_name};
use interslice_io::mesh::{MeshFormat, world_transform, write_mesh_as};
use std::path::PathBuf;

/// Arguments of `mesh`.
#[derive(clap::Args)]
pub struct Args {
    /// The label volume (with --method: the sparse one whose drawn slices carry the tracings).
    pub labels: PathBuf,
    /// Output mesh: .stl (binary), .ply (binary, or ASCII with --ascii) or .obj.
    #[arg(long)]
    pub out: PathBuf,
    /// Only this label (default: every non-zero voxel; with --method every label on its own). A number or a component's name.
    #[arg(long = "label", value_name = "L")]
    pub label_arg: Option<crate::label::LabelArg>,
    /// Mesh this method's interpolation of the sparse input (see `interpolate --list`).
    #[arg(long)]
    pub method: Option<String>,
    /// Axis the slices were drawn along (with --method).
    #[arg(long, default_value = "z")]
    pub axis: Axis,
    /// File listing the drawn slice indices, one integer a line (with --method).
    #[arg(long)]
    pub drawn: Option<PathBuf>,
    /// Write PLY as ASCII text instead of binary.
    #[arg(long)]
    pub ascii: bool,
}

/// Run `mesh`.
pub fn run(a: Args) -> Result<()> {
    let label = a
        .label_arg
        .as_ref()
        .map(|l| l.resolve(&[&a.labels]))
        .transpose()?;
    let mut format = MeshFormat::of_path(&a.out)?;
    if a.ascii {
        if format != MeshFormat::PlyBinary {
            bail!("--ascii applies to .ply output only");
        }
        format = MeshFormat::PlyAscii;
    }
    if a.method.is_none() && a.drawn.is_some() {
        bail!("--drawn needs --method");
    }
    let labels = interslice_io::read_volume(&a.labels)
        .with_context(|| format!("reading {}", a.labels.display()))?
        .to_labels()
        .with_context(|| format!("{} is not a label volume", a.labels.display()))?;
    let mut mesh = match &a.method {
        None => volume_surface(&labels, label, &a)?,
        Some(name) => method_surface(&labels, name, label, &a)?,
    };
    let (m, t) = world_transform(labels.geometry());
    mesh.transform(m, t);
    write_mesh_as(&a.out, &mesh, format).with_context(|| format!("writing {}", a.out.display()))?;
    let unit = labels.geometry().unit.symbol();
    println!(
        "{} triangles, area {:.6} {unit}², enclosed volume {:.6} {unit}³ -> {}",
        mesh.triangles.len(),
        mesh.area(),
        mesh.signed_volume().abs(),
        a.out.display()
    );
    Ok(())
}

/// The surface of the voxels equal to `label` (every non-zero voxel without one).
fn volume_surface(labels: &LabelVolume, label: Option<u16>, a: &Args) -> Result<TriMesh> {
    let mask: Mask = match label {
        Some(l) => labels.map(|v| v == l),
        None => labels.map(|v| v != 0),
    };
    if !mask.data().iter().any(|&v| v) {
        match label {
            Some(l) => bail!("label {l} does not occur in {}", a.labels.display()),
            None => bail!("{} has no non-zero voxel", a.labels.display()),
        }
    }
    Ok(mask_surface(&mask))
}

/// The mesh of method `name` for every label on the drawn slices (or `--label`).
fn method_surface(
    labels: &LabelVolume,
    name: &str,
    label: Option<u16>,
    a: &Args,
) -> Result<TriMesh> {
    let method = by_name(name)?;
    let drawn = super::interpolate::drawn_slices(labels, a.axis, a.drawn.as_deref())?;
    let drawn_labels = DrawnLabels::read(labels, a.axis, &drawn);
    let present = drawn_labels.labels();
    let wanted: Vec<u16> = match label {
        Some(l) if present.binary_search(&l).is_ok() => vec![l],
        Some(l) => bail!(
            "label {l} does not occur on the drawn slices along {}",
            a.axis
        ),
        None => present.to_vec(),
    };
    if wanted.is_empty() {
        bail!("the drawn slices along {} hold no label", a.axis);
    }
    let mut out = TriMesh::new();
    for l in wanted {
        let traced = drawn_labels.traced_mask(l);
        let input = SparseMask::new(&traced, a.axis, &drawn);
        let m = match method.surface_mesh(input) {
            Ok(Some(m)) => Ok(m),
            Ok(None) => method.interpolate(input).map(|r| mask_surface(&r)),
            Err(e) => Err(e),
        }
        .with_context(|| format!("method {} on label {l}", method.name()))?;
        out.append(&m);
    }
    Ok(out)
}
