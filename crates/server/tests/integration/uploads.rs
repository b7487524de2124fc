//! Hostile volume files over real HTTP: an uploaded segmentation is read
//! from memory, self-contained only, and checked against the cell's grid
//! before its data is decoded; a cell file that cannot be read is that
//! cell's error, never the server's end.
use crate::common;

use common::*;

/// A NIfTI-1 file whose header claims `dims` of f64 with only a few bytes
/// of data.
fn lying_nifti(dims: [i16; 3]) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.nii");
    let g = interslice_core::Geometry::new([2, 2, 2], [1.0; 3], Default::default()).unwrap();
    let v = interslice_core::Volume::from_vec(g, vec![1u8; 8]).unwrap();
    interslice_io::write_volume(&p, &interslice_core::AnyVolume::U8(v)).unwrap();
    let mut b = std::fs::read(&p).unwrap();
    for (i, d) in dims.iter().enumerate() {
        b[42 + 2 * i..44 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    b[70..72].copy_from_slice(&64i16.to_le_bytes());
    b[72..74].copy_from_slice(&64i16.to_le_bytes());
    b
}

#[test]
fn uploads_are_checked_against_the_grid_and_self_contained() {
    let dir = project();
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    let upload = |name: &str, body: &[u8]| {
        c.send(
            "POST",
            &format!("/api/cells/cell_01/segmentations/upload?name={name}"),
            Some((body, "application/octet-stream")),
        )
        .unwrap()
    };
    // 4096 x 4096 x 16 f64 against a 32 x 28 x 24 cell: refused on the header.
    let a = upload("big.nii", &lying_nifti([4096, 4096, 16]));
    expect(&a, 400);
    let e = a.error().unwrap();
    assert!(e.contains("do not match the expected [32, 28, 24]"), "{e}");
    // Detached headers and data files outside the upload: refused, and the
    // error names no path of the server.
    let project_dir = dir.path().display().to_string();
    for (name, body) in [
        (
            "s.nhdr",
            "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 32 28 24\nencoding: raw\ndata file: cell_01.nii\n",
        ),
        (
            "s.nrrd",
            "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 32 28 24\nencoding: raw\ndata file: /etc/passwd\n\n",
        ),
        (
            "s.mha",
            "ObjectType = Image\nNDims = 3\nDimSize = 32 28 24\nElementType = MET_UCHAR\nElementDataFile = ../cell_01.nii\n",
        ),
        (
            "s.mhd",
            "ObjectType = Image\nNDims = 3\nDimSize = 32 28 24\nElementType = MET_UCHAR\nElementDataFile = s.raw\n",
        ),
    ] {
        let a = upload(name, body.as_bytes());
        expect(&a, 400);
        let e = a.error().unwrap();
        // Refused by the upload's name (a detached header) or by the reader
        // (a header that names a data file): either way, one self-contained file.
        assert!(
            e.contains("self-contained") || e.contains("data lives in another file"),
            "{name}: {e}"
        );
        assert!(
            !e.contains(&project_dir) && !e.contains("/tmp"),
            "{name}: {e}"
        );
    }
}

/// CRC-32 (IEEE) of a PNG chunk, to patch an IHDR.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[test]
fn a_corrupt_slice_is_the_cells_error_not_the_servers_end() {
    let dir = project();
    // A folder cell whose second slice claims 2^31-1 x 2^31-1 pixels.
    let folder = dir.path().join("bad");
    let g = interslice_core::Geometry::new([6, 5, 3], [1.0; 3], Default::default()).unwrap();
    let v = interslice_core::Volume::from_vec(g, vec![3u8; 90]).unwrap();
    interslice_io::write_volume(&folder, &interslice_core::AnyVolume::U8(v)).unwrap();
    let p = folder.join("slice_0001.png");
    let mut b = std::fs::read(&p).unwrap();
    b[16..24].copy_from_slice(&[0x7F, 0xFF, 0xFF, 0xFF, 0x7F, 0xFF, 0xFF, 0xFF]);
    let crc = crc32(&b[12..29]);
    b[29..33].copy_from_slice(&crc.to_be_bytes());
    std::fs::write(&p, b).unwrap();
    let server = serve(config(dir.path()));
    let c = signed_in(&server, "alice");
    let list = c.get("/api/cells").unwrap();
    expect(&list, 200);
    // Listed with its reason, not dropped and not fatal.
    let cells = list.json();
    let bad = cells
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["id"] == "bad")
        .expect("the unreadable cell is listed");
    assert_eq!(bad["status"], "unreadable");
    assert!(
        bad["error"].as_str().unwrap().contains("slice_0001.png"),
        "{bad}"
    );
    let queue = c.get("/api/cells?queue=true").unwrap().json();
    assert!(queue.as_array().unwrap().iter().all(|c| c["id"] != "bad"));
    let a = c.get("/api/cells/bad").unwrap();
    expect(&a, 400);
    assert!(
        a.error().unwrap().contains("slice_0001.png"),
        "{:?}",
        a.error()
    );
    // Still serving, the same error again, and the good cells still load.
    expect(&c.get("/api/cells").unwrap(), 200);
    expect(&c.get("/api/cells/bad").unwrap(), 400);
    expect(&c.get("/api/cells/cell_01").unwrap(), 200);
}
