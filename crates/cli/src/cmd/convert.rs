//! `interslice convert IN OUT`: any supported volume format to any other.
//! Values and geometry are copied unchanged; when the target cannot hold the
//! voxel type without loss (a float volume to PNG slices) nothing is written
//! and the command fails.
use anyhow::Context;
use interslice_core::components::Components;
use interslice_io::{Format, segmentation};
use std::path::PathBuf;

/// Arguments of `convert`.
#[derive(clap::Args)]
pub struct Args {
    /// The volume file, slice folder or DICOM folder to read.
    pub input: PathBuf,
    /// The file or folder to write; its extension picks the format (.nii,
    /// .nii.gz, .nrrd, .mha, .mhd, .tif; a folder, or a name without an
    /// extension, for PNG slices).
    pub output: PathBuf,
    #[command(flatten)]
    pub series: crate::series::SeriesArg,
    /// Store the volume as labels: integer values 0..=65535, written as u8
    /// when the largest is at most 255, else u16 (fails on other values).
    /// (Implied by a `.seg.nrrd` output, or an input that names its components.)
    #[arg(long)]
    pub labels: bool,
    /// With --labels: the components' names, comma-separated, valued 1, 2, …
    /// ("Tumour,Oedema"); written as a `.seg.nrrd`'s segments or as an ITK-SNAP
    /// label description file beside any other label volume. Default: the
    /// components the input declares (its segments, or its NAME.label.txt).
    #[arg(long, value_parser = parse_components)]
    pub components: Option<Components>,
}

fn parse_components(s: &str) -> Result<Components, String> {
    Components::from_names(s).map_err(|e| e.to_string())
}

/// Run `convert`.
pub fn run(args: Args) -> anyhow::Result<()> {
    // Check both formats before reading a possibly large input.
    Format::of_path(&args.input)?;
    let out_format = Format::of_path(&args.output)?;
    let to_seg_nrrd = segmentation::is_seg_nrrd(&args.output);
    // A segmentation read with its component table is written with it.
    let components = match args.components {
        Some(c) => c,
        None => segmentation::read_components(&args.input)?,
    };
    if args.labels || to_seg_nrrd || !components.is_empty() {
        let v = args.series.read_labels(&args.input)?;
        if to_seg_nrrd || !components.is_empty() {
            for f in segmentation::write_segmentation(&args.output, &v, &components)?
                .iter()
                .skip(1)
            {
                println!("wrote {}", f.display());
            }
        } else {
            interslice_io::write_labels(&args.output, &v)?;
        }
        let n = v.label_counts().len();
        let [nx, ny, nz] = v.dims();
        println!(
            "wrote {} ({}, {nx} x {ny} x {nz}, {n} labels)",
            args.output.display(),
            out_format.name()
        );
        return Ok(());
    }
    let v = args.series.read_volume(&args.input)?;
    interslice_io::write_volume(&args.output, &v).with_context(|| {
        format!(
            "cannot convert {} ({}) to {}",
            args.input.display(),
            v.type_name(),
            out_format.name()
        )
    })?;
    let [nx, ny, nz] = v.geometry().dims;
    println!(
        "wrote {} ({}, {}, {nx} x {ny} x {nz})",
        args.output.display(),
        out_format.name(),
        v.type_name()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};

    fn geometry() -> Geometry {
        let mut g = Geometry::new([4, 3, 2], [0.35, 0.35, 0.7], LengthUnit::Micrometre).unwrap();
        g.origin = [1.0, -2.0, 3.5];
        g
    }

    fn convert(
        input: &std::path::Path,
        output: &std::path::Path,
        labels: bool,
    ) -> anyhow::Result<()> {
        run(Args {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
            labels,
            components: None,
            series: Default::default(),
        })
    }

    #[test]
    fn converts_between_every_pair_of_formats() {
        let dir = tempfile::tempdir().unwrap();
        let g = geometry();
        let v = AnyVolume::U16(
            Volume::from_vec(g.clone(), (0..24).map(|x| x * 1000).collect()).unwrap(),
        );
        let names = [
            "a.nii", "a.nii.gz", "a.nrrd", "a.mha", "a.mhd", "a.tif", "a_slices",
        ];
        for (n, from) in names.iter().enumerate() {
            let src = dir.path().join(format!("src_{from}"));
            interslice_io::write_volume(&src, &v).unwrap();
            for to in names {
                let dst = dir.path().join(format!("from{n}_{to}"));
                convert(&src, &dst, false).unwrap();
                assert_eq!(
                    interslice_io::read_volume(&dst).unwrap(),
                    v,
                    "{from} -> {to}"
                );
            }
        }
    }

    #[test]
    fn refuses_a_lossy_target_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let src = dir.path().join("f.nrrd");
        let f = AnyVolume::F32(Volume::from_vec(geometry(), vec![0.5; 24]).unwrap());
        interslice_io::write_volume(&src, &f).unwrap();
        let out = dir.path().join("slices");
        let e = format!("{:#}", convert(&src, &out, false).unwrap_err());
        assert!(e.contains("f32") && !e.contains('\n'), "{e}");
        assert!(!out.exists());
        // As labels it fails too: 0.5 is not a label.
        assert!(convert(&src, &out, true).is_err());
        assert!(!out.exists());
    }

    #[test]
    fn labels_are_narrowed_to_u8() {
        let dir = tempfile::tempdir().unwrap();
        let src = dir.path().join("l.nii.gz");
        let v =
            AnyVolume::U16(Volume::from_vec(geometry(), (0..24).map(|x| x % 3).collect()).unwrap());
        interslice_io::write_volume(&src, &v).unwrap();
        let out = dir.path().join("l.nrrd");
        convert(&src, &out, true).unwrap();
        let back = interslice_io::read_volume(&out).unwrap();
        assert_eq!(back.type_name(), "u8");
        assert_eq!(back.to_labels().unwrap(), v.to_labels().unwrap());
    }

    #[test]
    fn missing_input_and_unknown_format() {
        let dir = tempfile::tempdir().unwrap();
        let e = format!(
            "{:#}",
            convert(
                &dir.path().join("none.nii"),
                &dir.path().join("x.nrrd"),
                false
            )
            .unwrap_err()
        );
        assert!(e.contains("none.nii") && e.contains("No such file"), "{e}");
        assert_eq!(e.matches("No such file").count(), 1, "{e}");
        let e = format!(
            "{:#}",
            convert(
                &dir.path().join("none.nii"),
                &dir.path().join("x.jpg"),
                false
            )
            .unwrap_err()
        );
        assert!(e.contains("x.jpg"), "{e}");
    }
}
