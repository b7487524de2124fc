//! Mutation test of every reader, run by `scripts/test-mutation.sh` with the
//! `interslice` binary (`INTERSLICE_BIN`): thousands of seeded variants of
//! valid files (truncations, byte flips, hostile header values, huge dims,
//! bad spacing, data files outside the folder, compression bombs) are read
//! by `interslice info` (contours files by `interslice contours rasterize`)
//! under a 4 GiB address-space limit and a timeout. Each must succeed, or
//! fail with exit status 1 and one line `error: ...`: never a panic, an
//! abort, a hang, or a volume read from outside the variant's folder.
//!
//! A canary file outside every variant's folder holds bytes that no seed
//! contains; a volume whose every voxel is the canary's value was read from
//! it. Variants that name an outside file must fail.
//!
//! `MUTATION_SEED` and `MUTATION_VARIANTS` (default 3000) change the set.
use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The canary's byte: 0xC3 (195 as u8, 50115 as u16); no seed holds it.
const CANARY: u8 = 0xC3;
/// Address-space limit of each run (KiB).
const ULIMIT_KIB: u64 = 4 * 1024 * 1024;
/// Longest a run may take (a debug build on a busy machine).
const TIMEOUT: Duration = Duration::from_secs(30);

/// One file to read, in its own folder.
struct Variant {
    /// What was done to it (printed on failure).
    what: String,
    /// Files of the folder: relative name and bytes.
    files: Vec<(String, Vec<u8>)>,
    /// Symbolic links of the folder: name and target.
    links: Vec<(String, String)>,
    /// The name read (a file of the folder, or "." for the folder itself).
    read: String,
    /// True when the read must fail (it names something outside).
    must_fail: bool,
    /// True for a contours file.
    contours: bool,
}

fn variant(what: impl Into<String>, name: &str, bytes: Vec<u8>) -> Variant {
    Variant {
        what: what.into(),
        files: vec![(name.to_string(), bytes)],
        links: Vec::new(),
        read: name.to_string(),
        must_fail: false,
        contours: false,
    }
}

fn seed_volume() -> AnyVolume {
    let g = Geometry::new([6, 5, 4], [0.5, 0.5, 1.0], LengthUnit::Micrometre).unwrap();
    let data = (0..g.len()).map(|n| (n % 97 + 1) as u16).collect();
    AnyVolume::U16(Volume::from_vec(g, data).unwrap())
}

fn seed_u8() -> AnyVolume {
    let g = Geometry::new([6, 5, 4], [0.5, 0.5, 1.0], LengthUnit::Micrometre).unwrap();
    let data = (0..g.len()).map(|n| (n % 97 + 1) as u8).collect();
    AnyVolume::U8(Volume::from_vec(g, data).unwrap())
}

/// Bytes of a volume written under `name`.
fn written(name: &str, v: &AnyVolume) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    interslice_io::write_volume(&p, v).unwrap();
    std::fs::read(&p).unwrap()
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn zlib(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// Hostile values for a numeric header field.
const HOSTILE: &[&str] = &[
    "0",
    "-1",
    "-2",
    "-1000000",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "1e-320",
    "4294967295",
    "2147483647",
    "18446744073709551615",
    "99999999999999999999999",
    "65536",
    "1.5",
    "",
    "x",
];

/// Hostile values for a data file reference (`{abs}` is the canary's path).
const REFERENCES: &[&str] = &[
    "../../canary.raw",
    "../canary.raw",
    "{abs}",
    "sub/../../../canary.raw",
    "./../../canary.raw",
    "link.raw",
    "up/canary.raw",
    "/dev/zero",
    "/proc/self/environ",
    "LIST",
    "slice%03d.raw 0 3 1",
    "missing.raw",
    "",
];

/// Replace the value of a random `key<sep>value` line of a text header.
fn mutate_text_header(
    rng: &mut ChaCha8Rng,
    text: &str,
    sep: &str,
    values: &[&str],
) -> (String, String) {
    let lines: Vec<&str> = text.lines().collect();
    let fields: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].contains(sep))
        .collect();
    let i = fields[rng.gen_range(0..fields.len())];
    let key = lines[i].split(sep).next().unwrap();
    let value = values[rng.gen_range(0..values.len())];
    // A vector field gets the value once or in every position.
    let n = lines[i]
        .split(sep)
        .nth(1)
        .unwrap_or("")
        .split_whitespace()
        .count()
        .max(1);
    let v = if rng.gen_bool(0.5) {
        vec![value; n].join(" ")
    } else {
        value.to_string()
    };
    let mut out: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    out[i] = format!("{key}{sep}{v}");
    (out.join("\n") + "\n", format!("{key} = '{v}'"))
}

fn truncations(rng: &mut ChaCha8Rng, name: &str, bytes: &[u8], n: usize, out: &mut Vec<Variant>) {
    for _ in 0..n {
        let cut = rng.gen_range(0..bytes.len());
        out.push(variant(
            format!("{name} cut at {cut}"),
            name,
            bytes[..cut].to_vec(),
        ));
    }
}

fn flips(
    rng: &mut ChaCha8Rng,
    name: &str,
    bytes: &[u8],
    head: usize,
    n: usize,
    out: &mut Vec<Variant>,
) {
    for _ in 0..n {
        let mut b = bytes.to_vec();
        let k = rng.gen_range(1..=4);
        let mut at = Vec::new();
        for _ in 0..k {
            let range = if rng.gen_bool(0.7) {
                head.min(b.len())
            } else {
                b.len()
            };
            let i = rng.gen_range(0..range);
            let x: u8 = match rng.gen_range(0..4) {
                0 => 0xFF,
                1 => 0x00,
                2 => 0x7F,
                _ => rng.r#gen(),
            };
            b[i] = x;
            at.push(i);
        }
        out.push(variant(format!("{name} bytes {at:?} changed"), name, b));
    }
}

/// NIfTI variants: header fields set to hostile values, plain and gzip.
fn nifti(rng: &mut ChaCha8Rng, n: usize, out: &mut Vec<Variant>) {
    let plain = written("t.nii", &seed_volume());
    let gz = written("t.nii.gz", &seed_volume());
    truncations(rng, "t.nii", &plain, n / 10, out);
    truncations(rng, "t.nii.gz", &gz, n / 10, out);
    flips(rng, "t.nii", &plain, 352, n / 5, out);
    flips(rng, "t.nii.gz", &gz, 64, n / 10, out);
    // (offset, size) of header fields: dims, datatype, bitpix, pixdim,
    // vox_offset, slope, inter, qform/sform codes, quaternion, srow.
    let fields: &[(usize, usize, bool)] = &[
        (40, 2, false),
        (42, 2, false),
        (44, 2, false),
        (46, 2, false),
        (48, 2, false),
        (70, 2, false),
        (72, 2, false),
        (80, 4, true),
        (84, 4, true),
        (88, 4, true),
        (108, 4, true),
        (112, 4, true),
        (116, 4, true),
        (252, 2, false),
        (254, 2, false),
        (256, 4, true),
        (280, 4, true),
        (296, 4, true),
    ];
    for k in 0..n / 2 {
        let mut b = plain.clone();
        let (off, size, float) = fields[rng.gen_range(0..fields.len())];
        let what = if float {
            let v: f32 = [
                0.0,
                -1.0,
                f32::NAN,
                f32::INFINITY,
                -f32::INFINITY,
                1e38,
                1e-40,
                2e9,
            ][rng.gen_range(0..8)];
            b[off..off + 4].copy_from_slice(&v.to_le_bytes());
            format!("float at {off} = {v}")
        } else {
            let v: i16 =
                [0, -1, 1, 2, 7, 8, 32767, -32768, 128, 1024, 2304, 64, 3][rng.gen_range(0..13)];
            b[off..off + size].copy_from_slice(&v.to_le_bytes());
            format!("i16 at {off} = {v}")
        };
        if k % 2 == 0 {
            out.push(variant(format!("t.nii {what}"), "t.nii", b));
        } else {
            out.push(variant(format!("t.nii.gz {what}"), "t.nii.gz", gzip(&b)));
        }
    }
    // Huge dims in a tiny file, and a compression bomb: a stream far longer
    // than the header's dims.
    let mut big = plain.clone();
    for (i, d) in [(40, 3i16), (42, 32767), (44, 32767), (46, 32767)] {
        big[i..i + 2].copy_from_slice(&d.to_le_bytes());
    }
    out.push(variant("t.nii.gz claims 32767^3", "t.nii.gz", gzip(&big)));
    big[70..72].copy_from_slice(&64i16.to_le_bytes());
    out.push(variant("t.nii claims 32767^3 f64", "t.nii", big));
    let mut bomb = plain[..352].to_vec();
    bomb.extend(std::iter::repeat_n(0u8, 32 << 20));
    out.push(variant(
        "t.nii.gz with 32 MiB of zeros after the data",
        "t.nii.gz",
        gzip(&bomb),
    ));
    // 4096 x 4096 x 16 f64 (2 GiB decoded) from a small stream of zeros.
    let mut claim = plain[..352].to_vec();
    for (i, d) in [(42, 4096i16), (44, 4096), (46, 16), (70, 64), (72, 64)] {
        claim[i..i + 2].copy_from_slice(&d.to_le_bytes());
    }
    claim.extend(std::iter::repeat_n(0u8, 8 << 20));
    out.push(variant(
        "t.nii.gz claims 4096x4096x16 f64",
        "t.nii.gz",
        gzip(&claim),
    ));
}

/// Text-header formats: NRRD (attached, detached) and MetaImage.
fn text_headers(rng: &mut ChaCha8Rng, n: usize, canary: &Path, out: &mut Vec<Variant>) {
    let abs = canary.display().to_string();
    let v = seed_volume();
    let nrrd = written("t.nrrd", &v);
    let mha = written("t.mha", &v);
    let data = v.to_le_bytes();
    let nhdr = "NRRD0004\ntype: unsigned short\ndimension: 3\nspace: left-posterior-superior\nsizes: 6 5 4\nspace directions: (0.5,0,0) (0,0.5,0) (0,0,1)\nendian: little\nencoding: raw\nspace origin: (0,0,0)\nbyte skip: 0\ndata file: t.raw\n";
    let mhd = "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = False\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = 0 0 0\nElementSpacing = 0.5 0.5 1\nDimSize = 6 5 4\nHeaderSize = 0\nElementType = MET_USHORT\nElementDataFile = t.raw\n";
    truncations(rng, "t.nrrd", &nrrd, n / 12, out);
    truncations(rng, "t.mha", &mha, n / 12, out);
    flips(rng, "t.nrrd", &nrrd, 300, n / 8, out);
    flips(rng, "t.mha", &mha, 400, n / 8, out);
    let head_of = |b: &[u8], end: &[u8]| {
        let i = b.windows(end.len()).position(|w| w == end).unwrap() + end.len();
        (String::from_utf8(b[..i].to_vec()).unwrap(), b[i..].to_vec())
    };
    let (nrrd_head, nrrd_data) = head_of(&nrrd, b"\n\n");
    let (mha_head, mha_data) = head_of(&mha, b"LOCAL\n");
    for k in 0..n / 2 {
        let v = match k % 4 {
            0 => {
                let (h, what) = mutate_text_header(rng, nrrd_head.trim_end(), ": ", HOSTILE);
                let mut b = (h + "\n").into_bytes();
                b.extend_from_slice(&nrrd_data);
                variant(format!("t.nrrd {what}"), "t.nrrd", b)
            }
            1 => {
                let (h, what) = mutate_text_header(rng, mha_head.trim_end(), " = ", HOSTILE);
                let mut b = h.into_bytes();
                b.extend_from_slice(&mha_data);
                variant(format!("t.mha {what}"), "t.mha", b)
            }
            2 => {
                let (h, what) = mutate_text_header(rng, nhdr, ": ", HOSTILE);
                let mut v = variant(format!("t.nhdr {what}"), "t.nhdr", h.into_bytes());
                v.files.push(("t.raw".into(), data.clone()));
                v
            }
            _ => {
                let (h, what) = mutate_text_header(rng, mhd, " = ", HOSTILE);
                let mut v = variant(format!("t.mhd {what}"), "t.mhd", h.into_bytes());
                v.files.push(("t.raw".into(), data.clone()));
                v
            }
        };
        out.push(v);
    }
    // Data files outside the folder: by path, through links, with byte skip -1.
    for r in REFERENCES {
        let r = r.replace("{abs}", &abs);
        for skip in ["0", "-1"] {
            let h = nhdr
                .replace("data file: t.raw", &format!("data file: {r}"))
                .replace("byte skip: 0", &format!("byte skip: {skip}"));
            let mut v = variant(
                format!("t.nhdr data file '{r}', byte skip {skip}"),
                "t.nhdr",
                h.into_bytes(),
            );
            let m = mhd
                .replace("ElementDataFile = t.raw", &format!("ElementDataFile = {r}"))
                .replace("HeaderSize = 0", &format!("HeaderSize = {skip}"));
            let mut w = variant(
                format!("t.mhd data file '{r}', HeaderSize {skip}"),
                "t.mhd",
                m.into_bytes(),
            );
            for x in [&mut v, &mut w] {
                x.links.push(("link.raw".into(), "../../canary.raw".into()));
                x.links.push(("up".into(), "../..".into()));
                x.must_fail = true;
            }
            out.push(v);
            out.push(w);
        }
    }
    // Compression bombs: long streams of zeros behind small dims, byte skips
    // inside a gzip stream.
    let zeros = vec![0u8; 32 << 20];
    let mut b = nrrd_head.clone().into_bytes();
    b.extend_from_slice(&gzip(&zeros));
    out.push(variant("t.nrrd gzip of 32 MiB zeros", "t.nrrd", b));
    let mut b = nrrd_head
        .replace("encoding: gzip", "encoding: gzip\nbyte skip: 1000000000000")
        .into_bytes();
    b.extend_from_slice(&nrrd_data);
    out.push(variant("t.nrrd gzip byte skip 1e12", "t.nrrd", b));
    let mut b = mha_head
        .replace("DimSize = 6 5 4", "DimSize = 1024 1024 1024")
        .into_bytes();
    b.extend_from_slice(&zlib(&zeros));
    out.push(variant("t.mha 1024^3 from 32 MiB of zeros", "t.mha", b));
}

/// TIFF stacks and slice folders (PNG, TIFF), with hostile tags and headers.
fn images(rng: &mut ChaCha8Rng, n: usize, out: &mut Vec<Variant>) {
    let v = seed_volume();
    let tif = written("t.tif", &v);
    truncations(rng, "t.tif", &tif, n / 10, out);
    flips(rng, "t.tif", &tif, 512, n / 6, out);
    // IFD entries of the first directory: count and value set to hostile numbers.
    let ifd = u32::from_le_bytes(tif[4..8].try_into().unwrap()) as usize;
    let entries = u16::from_le_bytes(tif[ifd..ifd + 2].try_into().unwrap()) as usize;
    for _ in 0..n / 4 {
        let mut b = tif.clone();
        let e = ifd + 2 + 12 * rng.gen_range(0..entries);
        let tag = u16::from_le_bytes(b[e..e + 2].try_into().unwrap());
        let x: u32 =
            [0xFFFF_FFFF, 0x7FFF_FFFF, 0x1000_0000, 0, 1, 65535, 1 << 20][rng.gen_range(0..7)];
        let field = if rng.gen_bool(0.5) { 4 } else { 8 };
        b[e + field..e + field + 4].copy_from_slice(&x.to_le_bytes());
        out.push(variant(
            format!(
                "t.tif tag {tag} {} = {x:#x}",
                if field == 4 { "count" } else { "value" }
            ),
            "t.tif",
            b,
        ));
    }
    // ImageJ descriptions with hostile spacing and geometry.
    for d in [
        "ImageJ=1.11a\nimages=1\nspacing=0\nunit=micron\n",
        "ImageJ=1.11a\nimages=1\nspacing=-1\nunit=micron\n",
        "ImageJ=1.11a\nimages=1\nspacing=nan\nunit=micron\n",
        "ImageJ=1.11a\nimages=1\nspacing=inf\nunit=micron\n",
        "ImageJ=1.11a\nimages=1\nchannels=4294967295\n",
        "ImageJ=1.11a\nimages=1\ninterslice.direction=0,0,0,0,0,0,0,0,0\n",
        "ImageJ=1.11a\nimages=1\ninterslice.origin=nan,0,0\n",
    ] {
        out.push(variant(
            format!("t.tif description {d:?}"),
            "t.tif",
            tiff_page(6, 5, d, (1, 0)),
        ));
        out.push(variant(
            format!("t.tif description {d:?}, XResolution 0/1"),
            "t.tif",
            tiff_page(6, 5, d, (0, 1)),
        ));
    }
    // PNG slice folders: one slice mutated, or its header patched.
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("s");
    interslice_io::write_volume(&folder, &seed_u8()).unwrap();
    let mut slices: Vec<(String, Vec<u8>)> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    slices.sort();
    let folder_variant = |what: String, k: usize, bytes: Vec<u8>| {
        let mut files = slices.clone();
        files[k].1 = bytes;
        Variant {
            what,
            files,
            links: Vec::new(),
            read: ".".into(),
            must_fail: false,
            contours: false,
        }
    };
    for _ in 0..n / 4 {
        let k = rng.gen_range(0..slices.len());
        let png = &slices[k].1;
        let mut b = png.clone();
        let what = match rng.gen_range(0..3) {
            0 => {
                let cut = rng.gen_range(0..b.len());
                b.truncate(cut);
                format!("slice {k} cut at {cut}")
            }
            1 => {
                let i = rng.gen_range(0..b.len().min(200));
                b[i] = rng.r#gen();
                format!("slice {k} byte {i} changed")
            }
            _ => {
                // IHDR width/height/depth/colour, with a valid CRC.
                let (off, x): (usize, u32) = match rng.gen_range(0..4) {
                    0 => (
                        16,
                        [0x7FFF_FFFF, 0xFFFF_FFFF, 0, 100_000][rng.gen_range(0..4)],
                    ),
                    1 => (
                        20,
                        [0x7FFF_FFFF, 0xFFFF_FFFF, 0, 100_000][rng.gen_range(0..4)],
                    ),
                    _ => (
                        24,
                        [0x1000_0000u32, 0x0200_0000, 0x0402_0000, 0x1003_0000]
                            [rng.gen_range(0..4)],
                    ),
                };
                b[off..off + 4].copy_from_slice(&x.to_be_bytes());
                let mut crc = flate2::Crc::new();
                crc.update(&b[12..29]);
                b[29..33].copy_from_slice(&crc.sum().to_be_bytes());
                format!("slice {k} IHDR at {off} = {x:#x}")
            }
        };
        out.push(folder_variant(what, k, b));
    }
    // A slice that is a link out of the folder.
    let mut v = folder_variant("slice linked to outside".into(), 0, slices[0].1.clone());
    v.files.remove(1);
    v.links
        .push((slices[1].0.clone(), "../../canary.png".into()));
    v.must_fail = true;
    out.push(v);
    // A PNG claiming 2^31-1 x 2^31-1 pixels, alone and among good slices.
    let mut b = slices[0].1.clone();
    b[16..24].copy_from_slice(&[0x7F, 0xFF, 0xFF, 0xFF, 0x7F, 0xFF, 0xFF, 0xFF]);
    let mut crc = flate2::Crc::new();
    crc.update(&b[12..29]);
    b[29..33].copy_from_slice(&crc.sum().to_be_bytes());
    out.push(folder_variant(
        "slice 0 claims 2^31-1 squared".into(),
        0,
        b.clone(),
    ));
    out.push(folder_variant("slice 2 claims 2^31-1 squared".into(), 2, b));
    // Hostile interslice text chunks.
    for t in [
        "spacing=0,1,1\n",
        "spacing=-1,1,1\n",
        "spacing=nan,1,1\n",
        "spacing=inf,1,1\n",
        "spacing=1,1\ndirection=1,0,0,1,0,0,0,0,1\n",
        "origin=1e999,0,0\n",
    ] {
        out.push(folder_variant(
            format!("slice 0 text {t:?}"),
            0,
            png_slice(6, 5, t),
        ));
    }
    // TIFF slice folders.
    let tfolder: Vec<(String, Vec<u8>)> = (0..3)
        .map(|k| {
            (
                format!("s_{k}.tif"),
                tiff_page(6, 5, "ImageJ=1.11a\nimages=1\nunit=micron\n", (2, 1)),
            )
        })
        .collect();
    for _ in 0..n / 10 {
        let mut files = tfolder.clone();
        let k = rng.gen_range(0..files.len());
        let b = &mut files[k].1;
        let ifd = u32::from_le_bytes(b[4..8].try_into().unwrap()) as usize;
        let entries = u16::from_le_bytes(b[ifd..ifd + 2].try_into().unwrap()) as usize;
        let e = ifd + 2 + 12 * rng.gen_range(0..entries);
        let x: u32 = [0xFFFF_FFFF, 0x7FFF_FFFF, 0][rng.gen_range(0..3)];
        let field = if rng.gen_bool(0.5) { 4 } else { 8 };
        b[e + field..e + field + 4].copy_from_slice(&x.to_le_bytes());
        out.push(Variant {
            what: format!("TIFF slice {k} entry at {e} field {field} = {x:#x}"),
            files,
            links: Vec::new(),
            read: ".".into(),
            must_fail: false,
            contours: false,
        });
    }
}

/// A one-page 8-bit TIFF with a description and an XResolution.
fn tiff_page(w: u32, h: u32, desc: &str, xres: (u32, u32)) -> Vec<u8> {
    use tiff::encoder::{Rational, TiffEncoder, colortype};
    use tiff::tags::Tag;
    let mut c = std::io::Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut c).unwrap();
        let mut img = enc.new_image::<colortype::Gray8>(w, h).unwrap();
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
        let data: Vec<u8> = (0..w * h).map(|i| (i % 90 + 1) as u8).collect();
        img.write_data(&data).unwrap();
    }
    c.into_inner()
}

/// An 8-bit gray PNG with an `interslice` text chunk.
fn png_slice(w: u32, h: u32, text: &str) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        enc.add_text_chunk("interslice".into(), text.into())
            .unwrap();
        let mut wr = enc.write_header().unwrap();
        let data: Vec<u8> = (0..w * h).map(|i| (i % 90 + 1) as u8).collect();
        wr.write_image_data(&data).unwrap();
    }
    out
}

/// Contours files with hostile values in place of numbers.
fn contours(rng: &mut ChaCha8Rng, n: usize, out: &mut Vec<Variant>) {
    let seed = "{\n  \"format\": \"interslice-contours\",\n  \"version\": 1,\n  \"geometry\": {\"dims\":[40,32,24],\"spacing\":[0.35,0.35,0.35],\"unit\":\"um\"},\n  \"labels\": [\n    {\"id\":1,\"name\":\"Cell\",\"color\":\"#2ca02c\"}\n  ],\n  \"contours\": [\n    {\"axis\":\"z\",\"index\":10,\"label\":1,\"author\":\"a\",\"created\":\"t\",\"points\":[[10.5,4.0],[30.25,6.0],[28.0,27.5],[8.125,20.0]]}\n  ],\n  \"drawn_empty\": [\n    {\"axis\":\"z\",\"index\":2,\"label\":1,\"author\":\"a\"}\n  ]\n}\n";
    let numbers: Vec<(usize, usize)> = {
        let b = seed.as_bytes();
        let mut v = Vec::new();
        let mut i = 0;
        while i < b.len() {
            if b[i].is_ascii_digit()
                && (i == 0 || !b[i - 1].is_ascii_alphanumeric() && b[i - 1] != b'#')
            {
                let s = i;
                while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                    i += 1;
                }
                v.push((s, i));
            }
            i += 1;
        }
        v
    };
    let json_hostile = [
        "0",
        "-1",
        "1e999",
        "-1e999",
        "1e308",
        "4294967296",
        "2048",
        "99999999999",
        "null",
        "\"x\"",
        "[]",
        "0.0",
    ];
    for _ in 0..n {
        let (s, e) = numbers[rng.gen_range(0..numbers.len())];
        let x = json_hostile[rng.gen_range(0..json_hostile.len())];
        let text = format!("{}{x}{}", &seed[..s], &seed[e..]);
        let mut v = variant(
            format!("contours number at {s} = {x}"),
            "c.json",
            text.into_bytes(),
        );
        v.contours = true;
        out.push(v);
    }
    for cut in [0, 10, 100, seed.len() - 3] {
        let mut v = variant(
            format!("contours cut at {cut}"),
            "c.json",
            seed.as_bytes()[..cut].to_vec(),
        );
        v.contours = true;
        out.push(v);
    }
    let mut v = variant(
        "contours grid 2048^3",
        "c.json",
        seed.replace("[40,32,24]", "[2048,2048,2048]").into_bytes(),
    );
    v.contours = true;
    out.push(v);
}

/// What went wrong with one run, or None.
fn check(bin: &Path, root: &Path, k: usize, v: &Variant) -> Option<String> {
    let dir = root.join("v").join(k.to_string());
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in &v.files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    for (name, target) in &v.links {
        std::os::unix::fs::symlink(target, dir.join(name)).unwrap();
    }
    let target = if v.read == "." {
        dir.clone()
    } else {
        dir.join(&v.read)
    };
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("ulimit -v {ULIMIT_KIB}; exec \"$0\" \"$@\""))
        .arg(bin);
    if v.contours {
        cmd.args(["contours", "rasterize"])
            .arg(&target)
            .arg("--out")
            .arg(dir.join("out.nii"));
    } else {
        cmd.arg("info").arg(&target).arg("--json");
    }
    let mut child = cmd
        .env("RAYON_NUM_THREADS", "2")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The pipes are drained while the child runs (a long message must not
    // block it on a full pipe).
    let drain = |r: Option<Box<dyn std::io::Read + Send>>| {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            if let Some(mut r) = r {
                let _ = r.read_to_end(&mut buf);
            }
            buf
        })
    };
    let out_thread = drain(child.stdout.take().map(|r| Box::new(r) as _));
    let err_thread = drain(child.stderr.take().map(|r| Box::new(r) as _));
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Some(format!("no answer after {TIMEOUT:?}"));
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let stdout = String::from_utf8_lossy(&out_thread.join().unwrap()).into_owned();
    let stderr = String::from_utf8_lossy(&err_thread.join().unwrap()).into_owned();
    let _ = std::fs::remove_dir_all(&dir);
    match status.code() {
        Some(0) => {
            if v.must_fail {
                return Some(format!("read without error: {}", stdout.trim()));
            }
            if let Ok(j) = serde_json::from_str::<serde_json::Value>(&stdout) {
                let canary = [
                    f64::from(CANARY),
                    f64::from(u16::from_le_bytes([CANARY; 2])),
                ];
                let (min, max) = (j["min"].as_f64(), j["max"].as_f64());
                if min == max && min.is_some_and(|m| canary.contains(&m)) {
                    return Some(format!(
                        "read the canary outside the folder: {}",
                        stdout.trim()
                    ));
                }
            }
            None
        }
        Some(1) => {
            let lines: Vec<&str> = stderr.lines().collect();
            if lines.len() == 1 && lines[0].starts_with("error: ") {
                None
            } else {
                Some(format!("exit 1 without a one-line error: {stderr:?}"))
            }
        }
        Some(c) => Some(format!("exit status {c}: {stderr:?}")),
        None => Some(format!("killed by a signal ({status}): {stderr:?}")),
    }
}

#[test]
#[ignore = "run by scripts/test-mutation.sh with INTERSLICE_BIN set to the interslice binary"]
fn every_reader_survives_mutated_files() {
    let bin = PathBuf::from(
        std::env::var("INTERSLICE_BIN").expect("INTERSLICE_BIN is the interslice binary"),
    );
    let seed: u64 = std::env::var("MUTATION_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20261129);
    let total: usize = std::env::var("MUTATION_VARIANTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3000);
    let root = tempfile::tempdir().unwrap();
    let canary = root.path().join("canary.raw");
    std::fs::write(&canary, vec![CANARY; 6 * 5 * 4 * 2]).unwrap();
    std::fs::write(root.path().join("canary.png"), {
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, 6, 5);
        enc.set_color(png::ColorType::Grayscale);
        let mut wr = enc.write_header().unwrap();
        wr.write_image_data(&[CANARY; 30]).unwrap();
        drop(wr);
        out
    })
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut variants = Vec::new();
    nifti(&mut rng, total * 25 / 100, &mut variants);
    text_headers(&mut rng, total * 35 / 100, &canary, &mut variants);
    images(&mut rng, total * 30 / 100, &mut variants);
    contours(&mut rng, total * 10 / 100, &mut variants);
    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let started = Instant::now();
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(v) = variants.get(k) else { break };
                    if let Some(e) = check(&bin, root.path(), k, v) {
                        failures
                            .lock()
                            .unwrap()
                            .push(format!("#{k} {}: {e}", v.what));
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    println!(
        "{} variants (seed {seed}) in {:.1} s, {} failures",
        variants.len(),
        started.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of {} variants failed:\n{}",
        failures.len(),
        variants.len(),
        failures.join("\n")
    );
}
