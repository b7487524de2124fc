//! `interslice info FILE [--json] [--series UID]`: format, dims, spacing + unit, origin,
//! direction, voxel type, value range and, for label volumes, every label
//! with its voxel count and physical volume.
use anyhow::Context;
use interslice_core::AnyVolume;
use serde_json::{Value, json};
use std::path::PathBuf;

/// An integer volume with at most this many distinct values (0 included) is
/// reported as a label volume unless `--labels` says so explicitly.
const MAX_AUTO_LABELS: usize = 64;

/// Arguments of `info`.
#[derive(clap::Args)]
pub struct Args {
    /// The volume file, slice folder or DICOM folder.
    pub input: PathBuf,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// List every non-zero value as a label even when there are many.
    #[arg(long)]
    pub labels: bool,
    #[command(flatten)]
    pub series: crate::series::SeriesArg,
}

/// Voxel counts of every distinct integer value, or None for float volumes.
fn value_counts(v: &AnyVolume) -> Option<Vec<(i64, u64)>> {
    let mut counts = vec![0u64; 65536];
    let offset: i64 = match v {
        AnyVolume::U8(v) => {
            v.data().iter().for_each(|&x| counts[x as usize] += 1);
            0
        }
        AnyVolume::U16(v) => {
            v.data().iter().for_each(|&x| counts[x as usize] += 1);
            0
        }
        AnyVolume::I16(v) => {
            v.data()
                .iter()
                .for_each(|&x| counts[(i32::from(x) + 32768) as usize] += 1);
            -32768
        }
        AnyVolume::F32(_) => return None,
    };
    Some(
        counts
            .into_iter()
            .enumerate()
            .filter(|&(_, c)| c > 0)
            .map(|(i, c)| (i as i64 + offset, c))
            .collect(),
    )
}

/// A number for people: at most 9 significant digits, so float noise such
/// as `2.0999999999999996` prints as `2.1`.
fn fmt_num(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{x:.8e}").parse().unwrap_or(x);
    format!("{}", rounded + 0.0)
}

/// Run `info`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let format = interslice_io::Format::of_path(&args.input)?;
    if format == interslice_io::Format::Dicom && args.series.series.is_none() {
        let series = interslice_io::dicom::list_series(&args.input)?;
        if series.len() > 1 {
            return print_series(&args, &series);
        }
    }
    let v = args.series.read_volume(&args.input)?;
    let g = v.geometry().clone();
    let (min, max) = v.min_max();
    let unit = g.unit.symbol();
    let counts = value_counts(&v);
    let distinct = counts.as_ref().map(Vec::len);
    let labels: Option<Vec<(i64, u64)>> = counts.and_then(|c| {
        let all_labels = c.iter().all(|&(val, _)| val >= 0);
        if all_labels && (args.labels || c.len() <= MAX_AUTO_LABELS) {
            Some(c.into_iter().filter(|&(val, _)| val != 0).collect())
        } else {
            None
        }
    });
    if args.labels && labels.is_none() {
        anyhow::bail!(
            "{}: a {} volume{} cannot be listed as labels",
            args.input.display(),
            v.type_name(),
            if v.type_name() == "f32" {
                ""
            } else {
                " with negative values"
            }
        );
    }
    let voxel_volume = g.voxel_volume();
    if args.json {
        let labels_json: Value = match &labels {
            Some(l) => Value::Array(
                l.iter()
                    .map(|&(label, n)| json!({"label": label, "voxels": n, "volume": n as f64 * voxel_volume}))
                    .collect(),
            ),
            None => Value::Null,
        };
        let out = json!({
            "path": args.input.display().to_string(),
            "format": format.name(),
            "dims": g.dims,
            "spacing": g.spacing,
            "unit": unit,
            "origin": g.origin,
            "direction": g.direction,
            "dtype": v.type_name(),
            "min": min,
            "max": max,
            "voxels": g.len(),
            "voxel_volume": voxel_volume,
            "volume_unit": format!("{unit}³"),
            "distinct_values": distinct,
            "labels": labels_json,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&out).context("cannot format JSON")?
        );
        return Ok(());
    }
    let [nx, ny, nz] = g.dims;
    let [sx, sy, sz] = g.spacing;
    println!("file:       {}", args.input.display());
    println!("format:     {}", format.name());
    println!("dims:       {nx} x {ny} x {nz}  ({} voxels)", g.len());
    println!(
        "spacing:    {} x {} x {} {unit}",
        fmt_num(sx),
        fmt_num(sy),
        fmt_num(sz)
    );
    println!(
        "origin:     ({}, {}, {}) {unit}",
        fmt_num(g.origin[0]),
        fmt_num(g.origin[1]),
        fmt_num(g.origin[2])
    );
    let d = g.direction;
    println!(
        "direction:  [{} {} {}; {} {} {}; {} {} {}]",
        fmt_num(d[0][0]),
        fmt_num(d[0][1]),
        fmt_num(d[0][2]),
        fmt_num(d[1][0]),
        fmt_num(d[1][1]),
        fmt_num(d[1][2]),
        fmt_num(d[2][0]),
        fmt_num(d[2][1]),
        fmt_num(d[2][2])
    );
    println!("type:       {}", v.type_name());
    println!("range:      {} .. {}", fmt_num(min), fmt_num(max));
    println!(
        "size:       {} x {} x {} {unit}  (voxel {} {unit}³)",
        fmt_num(nx as f64 * sx),
        fmt_num(ny as f64 * sy),
        fmt_num(nz as f64 * sz),
        fmt_num(voxel_volume)
    );
    if labels.is_none()
        && let Some(n) = distinct
    {
        println!(
            "labels:     not listed ({n} distinct values; --labels lists them when none is negative)"
        );
    }
    if let Some(labels) = labels {
        println!("labels:     {}", labels.len());
        if !labels.is_empty() {
            println!(
                "  {:>6}  {:>12}  {:>14}",
                "label",
                "voxels",
                format!("volume ({unit}³)")
            );
            for (label, n) in labels {
                println!(
                    "  {label:>6}  {n:>12}  {:>14}",
                    fmt_num(n as f64 * voxel_volume)
                );
            }
        }
    }
    Ok(())
}

/// A DICOM folder with several series: list them and say how to choose one.
fn print_series(args: &Args, series: &[interslice_io::dicom::SeriesInfo]) -> anyhow::Result<()> {
    if args.json {
        let list: Vec<Value> = series
            .iter()
            .map(|s| {
                json!({"uid": s.uid, "description": s.description, "number": s.number,
                       "modality": s.modality, "files": s.files, "dims": s.dims})
            })
            .collect();
        let out =
            json!({"path": args.input.display().to_string(), "format": "DICOM", "series": list});
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("file:       {}", args.input.display());
    println!("format:     DICOM, {} series", series.len());
    println!(
        "  {:<8} {:<16} {:<24} {:>6}  description",
        "modality", "dims", "series UID", "files"
    );
    for s in series {
        let [x, y, z] = s.dims;
        println!(
            "  {:<8} {:<16} {:<24} {:>6}  {}",
            s.modality,
            format!("{x} x {y} x {z}"),
            s.uid,
            s.files,
            s.description
        );
    }
    println!("choose one with --series UID");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{Geometry, LengthUnit, Volume};

    #[test]
    fn numbers_print_without_float_noise() {
        assert_eq!(fmt_num(3.0 * 0.7), "2.1");
        assert_eq!(fmt_num(0.35 * 0.35 * 0.35), "0.042875");
        assert_eq!(fmt_num(1e-9), "0.000000001");
        assert_eq!(fmt_num(12345.0), "12345");
        assert_eq!(fmt_num(-0.0), "0");
    }

    #[test]
    fn counts_every_integer_value() {
        let g = Geometry::new([2, 2, 1], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let v = AnyVolume::I16(Volume::from_vec(g.clone(), vec![-3, 0, 0, 7]).unwrap());
        assert_eq!(value_counts(&v), Some(vec![(-3, 1), (0, 2), (7, 1)]));
        let f = AnyVolume::F32(Volume::from_vec(g, vec![0.0; 4]).unwrap());
        assert_eq!(value_counts(&f), None);
    }

    #[test]
    fn runs_on_a_label_volume_and_a_missing_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("l.nrrd");
        let g = Geometry::new([2, 2, 1], [0.5; 3], LengthUnit::Micrometre).unwrap();
        let v = AnyVolume::U8(Volume::from_vec(g, vec![0, 1, 1, 2]).unwrap());
        interslice_io::write_volume(&p, &v).unwrap();
        for json in [false, true] {
            run(Args {
                input: p.clone(),
                json,
                labels: false,
                series: Default::default(),
            })
            .unwrap();
        }
        let missing = Args {
            input: dir.path().join("none.nrrd"),
            json: true,
            labels: false,
            series: Default::default(),
        };
        let e = format!("{:#}", run(missing).unwrap_err());
        assert!(e.contains("none.nrrd") && !e.contains('\n'), "{e}");
    }
}
