//! Triangle mesh files: STL (binary), PLY (binary little-endian or ASCII)
//! and Wavefront OBJ.
//!
//! [`write_mesh`] picks the format from the extension (`.stl`, `.ply`,
//! `.obj`, case-insensitive; `.ply` is written binary); [`write_mesh_as`]
//! names it, e.g. [`MeshFormat::PlyAscii`]. Writes are atomic like every
//! writer of this crate (a temporary file renamed over the target).
//! [`read_mesh`] reads back the files these writers produce (and common
//! files of the same kinds: binary STL, PLY with `x y z` vertex properties
//! and a face index list, OBJ `v`/`f` lines), so tests and tools can check
//! a mesh round trip.
//!
//! Coordinates are written as given. Meshes of the interpolators are in the
//! voxel frame of [`interslice_core::mesh`] (no origin, no direction);
//! [`world_transform`] gives the affine map to the volume's physical frame,
//! which the `interslice mesh` command applies before writing. STL and PLY
//! store coordinates as 32-bit floats, OBJ as the shortest decimal text that
//! reads back to the same 64-bit value. Triangles are written in the
//! mesh's winding (counter-clockwise seen from outside); STL facet normals
//! are computed from that winding.
use crate::IoError;
use crate::raw::{open, write_atomic};
use interslice_core::Geometry;
use interslice_core::mesh::TriMesh;
use std::io::{BufRead, Read, Write};
use std::path::Path;

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Binary STL (`.stl`): triangle soup with facet normals, `f32`.
    Stl,
    /// Binary little-endian PLY (`.ply`): shared vertices, `f32`.
    PlyBinary,
    /// ASCII PLY: the same content as text.
    PlyAscii,
    /// Wavefront OBJ (`.obj`): `v` and `f` lines, shared vertices.
    Obj,
}

impl MeshFormat {
    /// The format of a path by its extension (case-insensitive); `.ply`
    /// means binary PLY. Errs for any other extension.
    pub fn of_path(path: &Path) -> Result<MeshFormat, IoError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "stl" => Ok(MeshFormat::Stl),
            "ply" => Ok(MeshFormat::PlyBinary),
            "obj" => Ok(MeshFormat::Obj),
            _ => Err(IoError::unsupported(
                path,
                "unknown mesh extension (use .stl, .ply or .obj)",
            )),
        }
    }
}

/// The affine map `p -> m p + t` from the mesh frame of
/// [`interslice_core::mesh`] (voxel centre at `(index + 0.5) * spacing`) to
/// the volume's physical frame (voxel (0,0,0)'s centre at `origin`, axes
/// along the direction cosines). Apply it with [`TriMesh::transform`].
pub fn world_transform(geometry: &Geometry) -> ([[f64; 3]; 3], [f64; 3]) {
    let d = geometry.direction;
    let s = geometry.spacing;
    let mut t = geometry.origin;
    for (r, tr) in t.iter_mut().enumerate() {
        for c in 0..3 {
            *tr -= d[r][c] * 0.5 * s[c];
        }
    }
    (d, t)
}

/// Write a mesh; the format is chosen by [`MeshFormat::of_path`].
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), IoError> {
    write_mesh_as(path, mesh, MeshFormat::of_path(path)?)
}

/// Write a mesh in the given format (atomically). Errs for a mesh with an
/// out-of-range vertex index or a non-finite coordinate, and when the
/// operating system refuses the write.
pub fn write_mesh_as(path: &Path, mesh: &TriMesh, format: MeshFormat) -> Result<(), IoError> {
    mesh.validate().map_err(|m| IoError::invalid(path, m))?;
    if u32::try_from(mesh.triangles.len()).is_err() || u32::try_from(mesh.vertices.len()).is_err() {
        return Err(IoError::unsupported(path, "mesh too large for the format"));
    }
    match format {
        MeshFormat::Stl => write_atomic(path, |w| write_stl(w, mesh)),
        MeshFormat::PlyBinary => write_atomic(path, |w| write_ply(w, mesh, false)),
        MeshFormat::PlyAscii => write_atomic(path, |w| write_ply(w, mesh, true)),
        MeshFormat::Obj => write_atomic(path, |w| write_obj(w, mesh)),
    }
}

fn facet_normal(c: [[f64; 3]; 3]) -> [f32; 3] {
    let a = [c[1][0] - c[0][0], c[1][1] - c[0][1], c[1][2] - c[0][2]];
    let b = [c[2][0] - c[0][0], c[2][1] - c[0][1], c[2][2] - c[0][2]];
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 {
        n.map(|x| (x / len) as f32)
    } else {
        [0.0; 3]
    }
}

fn write_stl(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    let mut header = [b' '; 80];
    let text = b"interslice binary STL";
    header[..text.len()].copy_from_slice(text);
    w.write_all(&header)?;
    w.write_all(&(mesh.triangles.len() as u32).to_le_bytes())?;
    for t in 0..mesh.triangles.len() {
        let c = mesh.corners(t);
        for x in facet_normal(c) {
            w.write_all(&x.to_le_bytes())?;
        }
        for p in c {
            for x in p {
                w.write_all(&(x as f32).to_le_bytes())?;
            }
        }
        w.write_all(&0u16.to_le_bytes())?;
    }
    Ok(())
}

fn write_ply(w: &mut impl Write, mesh: &TriMesh, ascii: bool) -> std::io::Result<()> {
    let format = if ascii {
        "ascii"
    } else {
        "binary_little_endian"
    };
    write!(
        w,
        "ply\nformat {format} 1.0\ncomment written by interslice\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    if ascii {
        for p in &mesh.vertices {
            writeln!(w, "{} {} {}", p[0] as f32, p[1] as f32, p[2] as f32)?;
        }
        for t in &mesh.triangles {
            writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
        }
    } else {
        for p in &mesh.vertices {
            for &x in p {
                w.write_all(&(x as f32).to_le_bytes())?;
            }
        }
        for t in &mesh.triangles {
            w.write_all(&[3u8])?;
            for &i in t {
                w.write_all(&(i as i32).to_le_bytes())?;
            }
        }
    }
    Ok(())
}

fn write_obj(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    writeln!(w, "# written by interslice")?;
    writeln!(
        w,
        "# {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    for p in &mesh.vertices {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    for t in &mesh.triangles {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    Ok(())
}

/// Read a mesh file (format by extension, see the module docs). STL
/// triangles do not share vertices: every triangle gets its own three.
pub fn read_mesh(path: &Path) -> Result<TriMesh, IoError> {
    let format = MeshFormat::of_path(path)?;
    let mut r = open(path)?;
    let mesh = match format {
        MeshFormat::Stl => read_stl(path, &mut r)?,
        MeshFormat::PlyBinary | MeshFormat::PlyAscii => read_ply(path, &mut r)?,
        MeshFormat::Obj => read_obj(path, &mut r)?,
    };
    mesh.validate().map_err(|m| IoError::invalid(path, m))?;
    Ok(mesh)
}

fn read_stl(path: &Path, r: &mut impl Read) -> Result<TriMesh, IoError> {
    let mut data = Vec::new();
    r.read_to_end(&mut data)
        .map_err(|e| IoError::read(path, e))?;
    if data.len() < 84 {
        return Err(IoError::invalid(path, "too short for a binary STL"));
    }
    let n = u32::from_le_bytes([data[80], data[81], data[82], data[83]]) as usize;
    // A binary header may start with "solid" too; the size tells them apart.
    if data.starts_with(b"solid") && data.len() != 84 + 50 * n {
        return Err(IoError::unsupported(path, "ASCII STL is not supported"));
    }
    if data.len() < 84 + 50 * n {
        return Err(IoError::invalid(
            path,
            format!(
                "truncated: {n} triangles need {} bytes, file has {}",
                84 + 50 * n,
                data.len()
            ),
        ));
    }
    let f = |o: usize| f32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]);
    let mut mesh = TriMesh::new();
    for t in 0..n {
        let base = 84 + 50 * t + 12;
        for c in 0..3 {
            let o = base + 12 * c;
            mesh.vertices
                .push([f(o).into(), f(o + 4).into(), f(o + 8).into()]);
        }
        let v = (3 * t) as u32;
        mesh.triangles.push([v, v + 1, v + 2]);
    }
    Ok(mesh)
}

fn parse_index(path: &Path, tok: &str, count: usize) -> Result<u32, IoError> {
    // OBJ: 1-based, negative = relative to the end; `v/vt/vn` forms allowed.
    let first = tok.split('/').next().unwrap_or("");
    let i: i64 = first
        .parse()
        .map_err(|_| IoError::invalid(path, format!("bad face index '{tok}'")))?;
    let idx = if i < 0 { count as i64 + i } else { i - 1 };
    if idx < 0 || idx >= count as i64 {
        return Err(IoError::invalid(
            path,
            format!("face index {i} out of range (1..={count})"),
        ));
    }
    Ok(idx as u32)
}

fn read_obj(path: &Path, r: &mut impl BufRead) -> Result<TriMesh, IoError> {
    let mut mesh = TriMesh::new();
    let mut line = String::new();
    let mut number = 0usize;
    loop {
        line.clear();
        number += 1;
        if r.read_line(&mut line).map_err(|e| IoError::read(path, e))? == 0 {
            break;
        }
        let mut toks = line.split_whitespace();
        match toks.next() {
            Some("v") => {
                let c: Vec<f64> = toks
                    .take(3)
                    .map(str::parse)
                    .collect::<Result<_, _>>()
                    .map_err(|_| IoError::invalid(path, format!("line {number}: bad vertex")))?;
                if c.len() != 3 {
                    return Err(IoError::invalid(path, format!("line {number}: bad vertex")));
                }
                mesh.vertices.push([c[0], c[1], c[2]]);
            }
            Some("f") => {
                let n = mesh.vertices.len();
                let ids: Vec<u32> = toks
                    .map(|t| parse_index(path, t, n))
                    .collect::<Result<_, _>>()?;
                if ids.len() < 3 {
                    return Err(IoError::invalid(
                        path,
                        format!("line {number}: face of < 3 vertices"),
                    ));
                }
                for k in 1..ids.len() - 1 {
                    mesh.triangles.push([ids[0], ids[k], ids[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(mesh)
}

/// One PLY property: its name and scalar type (lists: count and item type).
enum PlyProp {
    Scalar(String, String),
    List(String, String),
}

fn ply_scalar_size(path: &Path, t: &str) -> Result<usize, IoError> {
    Ok(match t {
        "char" | "uchar" | "int8" | "uint8" => 1,
        "short" | "ushort" | "int16" | "uint16" => 2,
        "int" | "uint" | "float" | "int32" | "uint32" | "float32" => 4,
        "double" | "float64" => 8,
        _ => return Err(IoError::invalid(path, format!("unknown PLY type '{t}'"))),
    })
}

fn ply_read_binary(path: &Path, data: &[u8], pos: &mut usize, t: &str) -> Result<f64, IoError> {
    let n = ply_scalar_size(path, t)?;
    let b = data
        .get(*pos..*pos + n)
        .ok_or_else(|| IoError::invalid(path, "truncated PLY data"))?;
    *pos += n;
    Ok(match t {
        "char" | "int8" => f64::from(b[0] as i8),
        "uchar" | "uint8" => f64::from(b[0]),
        "short" | "int16" => f64::from(i16::from_le_bytes([b[0], b[1]])),
        "ushort" | "uint16" => f64::from(u16::from_le_bytes([b[0], b[1]])),
        "int" | "int32" => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        "uint" | "uint32" => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        "float" | "float32" => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        _ => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
    })
}

fn read_ply(path: &Path, r: &mut impl BufRead) -> Result<TriMesh, IoError> {
    let bad = |m: &str| IoError::invalid(path, m.to_string());
    let mut line = String::new();
    let mut header = Vec::new();
    loop {
        line.clear();
        if r.read_line(&mut line).map_err(|e| IoError::read(path, e))? == 0 {
            return Err(bad("PLY header has no end_header"));
        }
        let l = line.trim().to_string();
        if l == "end_header" {
            break;
        }
        header.push(l);
        if header.len() > 10_000 {
            return Err(bad("PLY header too long"));
        }
    }
    if header.first().map(String::as_str) != Some("ply") {
        return Err(bad("not a PLY file"));
    }
    let mut ascii = None;
    let mut elements: Vec<(String, usize, Vec<PlyProp>)> = Vec::new();
    for l in &header[1..] {
        let t: Vec<&str> = l.split_whitespace().collect();
        match t.as_slice() {
            ["format", "ascii", _] => ascii = Some(true),
            ["format", "binary_little_endian", _] => ascii = Some(false),
            ["format", f, ..] => {
                return Err(IoError::unsupported(
                    path,
                    format!("PLY format '{f}' is not supported"),
                ));
            }
            ["element", name, count] => {
                let n = count.parse().map_err(|_| bad("bad PLY element count"))?;
                elements.push((name.to_string(), n, Vec::new()));
            }
            ["property", "list", count_t, item_t, name] => {
                ply_scalar_size(path, count_t)?;
                let e = elements
                    .last_mut()
                    .ok_or_else(|| bad("PLY property before element"))?;
                e.2.push(PlyProp::List(
                    name.to_string(),
                    format!("{count_t} {item_t}"),
                ));
            }
            ["property", t, name] => {
                ply_scalar_size(path, t)?;
                let e = elements
                    .last_mut()
                    .ok_or_else(|| bad("PLY property before element"))?;
                e.2.push(PlyProp::Scalar(name.to_string(), t.to_string()));
            }
            _ => {}
        }
    }
    let ascii = ascii.ok_or_else(|| bad("PLY header has no format line"))?;
    let mut data = Vec::new();
    r.read_to_end(&mut data)
        .map_err(|e| IoError::read(path, e))?;
    let text = if ascii {
        String::from_utf8_lossy(&data).into_owned()
    } else {
        String::new()
    };
    let mut words = text.split_whitespace();
    let mut pos = 0usize;
    let mut next = |t: &str| -> Result<f64, IoError> {
        if ascii {
            let v: f64 = words
                .next()
                .ok_or_else(|| bad("truncated PLY data"))?
                .parse()
                .map_err(|_| bad("bad number in PLY data"))?;
            // A `float` property holds the f32 nearest to its text.
            Ok(if matches!(t, "float" | "float32") {
                f64::from(v as f32)
            } else {
                v
            })
        } else {
            ply_read_binary(path, &data, &mut pos, t)
        }
    };
    let mut mesh = TriMesh::new();
    for (name, count, props) in &elements {
        for _ in 0..*count {
            let mut p = [0.0; 3];
            for prop in props {
                match prop {
                    PlyProp::Scalar(pname, t) => {
                        let v = next(t)?;
                        if name == "vertex" {
                            match pname.as_str() {
                                "x" => p[0] = v,
                                "y" => p[1] = v,
                                "z" => p[2] = v,
                                _ => {}
                            }
                        }
                    }
                    PlyProp::List(pname, types) => {
                        let (ct, it) = types.split_once(' ').unwrap_or(("uchar", "int"));
                        let n = next(ct)?;
                        if !(0.0..=1e6).contains(&n) {
                            return Err(bad("bad PLY list length"));
                        }
                        let ids: Vec<f64> = (0..n as usize)
                            .map(|_| next(it))
                            .collect::<Result<_, _>>()?;
                        if name == "face" && (pname == "vertex_indices" || pname == "vertex_index")
                        {
                            if ids.len() < 3
                                || ids.iter().any(|&i| i < 0.0 || i > f64::from(u32::MAX))
                            {
                                return Err(bad("bad PLY face"));
                            }
                            for k in 1..ids.len() - 1 {
                                mesh.triangles.push([
                                    ids[0] as u32,
                                    ids[k] as u32,
                                    ids[k + 1] as u32,
                                ]);
                            }
                        }
                    }
                }
            }
            if name == "vertex" {
                mesh.vertices.push(p);
            }
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::LengthUnit;

    #[test]
    fn formats_by_extension() {
        assert_eq!(
            MeshFormat::of_path(Path::new("a/b.STL")).unwrap(),
            MeshFormat::Stl
        );
        assert_eq!(
            MeshFormat::of_path(Path::new("b.ply")).unwrap(),
            MeshFormat::PlyBinary
        );
        assert_eq!(
            MeshFormat::of_path(Path::new("b.obj")).unwrap(),
            MeshFormat::Obj
        );
        let e = MeshFormat::of_path(Path::new("b.vtk"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("b.vtk") && !e.contains('\n'), "{e}");
    }

    #[test]
    fn world_transform_puts_voxel_centre_on_origin() {
        let mut g = Geometry::new([4, 4, 4], [0.5, 1.0, 2.0], LengthUnit::Millimetre).unwrap();
        g.origin = [10.0, 20.0, 30.0];
        g.direction = [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let (m, t) = world_transform(&g);
        let mut mesh = TriMesh {
            vertices: vec![[0.25, 0.5, 1.0]],
            triangles: vec![],
        };
        mesh.transform(m, t);
        assert_eq!(mesh.vertices[0], [10.0, 20.0, 30.0]);
    }
}
