//! Label volumes together with their component table, in the forms the tools
//! of the field read: a 3D Slicer segmentation (`.seg.nrrd`, the segment
//! table in `Segment{N}_*` keys of the NRRD header) and, beside any other
//! label volume, an ITK-SNAP label description file (`NAME.label.txt`, the
//! text format of ITK-SNAP's *Segmentation › Export/Import Label
//! Descriptions*).
//!
//! Written by hand: no crate writes Slicer's segment keys or ITK-SNAP's label
//! descriptions; both are a few lines of text.
use crate::{IoError, nrrd};
use interslice_core::LabelVolume;
use interslice_core::components::{Component, Components};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Whether a path names a 3D Slicer segmentation (`.seg.nrrd`).
pub fn is_seg_nrrd(path: &Path) -> bool {
    path.file_name().is_some_and(|n| {
        n.to_string_lossy()
            .to_ascii_lowercase()
            .ends_with(".seg.nrrd")
    })
}

/// The ITK-SNAP label description file kept beside a label volume:
/// `labels.nii.gz` → `labels.label.txt`.
pub fn label_description_path(volume: &Path) -> PathBuf {
    let name = volume
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    let stem_len = [
        ".nii.gz",
        ".seg.nrrd",
        ".nii",
        ".nrrd",
        ".mha",
        ".mhd",
        ".tiff",
        ".tif",
    ]
    .iter()
    .find(|e| lower.ends_with(*e))
    .map_or(name.len(), |e| name.len() - e.len());
    volume.with_file_name(format!("{}.label.txt", &name[..stem_len]))
}

/// Write a label volume with its components: a `.seg.nrrd` holds the segment
/// table in its header; any other format is written by
/// [`crate::write_labels`] and an ITK-SNAP label description file is written
/// beside it ([`label_description_path`]). Only components whose value occurs
/// in the volume, or that are declared, are listed: every declared component
/// is listed (an empty segment is still a segment), and a value in the volume
/// that no component names gets "Label N". Returns the files written.
pub fn write_segmentation(
    path: &Path,
    labels: &LabelVolume,
    components: &Components,
) -> Result<Vec<PathBuf>, IoError> {
    let table = table_for(labels, components);
    if is_seg_nrrd(path) {
        let keys = slicer_keys(labels, &table);
        nrrd::write_with_keys(path, &crate::narrowest(labels), &keys)?;
        return Ok(vec![path.to_path_buf()]);
    }
    crate::write_labels(path, labels)?;
    let desc = label_description_path(path);
    crate::raw::write_atomic(&desc, |w| {
        use std::io::Write;
        w.write_all(itksnap_text(&table).as_bytes())
    })?;
    Ok(vec![path.to_path_buf(), desc])
}

/// The bytes of a `.seg.nrrd` file named `name` holding `labels` and the
/// segment table of `components`, made in memory (downloads).
pub fn seg_nrrd_bytes(
    name: &str,
    labels: &LabelVolume,
    components: &Components,
) -> Result<Vec<u8>, IoError> {
    let path = Path::new(name);
    if !is_seg_nrrd(path) {
        return Err(IoError::unsupported(path, "not a .seg.nrrd name"));
    }
    let keys = slicer_keys(labels, &table_for(labels, components));
    let mut out = Vec::new();
    nrrd::encode(&mut out, path, &crate::narrowest(labels), &keys)?;
    Ok(out)
}

/// The components a label file declares: the segment table of a `.seg.nrrd`,
/// else the ITK-SNAP label description file beside it, else none.
pub fn read_components(path: &Path) -> Result<Components, IoError> {
    if is_seg_nrrd(path) {
        return slicer_components(path, &nrrd::read_keys(path)?);
    }
    let desc = label_description_path(path);
    if desc.is_file() {
        return read_label_descriptions(&desc);
    }
    Ok(Components::default())
}

/// Largest ITK-SNAP label description file read (it is a few lines a label).
const MAX_DESCRIPTION_BYTES: u64 = 4 << 20;

/// Read an ITK-SNAP label description file. Label 0 ("Clear Label") is
/// background and not a component.
pub fn read_label_descriptions(path: &Path) -> Result<Components, IoError> {
    use std::io::Read;
    let f = std::fs::File::open(path).map_err(|e| IoError::Read {
        path: path.to_path_buf(),
        cause: e,
    })?;
    let mut text = String::new();
    f.take(MAX_DESCRIPTION_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(|e| IoError::Read {
            path: path.to_path_buf(),
            cause: e,
        })?;
    if text.len() as u64 > MAX_DESCRIPTION_BYTES {
        return Err(IoError::invalid(path, "label description file over 4 MiB"));
    }
    let mut list = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = || {
            IoError::invalid(
                path,
                format!("line {}: not an ITK-SNAP label description", n + 1),
            )
        };
        let (fields, name) = line.split_once('"').ok_or_else(bad)?;
        let name = name.strip_suffix('"').ok_or_else(bad)?;
        let f: Vec<&str> = fields.split_whitespace().collect();
        if f.len() != 7 {
            return Err(bad());
        }
        let value: u16 = f[0].parse().map_err(|_| bad())?;
        let rgb: Vec<u8> = f[1..4]
            .iter()
            .map(|c| c.parse::<u8>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        if value == 0 {
            continue;
        }
        list.push(Component {
            value,
            name: name.to_string(),
            color: [rgb[0], rgb[1], rgb[2]],
        });
    }
    Components::new(list).map_err(|e| IoError::invalid(path, e.to_string()))
}

/// One row of the table written: every declared component, then "Label N"
/// for values present but undeclared.
fn table_for(labels: &LabelVolume, components: &Components) -> Vec<Component> {
    let mut present = vec![false; usize::from(u16::MAX) + 1];
    for &v in labels.data() {
        present[usize::from(v)] = true;
    }
    let mut table: Vec<Component> = components.as_slice().to_vec();
    for v in 1..=u16::MAX {
        if present[usize::from(v)] && components.by_value(v).is_none() {
            let mut name = format!("Label {v}");
            if components.by_name(&name).is_some() {
                name = format!("Label {v} (unnamed)");
            }
            table.push(Component::new(v, name));
        }
    }
    table.sort_by_key(|c| c.value);
    table
}

/// The voxel extent of each value: `[imin, imax, jmin, jmax, kmin, kmax]`,
/// or None where the value does not occur.
fn extents(labels: &LabelVolume) -> HashMap<u16, [usize; 6]> {
    let [nx, ny, _] = labels.geometry().dims;
    let mut out: HashMap<u16, [usize; 6]> = HashMap::new();
    for (idx, &v) in labels.data().iter().enumerate() {
        if v == 0 {
            continue;
        }
        let (i, j, k) = (idx % nx, (idx / nx) % ny, idx / (nx * ny));
        let e = out.entry(v).or_insert([i, i, j, j, k, k]);
        e[0] = e[0].min(i);
        e[1] = e[1].max(i);
        e[2] = e[2].min(j);
        e[3] = e[3].max(j);
        e[4] = e[4].min(k);
        e[5] = e[5].max(k);
    }
    out
}

/// The header keys 3D Slicer writes for a single-layer segmentation.
fn slicer_keys(labels: &LabelVolume, table: &[Component]) -> Vec<(String, String)> {
    let ext = extents(labels);
    let mut keys = Vec::new();
    for (n, c) in table.iter().enumerate() {
        let [r, g, b] = c.color;
        let e = ext
            .get(&c.value)
            .map(|e| e.map(|x| x.to_string()).join(" "))
            .unwrap_or_else(|| "0 -1 0 -1 0 -1".into());
        let mut kv = |k: &str, v: String| keys.push((format!("Segment{n}_{k}"), v));
        kv(
            "Color",
            format!(
                "{:.6} {:.6} {:.6}",
                f64::from(r) / 255.0,
                f64::from(g) / 255.0,
                f64::from(b) / 255.0
            ),
        );
        kv("ColorAutoGenerated", "0".into());
        kv("Extent", e);
        kv("ID", format!("Segment_{}", c.value));
        kv("LabelValue", c.value.to_string());
        kv("Layer", "0".into());
        kv("Name", c.name.clone());
        kv("NameAutoGenerated", "0".into());
        kv("Tags", "|".into());
    }
    keys.push((
        "Segmentation_ContainedRepresentationNames".into(),
        "Binary labelmap|".into(),
    ));
    keys.push((
        "Segmentation_MasterRepresentation".into(),
        "Binary labelmap".into(),
    ));
    keys.push((
        "Segmentation_ReferenceImageExtentOffset".into(),
        "0 0 0".into(),
    ));
    keys
}

/// The segment table of a `.seg.nrrd` header.
fn slicer_components(path: &Path, keys: &HashMap<String, String>) -> Result<Components, IoError> {
    let mut list = Vec::new();
    for n in 0..interslice_core::components::MAX_COMPONENTS + 1 {
        let Some(value) = keys.get(&format!("Segment{n}_LabelValue")) else {
            break;
        };
        let bad = |what: &str| IoError::invalid(path, format!("bad Segment{n}_{what}"));
        let value: u16 = value.trim().parse().map_err(|_| bad("LabelValue"))?;
        let name = keys
            .get(&format!("Segment{n}_Name"))
            .cloned()
            .unwrap_or_else(|| format!("Segment {}", n + 1));
        let color = match keys.get(&format!("Segment{n}_Color")) {
            Some(c) => {
                let v: Vec<f64> = c
                    .split_whitespace()
                    .map(str::parse)
                    .collect::<Result<_, _>>()
                    .map_err(|_| bad("Color"))?;
                if v.len() != 3 || v.iter().any(|x| !(0.0..=1.0).contains(x)) {
                    return Err(bad("Color"));
                }
                [0, 1, 2].map(|i| (v[i] * 255.0).round() as u8)
            }
            None => Component::new(value, "").color,
        };
        list.push(Component { value, name, color });
    }
    Components::new(list).map_err(|e| IoError::invalid(path, e.to_string()))
}

/// ITK-SNAP's label description text: a comment block, the clear label, then
/// one line a component (index, R G B, opacity, visibility, mesh visibility,
/// quoted name).
fn itksnap_text(table: &[Component]) -> String {
    let mut s = String::from(
        "################################################\n\
         # ITK-SnAP Label Description File\n\
         # File format: \n\
         # IDX   -R-  -G-  -B-  -A--  VIS MSH  LABEL\n\
         # Fields: \n\
         #    IDX:   Zero-based index \n\
         #    -R-:   Red color component (0..255)\n\
         #    -G-:   Green color component (0..255)\n\
         #    -B-:   Blue color component (0..255)\n\
         #    -A-:   Label transparency (0.00 .. 1.00)\n\
         #    VIS:   Label visibility (0 or 1)\n\
         #    IDX:   Label mesh visibility (0 or 1)\n\
         #  LABEL:   Label description \n\
         ################################################\n\
         \x20   0     0    0    0        0  0  0    \"Clear Label\"\n",
    );
    for c in table {
        let [r, g, b] = c.color;
        // A name cannot hold a quote in this format: ITK-SNAP ends it there.
        let name = c.name.replace('"', "'");
        s.push_str(&format!(
            "{:>5} {:>5} {:>4} {:>4}        1  1  1    \"{name}\"\n",
            c.value, r, g, b
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{Geometry, LengthUnit, Volume};

    fn labels() -> LabelVolume {
        let g = Geometry::new([4, 3, 2], [0.5, 0.5, 2.0], LengthUnit::Millimetre).unwrap();
        let mut data = vec![0u16; 24];
        data[5] = 1;
        data[6] = 1;
        data[20] = 7;
        Volume::from_vec(g, data).unwrap()
    }

    #[test]
    fn seg_nrrd_round_trips_names_colours_and_values() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.seg.nrrd");
        let comps = Components::from_names("Tumour,Oedema").unwrap();
        write_segmentation(&p, &labels(), &comps).unwrap();
        let back = crate::read_labels(&p).unwrap();
        assert_eq!(back.data(), labels().data());
        let c = read_components(&p).unwrap();
        let names: Vec<(&str, u16)> = c
            .as_slice()
            .iter()
            .map(|c| (c.name.as_str(), c.value))
            .collect();
        assert_eq!(names, [("Tumour", 1), ("Oedema", 2), ("Label 7", 7)]);
        assert_eq!(
            c.by_value(1).unwrap().color,
            comps.by_value(1).unwrap().color
        );
        let keys = nrrd::read_keys(&p).unwrap();
        assert_eq!(keys["Segment0_Extent"], "1 2 1 1 0 0");
        assert_eq!(keys["Segment1_Extent"], "0 -1 0 -1 0 -1");
        assert_eq!(keys["Segment2_ID"], "Segment_7");
        // The download's bytes are the file's.
        let bytes = seg_nrrd_bytes("out.seg.nrrd", &labels(), &comps).unwrap();
        assert_eq!(bytes, std::fs::read(&p).unwrap());
        assert!(seg_nrrd_bytes("out.nrrd", &labels(), &comps).is_err());
    }

    #[test]
    fn itksnap_descriptions_are_written_beside_and_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("alice.nii.gz");
        let written = write_segmentation(&p, &labels(), &Components::cell_ct()).unwrap();
        assert_eq!(written[1], dir.path().join("alice.label.txt"));
        let text = std::fs::read_to_string(&written[1]).unwrap();
        assert!(
            text.contains("    1   230   25   75        1  1  1    \"Cell\"\n"),
            "{text}"
        );
        let c = read_components(&p).unwrap();
        assert_eq!(c.resolve("nucleus").unwrap(), 2);
        assert_eq!(c.by_value(7).unwrap().name, "Label 7");
        assert_eq!(c.as_slice().len(), 5);
    }

    #[test]
    fn malformed_descriptions_are_one_line_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.label.txt");
        std::fs::write(&p, "1 2 3 \"A\"\n").unwrap();
        let e = read_label_descriptions(&p).unwrap_err().to_string();
        assert!(e.contains("line 1"), "{e}");
        std::fs::write(&p, "1 2 3 4 1 1 1 \"A\"\n2 2 3 4 1 1 1 \"A\"\n").unwrap();
        let e = read_label_descriptions(&p).unwrap_err().to_string();
        assert!(e.contains("declared twice"), "{e}");
    }
}
