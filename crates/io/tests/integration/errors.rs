//! Bad input gives a one-line error that names the file, never a panic, and a
//! failed write leaves nothing behind (and an existing target untouched).
use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};
use interslice_io::{IoError, read_volume, write_volume};
use std::path::{Path, PathBuf};
use tiff::encoder::{TiffEncoder, colortype};

fn volume() -> AnyVolume {
    let g = Geometry::new([6, 5, 4], [0.5, 0.5, 1.0], LengthUnit::Micrometre).unwrap();
    let data = (0..g.len()).map(|n| (n * 11 % 65536) as u16).collect();
    AnyVolume::U16(Volume::from_vec(g, data).unwrap())
}

/// Write a valid file of the given name into `dir`.
fn valid(dir: &Path, name: &str) -> PathBuf {
    let p = dir.join(name);
    write_volume(&p, &volume()).unwrap();
    p
}

/// The error of reading `path`, checked to be one line naming the file.
fn read_err(path: &Path) -> String {
    let e = match read_volume(path) {
        Ok(v) => panic!(
            "{} read as {:?} without error",
            path.display(),
            v.geometry()
        ),
        Err(e) => e,
    };
    let msg = e.to_string();
    assert!(!msg.contains('\n'), "message is not one line: {msg:?}");
    assert!(
        msg.contains(&*path.file_name().unwrap().to_string_lossy()),
        "message does not name the file: {msg}"
    );
    msg
}

#[test]
fn truncated_nii_gz() {
    let dir = tempfile::tempdir().unwrap();
    let p = valid(dir.path(), "t.nii.gz");
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    let msg = read_err(&p);
    assert!(msg.contains("truncated"), "{msg}");
}

#[test]
fn truncated_files_of_every_format() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["t.nii", "t.nrrd", "t.mha", "t.tif"] {
        let p = valid(dir.path(), name);
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() - 7]).unwrap();
        read_err(&p);
    }
    // .mhd: the .raw file is short.
    let p = valid(dir.path(), "t.mhd");
    let raw = dir.path().join("t.raw");
    let bytes = std::fs::read(&raw).unwrap();
    std::fs::write(&raw, &bytes[..bytes.len() - 2]).unwrap();
    let msg = read_volume(&p).unwrap_err().to_string();
    assert!(msg.contains("t.raw") && msg.contains("truncated"), "{msg}");
}

#[test]
fn header_dims_do_not_match_data() {
    let dir = tempfile::tempdir().unwrap();
    // NIfTI: dim[3] (bytes 46..48) says 9 slices, the data has 4.
    let p = valid(dir.path(), "d.nii");
    let mut b = std::fs::read(&p).unwrap();
    b[46..48].copy_from_slice(&9i16.to_le_bytes());
    std::fs::write(&p, b).unwrap();
    let msg = read_err(&p);
    assert!(
        msg.contains("truncated") && msg.contains("[6, 5, 9]"),
        "{msg}"
    );

    // The same inside gzip.
    let p = valid(dir.path(), "d.nii.gz");
    let b = std::fs::read(&p).unwrap();
    let mut raw = Vec::new();
    std::io::Read::read_to_end(&mut flate2::read::GzDecoder::new(&b[..]), &mut raw).unwrap();
    raw[46..48].copy_from_slice(&9i16.to_le_bytes());
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    std::io::Write::write_all(&mut enc, &raw).unwrap();
    std::fs::write(&p, enc.finish().unwrap()).unwrap();
    assert!(read_err(&p).contains("truncated"));

    // NRRD and MetaImage: sizes larger than the data.
    let p = valid(dir.path(), "d.nrrd");
    let b = std::fs::read(&p).unwrap();
    let mut fixed = b.clone();
    let at = b.windows(12).position(|w| w == b"sizes: 6 5 4").unwrap();
    fixed.splice(at..at + 12, b"sizes: 6 5 9".iter().copied());
    std::fs::write(&p, fixed).unwrap();
    read_err(&p);

    let p = valid(dir.path(), "d.mhd");
    let h = std::fs::read_to_string(&p)
        .unwrap()
        .replace("DimSize = 6 5 4", "DimSize = 6 5 5");
    std::fs::write(&p, h).unwrap();
    let msg = read_volume(&p).unwrap_err().to_string();
    assert!(msg.contains("d.raw") && msg.contains("truncated"), "{msg}");

    // NIfTI claiming more voxels than we agree to allocate.
    let p = valid(dir.path(), "huge.nii");
    let mut b = std::fs::read(&p).unwrap();
    for d in 0..3 {
        b[42 + 2 * d..44 + 2 * d].copy_from_slice(&30000i16.to_le_bytes());
    }
    std::fs::write(&p, b).unwrap();
    read_err(&p);
}

#[test]
fn tiff_with_pages_of_different_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("mixed.tif");
    {
        let f = std::fs::File::create(&p).unwrap();
        let mut enc = TiffEncoder::new(f).unwrap();
        enc.write_image::<colortype::Gray8>(4, 3, &[0u8; 12])
            .unwrap();
        enc.write_image::<colortype::Gray8>(5, 3, &[0u8; 15])
            .unwrap();
    }
    let msg = read_err(&p);
    assert!(msg.contains("5 x 3") && msg.contains("4 x 3"), "{msg}");

    // Pages of different types.
    let p = dir.path().join("types.tif");
    {
        let f = std::fs::File::create(&p).unwrap();
        let mut enc = TiffEncoder::new(f).unwrap();
        enc.write_image::<colortype::Gray8>(2, 2, &[0u8; 4])
            .unwrap();
        enc.write_image::<colortype::Gray16>(2, 2, &[0u16; 4])
            .unwrap();
    }
    read_err(&p);

    // RGB is refused by name.
    let p = dir.path().join("rgb.tif");
    {
        let f = std::fs::File::create(&p).unwrap();
        let mut enc = TiffEncoder::new(f).unwrap();
        enc.write_image::<colortype::RGB8>(2, 2, &[0u8; 12])
            .unwrap();
    }
    assert!(read_err(&p).contains("RGB"));
}

#[test]
fn slice_folder_with_slices_of_different_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let g = Geometry::new([4, 3, 2], [1.0; 3], LengthUnit::Micrometre).unwrap();
    write_volume(&a, &AnyVolume::U8(Volume::zeros(g))).unwrap();
    let b = dir.path().join("b");
    let g = Geometry::new([5, 3, 1], [1.0; 3], LengthUnit::Micrometre).unwrap();
    write_volume(&b, &AnyVolume::U8(Volume::zeros(g))).unwrap();
    std::fs::rename(b.join("slice_0000.png"), a.join("slice_0002.png")).unwrap();
    let msg = read_volume(&a).unwrap_err().to_string();
    assert!(
        msg.contains("slice_0002.png") && msg.contains("5 x 3"),
        "{msg}"
    );
    // An empty folder and a folder of mixed kinds.
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    assert!(read_err(&empty).contains("no PNG or TIFF"));
    std::fs::write(a.join("x.tif"), b"II*\0").unwrap();
    assert!(read_err(&a).contains("mixes"));
}

#[test]
fn nrrd_with_unknown_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("enc.nrrd");
    std::fs::write(
        &p,
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: bzip2\n\n\0\0\0\0\0\0\0\0",
    )
    .unwrap();
    let msg = read_err(&p);
    assert!(msg.contains("bzip2"), "{msg}");
}

#[test]
fn missing_files() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "none.nii",
        "none.nii.gz",
        "none.nrrd",
        "none.nhdr",
        "none.mha",
        "none.mhd",
        "none.tif",
        "none_folder",
    ] {
        let p = dir.path().join(name);
        let msg = read_err(&p);
        assert!(msg.contains("No such file"), "{msg}");
        assert!(matches!(read_volume(&p), Err(IoError::Read { .. })));
    }
    // A .mhd whose .raw is missing names the .raw.
    let p = valid(dir.path(), "lonely.mhd");
    std::fs::remove_file(dir.path().join("lonely.raw")).unwrap();
    assert!(
        read_volume(&p)
            .unwrap_err()
            .to_string()
            .contains("lonely.raw")
    );
}

#[test]
fn garbage_and_wrong_magic() {
    let dir = tempfile::tempdir().unwrap();
    let garbage: Vec<u8> = (0..2000u32)
        .map(|n| (n.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    for name in [
        "g.nii", "g.nii.gz", "g.nrrd", "g.nhdr", "g.mha", "g.mhd", "g.tif",
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, &garbage).unwrap();
        read_err(&p);
        std::fs::write(&p, b"").unwrap();
        read_err(&p);
        std::fs::write(&p, b"hello world\n").unwrap();
        read_err(&p);
    }
    // The right container with the wrong content.
    let p = valid(dir.path(), "magic.nii");
    let mut b = std::fs::read(&p).unwrap();
    b[344..348].copy_from_slice(b"xyz\0");
    std::fs::write(&p, b).unwrap();
    assert!(read_err(&p).contains("magic"));
    let p = dir.path().join("png");
    std::fs::create_dir(&p).unwrap();
    std::fs::write(p.join("slice_0.png"), &garbage).unwrap();
    let msg = read_volume(&p).unwrap_err().to_string();
    assert!(msg.contains("slice_0.png") && !msg.contains('\n'), "{msg}");
    // An unknown extension.
    let p = dir.path().join("x.jpg");
    std::fs::write(&p, &garbage).unwrap();
    assert!(read_err(&p).contains("unknown volume format"));
}

/// Cut a valid file at every length and flip bytes: errors, never a panic.
#[test]
fn no_panic_on_any_prefix_or_corruption() {
    let dir = tempfile::tempdir().unwrap();
    let g = Geometry::new([3, 2, 2], [0.5, 0.5, 1.0], LengthUnit::Micrometre).unwrap();
    let v = AnyVolume::U8(Volume::from_vec(g, (0..12).collect()).unwrap());
    for name in ["p.nii", "p.nii.gz", "p.nrrd", "p.mha", "p.tif"] {
        let p = dir.path().join(name);
        write_volume(&p, &v).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let cut = dir.path().join(format!("cut_{name}"));
        for len in 0..bytes.len() {
            std::fs::write(&cut, &bytes[..len]).unwrap();
            let _ = read_volume(&cut);
        }
        for at in 0..bytes.len() {
            let mut b = bytes.clone();
            b[at] ^= 0xa5;
            std::fs::write(&cut, &b).unwrap();
            if let Err(e) = read_volume(&cut) {
                assert!(!e.to_string().contains('\n'));
            }
        }
    }
}

#[test]
fn failed_writes_leave_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let files = |d: &Path| std::fs::read_dir(d).unwrap().count();

    // A float volume cannot become PNG slices: no folder is created.
    let g = Geometry::new([2, 2, 2], [1.0; 3], LengthUnit::Millimetre).unwrap();
    let f = AnyVolume::F32(Volume::zeros(g.clone()));
    let out = dir.path().join("slices");
    let msg = write_volume(&out, &f).unwrap_err().to_string();
    assert!(msg.contains("f32") && msg.contains("slices"), "{msg}");
    assert!(!out.exists());
    assert_eq!(files(dir.path()), 0);

    // A NIfTI-1 cannot hold 40000 voxels along x: the old file is untouched.
    let target = valid(dir.path(), "keep.nii");
    let before = std::fs::read(&target).unwrap();
    let wide = Geometry::new([40000, 1, 1], [1.0; 3], LengthUnit::Millimetre).unwrap();
    let e = write_volume(&target, &AnyVolume::U8(Volume::zeros(wide))).unwrap_err();
    assert!(e.to_string().contains("keep.nii"));
    assert_eq!(std::fs::read(&target).unwrap(), before);
    assert_eq!(files(dir.path()), 1);

    // A folder that does not exist.
    let p = dir.path().join("no/such/dir/out.nrrd");
    let e = write_volume(&p, &volume()).unwrap_err().to_string();
    assert!(e.contains("out.nrrd") && !e.contains('\n'), "{e}");
    assert_eq!(files(dir.path()), 1);
}

#[cfg(unix)]
#[test]
fn written_files_get_ordinary_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let p = valid(dir.path(), "perm.nrrd");
    let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
    assert_ne!(mode & 0o044, 0, "mode {mode:o}: others cannot read");
}
