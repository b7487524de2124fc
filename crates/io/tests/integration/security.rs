//! Hostile files: data files outside the header's folder, negative skips,
//! headers that ask for absurd allocations, bad spacing, uploads read from
//! memory. Each gives a one-line error (or reads what it should), never a
//! read outside the folder, a panic or an abort.
use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};
use interslice_io::{
    Format, ReadLimits, read_bytes, read_header, read_header_bytes, read_labels_bytes, read_volume,
    read_volume_with, write_volume,
};
use std::io::Write;
use std::path::Path;

fn volume() -> AnyVolume {
    let g = Geometry::new([6, 5, 4], [0.5, 0.5, 1.0], LengthUnit::Micrometre).unwrap();
    let data = (0..g.len()).map(|n| (n % 97 + 1) as u16).collect();
    AnyVolume::U16(Volume::from_vec(g, data).unwrap())
}

fn raw_bytes() -> Vec<u8> {
    volume().to_le_bytes()
}

const NHDR: &str = "NRRD0004\ntype: unsigned short\ndimension: 3\nsizes: 6 5 4\nspacings: 0.5 0.5 1\nendian: little\nencoding: raw\ndata file: DATA\n";
const MHD: &str = "ObjectType = Image\nNDims = 3\nBinaryData = True\nCompressedData = False\nElementSpacing = 0.5 0.5 1\nDimSize = 6 5 4\nHeaderSize = SKIP\nElementType = MET_USHORT\nElementDataFile = DATA\n";

fn err(path: &Path) -> String {
    let e = read_volume(path).expect_err("must fail").to_string();
    assert!(!e.contains('\n'), "{e}");
    e
}

/// A folder `root/inner` holding a header; `root/secret.raw` is outside it.
fn layout() -> (tempfile::TempDir, std::path::PathBuf) {
    let root = tempfile::tempdir().unwrap();
    let inner = root.path().join("inner");
    std::fs::create_dir(&inner).unwrap();
    std::fs::write(root.path().join("secret.raw"), vec![0xC3u8; 240]).unwrap();
    (root, inner)
}

#[test]
fn detached_data_must_stay_in_the_header_folder() {
    let (root, inner) = layout();
    let secret = root.path().join("secret.raw");
    std::os::unix::fs::symlink("../secret.raw", inner.join("link.raw")).unwrap();
    std::os::unix::fs::symlink("..", inner.join("up")).unwrap();
    std::os::unix::fs::symlink("../nowhere.raw", inner.join("dangling.raw")).unwrap();
    let refs = [
        "../secret.raw".to_string(),
        secret.display().to_string(),
        "link.raw".into(),
        "up/secret.raw".into(),
        "sub/../../secret.raw".into(),
        "/dev/zero".into(),
    ];
    for r in &refs {
        for (name, text) in [
            ("h.nhdr", NHDR.replace("DATA", r)),
            ("h.mhd", MHD.replace("DATA", r).replace("SKIP", "0")),
            ("h2.mhd", MHD.replace("DATA", r).replace("SKIP", "-1")),
        ] {
            let h = inner.join(name);
            std::fs::write(&h, text).unwrap();
            let e = err(&h);
            assert!(e.contains("not inside the header's folder"), "{r}: {e}");
        }
    }
    // The refusal does not say whether the outside file exists: a missing
    // outside file and a dangling link give the same message as a real one.
    let msg = |r: &str| {
        let h = inner.join("m.nhdr");
        std::fs::write(&h, NHDR.replace("DATA", r)).unwrap();
        err(&h).replace(r, "R")
    };
    assert_eq!(msg("../secret.raw"), msg("../absent.raw"));
    assert_eq!(msg("link.raw"), msg("dangling.raw"));
    // Inside the folder (also below it, and through a link that stays inside) is read.
    std::fs::create_dir(inner.join("sub")).unwrap();
    std::fs::write(inner.join("sub/d.raw"), raw_bytes()).unwrap();
    std::os::unix::fs::symlink("sub/d.raw", inner.join("inside.raw")).unwrap();
    for r in ["sub/d.raw", "inside.raw", "./sub/d.raw"] {
        let h = inner.join("ok.nhdr");
        std::fs::write(&h, NHDR.replace("DATA", r)).unwrap();
        assert_eq!(voxels(&h), raw_bytes(), "{r}");
        let h = inner.join("ok.mhd");
        std::fs::write(&h, MHD.replace("DATA", r).replace("SKIP", "-1")).unwrap();
        assert_eq!(voxels(&h), raw_bytes(), "{r}");
    }
}

#[test]
fn negative_skips_other_than_minus_one_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("d.raw"), raw_bytes()).unwrap();
    let h = dir.path().join("h.mhd");
    std::fs::write(&h, MHD.replace("DATA", "d.raw").replace("SKIP", "-5")).unwrap();
    assert!(err(&h).contains("bad HeaderSize '-5'"));
    let h = dir.path().join("h.nhdr");
    std::fs::write(
        &h,
        NHDR.replace("DATA", "d.raw")
            .replace("encoding: raw", "encoding: raw\nbyte skip: -7"),
    )
    .unwrap();
    assert!(err(&h).contains("bad NRRD 'byte skip'"));
    std::fs::write(
        &h,
        NHDR.replace("DATA", "d.raw")
            .replace("encoding: raw", "encoding: gzip\nbyte skip: -1"),
    )
    .unwrap();
    assert!(err(&h).contains("bad NRRD 'byte skip'"));
    // -1 on a data file inside the folder reads its tail.
    let mut tail = vec![7u8; 100];
    tail.extend(raw_bytes());
    std::fs::write(dir.path().join("d.raw"), tail).unwrap();
    std::fs::write(
        &h,
        NHDR.replace("DATA", "d.raw")
            .replace("encoding: raw", "encoding: raw\nbyte skip: -1"),
    )
    .unwrap();
    assert_eq!(voxels(&h), raw_bytes());
}

/// The voxels read from `path`, as little-endian bytes.
fn voxels(path: &Path) -> Vec<u8> {
    read_volume(path).unwrap().to_le_bytes()
}

#[test]
fn slice_links_out_of_the_folder_are_refused() {
    let root = tempfile::tempdir().unwrap();
    let s = root.path().join("s");
    write_volume(
        &s,
        &AnyVolume::U8(
            Volume::from_vec(
                Geometry::new([6, 5, 3], [1.0; 3], LengthUnit::Micrometre).unwrap(),
                (0..90).map(|n| n as u8).collect(),
            )
            .unwrap(),
        ),
    )
    .unwrap();
    std::fs::copy(s.join("slice_0000.png"), root.path().join("outside.png")).unwrap();
    std::fs::remove_file(s.join("slice_0001.png")).unwrap();
    std::os::unix::fs::symlink("../outside.png", s.join("slice_0001.png")).unwrap();
    let e = err(&s);
    assert!(e.contains("leads out of the folder"), "{e}");
    // Same refusal for a link to nothing outside.
    std::fs::remove_file(s.join("slice_0001.png")).unwrap();
    std::os::unix::fs::symlink("../absent.png", s.join("slice_0001.png")).unwrap();
    assert!(err(&s).contains("leads out of the folder"));
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// A NIfTI header (352 bytes) claiming `dims` of `datatype`.
fn nifti_header(dims: [i16; 3], datatype: i16, bitpix: i16, pixdim: [f32; 3]) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("h.nii");
    write_volume(&p, &volume()).unwrap();
    let mut b = std::fs::read(&p).unwrap()[..352].to_vec();
    for (i, d) in dims.iter().enumerate() {
        b[42 + 2 * i..44 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    b[70..72].copy_from_slice(&datatype.to_le_bytes());
    b[72..74].copy_from_slice(&bitpix.to_le_bytes());
    for (i, s) in pixdim.iter().enumerate() {
        b[80 + 4 * i..84 + 4 * i].copy_from_slice(&s.to_le_bytes());
    }
    b
}

#[test]
fn the_header_is_checked_against_the_grid_before_decoding() {
    // 4096 x 4096 x 16 f64: 2 GiB decoded, from a gzip stream of a few MB.
    let mut b = nifti_header([4096, 4096, 16], 64, 64, [1.0; 3]);
    b.extend(std::iter::repeat_n(0u8, 4 << 20));
    let upload = gzip(&b);
    assert!(upload.len() < 100_000);
    let h = read_header_bytes("seg.nii.gz", &upload).unwrap();
    assert_eq!(h.geometry.dims, [4096, 4096, 16]);
    assert_eq!(h.data_bytes, 4096 * 4096 * 16 * 8);
    assert_eq!(h.format, Format::NiftiGz);
    let e = read_bytes("seg.nii.gz", &upload, &ReadLimits::for_grid([6, 5, 4]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("do not match the expected [6, 5, 4]"), "{e}");
    // The same file on disk with the default limits: truncated, found after
    // inflating only what is there.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.nii.gz");
    std::fs::write(&p, &upload).unwrap();
    assert!(err(&p).contains("truncated"));
    // Past the voxel limit: refused on the header.
    let limits = ReadLimits {
        max_voxels: 1000,
        ..ReadLimits::default()
    };
    let e = read_volume_with(&p, &limits).unwrap_err().to_string();
    assert!(
        e.contains("too large") && e.contains("the limit is 1000"),
        "{e}"
    );
    // And past the byte limit.
    let limits = ReadLimits {
        max_bytes: 1 << 20,
        ..ReadLimits::default()
    };
    let e = read_volume_with(&p, &limits).unwrap_err().to_string();
    assert!(e.contains("voxel data is too large"), "{e}");
}

#[test]
fn what_a_gzip_stream_may_inflate_is_bounded() {
    let dir = tempfile::tempdir().unwrap();
    // A byte skip inside a gzip stream counts towards the bound.
    let p = dir.path().join("skip.nrrd");
    let mut b = b"NRRD0004\ntype: unsigned short\ndimension: 3\nsizes: 6 5 4\nencoding: gzip\nbyte skip: 100000000000\n\n".to_vec();
    b.extend(gzip(&raw_bytes()));
    std::fs::write(&p, b).unwrap();
    assert!(err(&p).contains("more than the"));
    // So do NIfTI extensions inside a gzip stream.
    let mut h = nifti_header([6, 5, 4], 512, 16, [1.0; 3]);
    h[108..112].copy_from_slice(&2e9f32.to_le_bytes());
    let e = read_bytes("x.nii.gz", &gzip(&h), &ReadLimits::for_grid([6, 5, 4]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("more than the"), "{e}");
}

#[test]
fn uploads_refuse_every_external_reference() {
    let nii = {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.nii.gz");
        write_volume(&p, &volume()).unwrap();
        std::fs::read(&p).unwrap()
    };
    let labels = read_labels_bytes("a.nii.gz", &nii, &ReadLimits::for_grid([6, 5, 4])).unwrap();
    assert_eq!(labels.geometry().dims, [6, 5, 4]);
    for (name, bytes) in [
        ("a.nhdr", NHDR.replace("DATA", "a.raw").into_bytes()),
        (
            "a.mhd",
            MHD.replace("DATA", "a.raw")
                .replace("SKIP", "0")
                .into_bytes(),
        ),
        ("a.nrrd", NHDR.replace("DATA", "/etc/passwd").into_bytes()),
        ("a.nrrd", NHDR.replace("DATA", "a.raw").into_bytes()),
        (
            "a.mha",
            MHD.replace("DATA", "/etc/passwd")
                .replace("SKIP", "0")
                .into_bytes(),
        ),
        (
            "a.mha",
            MHD.replace("DATA", "../a.raw")
                .replace("SKIP", "-1")
                .into_bytes(),
        ),
        ("slices", Vec::new()),
    ] {
        let e = read_bytes(name, &bytes, &ReadLimits::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(name), "{e}");
        assert!(!e.contains("/tmp") && !e.contains("No such file"), "{e}");
        assert!(
            e.contains("self-contained") || e.contains("unknown volume format"),
            "{name}: {e}"
        );
    }
}

#[test]
fn a_png_claiming_2_pow_31_pixels_is_an_error_not_an_abort() {
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("s");
    write_volume(
        &s,
        &AnyVolume::U8(
            Volume::from_vec(
                Geometry::new([6, 5, 2], [1.0; 3], LengthUnit::Micrometre).unwrap(),
                vec![1; 60],
            )
            .unwrap(),
        ),
    )
    .unwrap();
    for (slice, wh) in [
        ("slice_0000.png", [0x7FFF_FFFFu32, 1]),
        ("slice_0001.png", [0x7FFF_FFFF, 0x7FFF_FFFF]),
    ] {
        let p = s.join(slice);
        let mut b = std::fs::read(&p).unwrap();
        b[16..20].copy_from_slice(&wh[0].to_be_bytes());
        b[20..24].copy_from_slice(&wh[1].to_be_bytes());
        let mut crc = flate2::Crc::new();
        crc.update(&b[12..29]);
        b[29..33].copy_from_slice(&crc.sum().to_be_bytes());
        std::fs::write(&p, &b).unwrap();
        let e = err(&s);
        assert!(
            e.contains("more than the file can hold") || e.contains("too large"),
            "{e}"
        );
        std::fs::write(&p, b).unwrap();
    }
}

/// A one-page 8-bit TIFF with the given description.
fn tiff_page(desc: &str, xres: (u32, u32)) -> Vec<u8> {
    use tiff::encoder::{Rational, TiffEncoder, colortype};
    use tiff::tags::Tag;
    let mut c = std::io::Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut c).unwrap();
        let mut img = enc.new_image::<colortype::Gray8>(6, 5).unwrap();
        img.encoder()
            .write_tag(Tag::ImageDescription, desc)
            .unwrap();
        img.encoder()
            .write_tag(
                Tag::XResolution,
                Rational {
                    n: xres.0,
                    d: xres.1,
                },
            )
            .unwrap();
        img.write_data(&[1u8; 30]).unwrap();
    }
    c.into_inner()
}

#[test]
fn a_tiff_tag_count_of_0xffffffff_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = tiff_page("ImageJ=1.11a\nimages=1\nunit=micron\n", (2, 1));
    let ifd = u32::from_le_bytes(b[4..8].try_into().unwrap()) as usize;
    let n = u16::from_le_bytes(b[ifd..ifd + 2].try_into().unwrap()) as usize;
    let e = (0..n)
        .map(|i| ifd + 2 + 12 * i)
        .find(|&e| u16::from_le_bytes(b[e..e + 2].try_into().unwrap()) == 270)
        .unwrap();
    b[e + 4..e + 8].copy_from_slice(&u32::MAX.to_le_bytes());
    let p = dir.path().join("d.tif");
    std::fs::write(&p, &b).unwrap();
    // The description cannot be read: the stack is read without it, or refused.
    match read_volume(&p) {
        Ok(v) => assert_eq!(v.geometry().dims, [6, 5, 1]),
        Err(e) => assert!(!e.to_string().contains('\n')),
    }
    // A page claiming 2^31-1 x 2^31-1 pixels.
    let mut b = tiff_page("x", (1, 1));
    let ifd = u32::from_le_bytes(b[4..8].try_into().unwrap()) as usize;
    let n = u16::from_le_bytes(b[ifd..ifd + 2].try_into().unwrap()) as usize;
    for tag in [256u16, 257] {
        let e = (0..n)
            .map(|i| ifd + 2 + 12 * i)
            .find(|&e| u16::from_le_bytes(b[e..e + 2].try_into().unwrap()) == tag)
            .unwrap();
        b[e + 2..e + 4].copy_from_slice(&4u16.to_le_bytes());
        b[e + 8..e + 12].copy_from_slice(&0x7FFF_FFFFu32.to_le_bytes());
    }
    std::fs::write(&p, &b).unwrap();
    let e = err(&p);
    assert!(e.contains("d.tif"), "{e}");
}

#[test]
fn bad_spacing_is_an_error_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    for s in [0.0f32, -1.0, f32::NAN, f32::INFINITY] {
        let mut b = nifti_header([6, 5, 4], 512, 16, [0.5, s, 1.0]);
        b.extend(raw_bytes());
        let p = dir.path().join("s.nii");
        std::fs::write(&p, &b).unwrap();
        assert!(err(&p).contains("pixdim[2]"), "{s}");
    }
    // A 2D NIfTI has no z spacing: 1, not an error.
    let mut b = nifti_header([6, 5, 1], 512, 16, [0.5, 0.5, 0.0]);
    b[40..42].copy_from_slice(&2i16.to_le_bytes());
    b.extend(&raw_bytes()[..60]);
    let p = dir.path().join("2d.nii");
    std::fs::write(&p, &b).unwrap();
    assert_eq!(read_volume(&p).unwrap().geometry().spacing, [0.5, 0.5, 1.0]);

    std::fs::write(dir.path().join("d.raw"), raw_bytes()).unwrap();
    for (name, text, needle) in [
        (
            "a.nhdr",
            NHDR.replace("0.5 0.5 1", "0.5 0 1"),
            "spacing of axis 1",
        ),
        (
            "b.nhdr",
            NHDR.replace("0.5 0.5 1", "0.5 nan 1"),
            "spacing of axis 1",
        ),
        (
            "c.nhdr",
            NHDR.replace("0.5 0.5 1", "0.5 -2 1"),
            "spacing of axis 1",
        ),
        (
            "d.nhdr",
            NHDR.replace(
                "spacings: 0.5 0.5 1",
                "space: left-posterior-superior\nspace directions: (1,0,0) (1,0,0) (0,0,1)",
            ),
            "degenerate",
        ),
        (
            "e.nhdr",
            NHDR.replace(
                "spacings: 0.5 0.5 1",
                "space: left-posterior-superior\nspace directions: (1,0,0) (0,0,0) (0,0,1)",
            ),
            "zero or invalid direction",
        ),
        (
            "a.mhd",
            MHD.replace("SKIP", "0").replace("0.5 0.5 1", "0.5 -0.5 1"),
            "ElementSpacing -0.5",
        ),
        (
            "b.mhd",
            MHD.replace("SKIP", "0").replace("0.5 0.5 1", "0 0.5 1"),
            "ElementSpacing 0",
        ),
        (
            "c.mhd",
            MHD.replace("SKIP", "0").replace("0.5 0.5 1", "nan 0.5 1"),
            "ElementSpacing NaN",
        ),
        (
            "d.mhd",
            MHD.replace("SKIP", "0").replace(
                "ElementSpacing",
                "TransformMatrix = 1 0 0 1 0 0 0 0 1\nElementSpacing",
            ),
            "degenerate",
        ),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, text.replace("DATA", "d.raw")).unwrap();
        let e = err(&p);
        assert!(e.contains(needle), "{name}: {e}");
    }
    for (desc, xres, needle) in [
        (
            "ImageJ=1.11a\nimages=1\nspacing=0\nunit=micron\n",
            (2, 1),
            "spacing=0",
        ),
        (
            "ImageJ=1.11a\nimages=1\nspacing=-2\nunit=micron\n",
            (2, 1),
            "spacing=-2",
        ),
        (
            "ImageJ=1.11a\nimages=1\nspacing=nan\nunit=micron\n",
            (2, 1),
            "spacing=nan",
        ),
        (
            "ImageJ=1.11a\nimages=1\nspacing=1\nunit=micron\n",
            (0, 1),
            "XResolution",
        ),
    ] {
        let p = dir.path().join("s.tif");
        std::fs::write(&p, tiff_page(desc, xres)).unwrap();
        let e = err(&p);
        assert!(e.contains(needle), "{desc:?}: {e}");
    }
    // Without ImageJ metadata a TIFF has no spacing: 1.
    std::fs::write(dir.path().join("n.tif"), tiff_page("no metadata", (0, 1))).unwrap();
    assert_eq!(
        read_volume(&dir.path().join("n.tif"))
            .unwrap()
            .geometry()
            .spacing,
        [1.0; 3]
    );
}

#[test]
fn headers_are_read_without_the_data() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "h.nii", "h.nii.gz", "h.nrrd", "h.mha", "h.mhd", "h.tif", "h",
    ] {
        let p = dir.path().join(name);
        let v = volume();
        write_volume(&p, &v).unwrap();
        let h = read_header(&p).unwrap();
        assert_eq!(h.geometry, *v.geometry(), "{name}");
        assert_eq!(h.format, Format::of_path(&p).unwrap(), "{name}");
        assert_eq!(h.data_bytes, 240, "{name}");
    }
    // A header whose data is missing still reads as a header.
    let p = dir.path().join("cut.nii");
    std::fs::write(&p, nifti_header([6, 5, 4], 512, 16, [1.0; 3])).unwrap();
    assert_eq!(read_header(&p).unwrap().geometry.dims, [6, 5, 4]);
    assert!(err(&p).contains("truncated"));
}

#[test]
fn absurd_segmentation_layers_and_ascii_counts_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("l.seg.nrrd");
    std::fs::write(
        &p,
        "NRRD0004\ntype: unsigned char\ndimension: 4\nsizes: 100000 1 1 1\nkinds: list domain domain domain\nencoding: raw\nSegment0_LabelValue:=1\n\n",
    )
    .unwrap();
    let mut b = std::fs::read(&p).unwrap();
    b.extend(vec![0u8; 100000]);
    std::fs::write(&p, b).unwrap();
    assert!(err(&p).contains("layers is not supported"));
    let p = dir.path().join("a.nrrd");
    std::fs::write(
        &p,
        "NRRD0004\ntype: double\ndimension: 3\nsizes: 1024 1024 64\nencoding: ascii\n\n1 2 3\n",
    )
    .unwrap();
    assert!(err(&p).contains("truncated"));
}
