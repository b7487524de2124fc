//! Mesh files: STL, PLY (binary and ASCII) and OBJ read back what was
//! written; an OBJ of a cube matches a committed golden file; bad files and
//! names give one-line errors naming the file.
use interslice_core::mesh::TriMesh;
use interslice_io::mesh::{MeshFormat, read_mesh, write_mesh, write_mesh_as};
use std::path::Path;

/// A box with outward winding (two triangles per face).
fn cube(lo: [f64; 3], hi: [f64; 3]) -> TriMesh {
    let vertices = (0..8)
        .map(|c| {
            [
                if c & 1 == 0 { lo[0] } else { hi[0] },
                if c & 2 == 0 { lo[1] } else { hi[1] },
                if c & 4 == 0 { lo[2] } else { hi[2] },
            ]
        })
        .collect();
    let mut triangles = Vec::new();
    for q in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
    }
    TriMesh {
        vertices,
        triangles,
    }
}

/// A mesh with pseudo-random vertices (exactly representable in f32) and
/// triangles, for round trips.
fn scrambled(n: usize, seed: u64) -> TriMesh {
    let mut x = seed;
    let mut next = move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        x >> 33
    };
    let vertices: Vec<[f64; 3]> = (0..n)
        .map(|_| std::array::from_fn(|_| (next() % 20_000) as f64 / 64.0 - 150.0))
        .collect();
    let triangles = (0..2 * n)
        .map(|_| std::array::from_fn(|_| (next() % n as u64) as u32))
        .collect();
    TriMesh {
        vertices,
        triangles,
    }
}

#[test]
fn stl_reads_back_triangles_and_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cube.stl");
    let m = cube([0.5, -1.0, 2.0], [1.75, 3.0, 2.5]);
    write_mesh(&path, &m).unwrap();
    assert_eq!(std::fs::metadata(&path).unwrap().len(), 84 + 50 * 12);
    let back = read_mesh(&path).unwrap();
    assert_eq!(back.triangles.len(), 12);
    for t in 0..12 {
        assert_eq!(back.corners(t), m.corners(t), "triangle {t}");
    }
    // Facet normals follow the winding: the first face (z = lo) points -z.
    let bytes = std::fs::read(&path).unwrap();
    let nz = f32::from_le_bytes(bytes[92..96].try_into().unwrap());
    assert_eq!(nz, -1.0);
    assert!((back.signed_volume() - m.signed_volume()).abs() < 1e-9);
}

#[test]
fn ply_binary_and_ascii_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    for (seed, format, name) in [
        (1, MeshFormat::PlyBinary, "a.ply"),
        (2, MeshFormat::PlyAscii, "b.ply"),
        (3, MeshFormat::Obj, "c.obj"),
    ] {
        let m = scrambled(50, seed);
        let path = dir.path().join(name);
        write_mesh_as(&path, &m, format).unwrap();
        let back = read_mesh(&path).unwrap();
        assert_eq!(back, m, "{format:?}");
    }
    let text = std::fs::read(dir.path().join("b.ply")).unwrap();
    assert!(text.starts_with(b"ply\nformat ascii 1.0\n"));
    let bin = std::fs::read(dir.path().join("a.ply")).unwrap();
    assert!(bin.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
}

#[test]
fn obj_of_a_cube_matches_the_golden_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cube.obj");
    write_mesh(&path, &cube([0.0; 3], [1.0, 2.0, 0.35])).unwrap();
    let got = std::fs::read_to_string(&path).unwrap();
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube_golden.obj");
    let want = std::fs::read_to_string(golden).unwrap();
    assert_eq!(got, want);
}

#[test]
fn writes_leave_no_temporary_files_and_replace_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.obj");
    std::fs::write(&path, "old").unwrap();
    write_mesh(&path, &cube([0.0; 3], [1.0; 3])).unwrap();
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "{names:?}");
    assert!(
        std::fs::read_to_string(&path)
            .unwrap()
            .starts_with("# written by interslice")
    );
}

#[test]
fn bad_names_and_files_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let m = cube([0.0; 3], [1.0; 3]);
    let one_line = |e: String, what: &str| {
        assert!(!e.contains('\n') && e.contains(what), "{e}");
    };
    one_line(
        write_mesh(&dir.path().join("m.vtk"), &m)
            .unwrap_err()
            .to_string(),
        "m.vtk",
    );
    one_line(
        write_mesh(&dir.path().join("missing/m.stl"), &m)
            .unwrap_err()
            .to_string(),
        "m.stl",
    );
    let mut broken = m.clone();
    broken.triangles.push([0, 1, 99]);
    one_line(
        write_mesh(&dir.path().join("b.stl"), &broken)
            .unwrap_err()
            .to_string(),
        "b.stl",
    );

    let stl = dir.path().join("t.stl");
    write_mesh(&stl, &m).unwrap();
    let bytes = std::fs::read(&stl).unwrap();
    std::fs::write(&stl, &bytes[..bytes.len() - 10]).unwrap();
    one_line(read_mesh(&stl).unwrap_err().to_string(), "truncated");

    let obj = dir.path().join("t.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap();
    one_line(read_mesh(&obj).unwrap_err().to_string(), "out of range");

    let ply = dir.path().join("t.ply");
    std::fs::write(&ply, "ply\nformat binary_big_endian 1.0\nend_header\n").unwrap();
    one_line(read_mesh(&ply).unwrap_err().to_string(), "not supported");
}
