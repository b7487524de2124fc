//! Every voxel type a NIfTI file may carry reaches the browser as the values
//! the file means: the binary slices along x, y and z, the cell's range and
//! its histogram, in the file's units (`scl_slope`/`scl_inter` applied).
//! The files are written here byte by byte (a NIfTI-1 header is 348 fixed
//! fields), so each datatype code is exercised as a file in the wild has it.
use crate::common;

use common::*;
use interslice_core::Axis;

/// `[nx, ny, nz]`: all different, so a wrong stride on any axis shows.
const DIMS: [usize; 3] = [5, 4, 3];

/// A NIfTI-1 file (`.nii`, little-endian) of `dims` with datatype `code`,
/// voxel bytes `data` (x fastest) and the scaling `slope`, `inter`.
fn nifti(code: i16, bitpix: i16, data: &[u8], slope: f32, inter: f32) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let dim: [i16; 8] = [
        3,
        DIMS[0] as i16,
        DIMS[1] as i16,
        DIMS[2] as i16,
        1,
        1,
        1,
        1,
    ];
    for (n, d) in dim.iter().enumerate() {
        h[40 + 2 * n..42 + 2 * n].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&code.to_le_bytes());
    h[72..74].copy_from_slice(&bitpix.to_le_bytes());
    let pixdim: [f32; 8] = [1.0, 0.5, 0.5, 2.0, 1.0, 1.0, 1.0, 1.0];
    for (n, p) in pixdim.iter().enumerate() {
        h[76 + 4 * n..80 + 4 * n].copy_from_slice(&p.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes()); // vox_offset
    h[112..116].copy_from_slice(&slope.to_le_bytes());
    h[116..120].copy_from_slice(&inter.to_le_bytes());
    h[123] = 2; // xyzt_units: mm
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend_from_slice(data);
    h
}

/// The stored value of voxel `n` (x fastest): negative, zero and positive
/// values, distinct along every axis.
fn stored(n: usize) -> f64 {
    n as f64 * 7.0 - 150.0
}

/// One case: a file's datatype, how its stored values are written, the
/// scaling, the voxel type the server sends and the value it means.
struct Case {
    name: &'static str,
    code: i16,
    bitpix: i16,
    bytes: fn(f64) -> Vec<u8>,
    slope: f32,
    inter: f32,
    dtype: &'static str,
    /// The stored value of voxel `n` (the type's range decides the offset).
    value: fn(usize) -> f64,
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "u8",
            code: 2,
            bitpix: 8,
            bytes: |x| vec![x as u8],
            slope: 0.0,
            inter: 0.0,
            dtype: "u8",
            value: |n| n as f64 * 4.0 + 3.0,
        },
        Case {
            name: "i8",
            code: 256,
            bitpix: 8,
            bytes: |x| vec![x as i8 as u8],
            slope: 0.0,
            inter: 0.0,
            dtype: "i16",
            value: |n| n as f64 * 4.0 - 120.0,
        },
        Case {
            name: "u16",
            code: 512,
            bitpix: 16,
            bytes: |x| (x as u16).to_le_bytes().to_vec(),
            slope: 1.0,
            inter: 0.0,
            dtype: "u16",
            value: |n| stored(n) * 100.0 + 15000.0,
        },
        Case {
            name: "i16",
            code: 4,
            bitpix: 16,
            bytes: |x| (x as i16).to_le_bytes().to_vec(),
            slope: 0.0,
            inter: 0.0,
            dtype: "i16",
            value: |n| stored(n) * 10.0 - 400.0,
        },
        Case {
            name: "u32",
            code: 768,
            bitpix: 32,
            bytes: |x| (x as u32).to_le_bytes().to_vec(),
            slope: 0.0,
            inter: 0.0,
            dtype: "u16",
            value: |n| stored(n) + 60000.0,
        },
        Case {
            name: "i32",
            code: 8,
            bitpix: 32,
            bytes: |x| (x as i32).to_le_bytes().to_vec(),
            slope: 0.0,
            inter: 0.0,
            dtype: "i16",
            value: |n| stored(n) * 100.0,
        },
        Case {
            name: "f32",
            code: 16,
            bitpix: 32,
            bytes: |x| (x as f32).to_le_bytes().to_vec(),
            slope: 0.0,
            inter: 0.0,
            dtype: "f32",
            value: |n| stored(n) / 8.0,
        },
        Case {
            name: "f64",
            code: 64,
            bitpix: 64,
            bytes: |x| x.to_le_bytes().to_vec(),
            slope: 0.0,
            inter: 0.0,
            dtype: "f32",
            value: |n| stored(n) * 0.25,
        },
        // CT as scanners often store it: unsigned, intercept -1024.
        Case {
            name: "u16_scaled",
            code: 512,
            bitpix: 16,
            bytes: |x| (x as u16).to_le_bytes().to_vec(),
            slope: 1.0,
            inter: -1024.0,
            dtype: "f32",
            value: |n| stored(n) * 5.0 + 1000.0,
        },
        Case {
            name: "i16_scaled",
            code: 4,
            bitpix: 16,
            bytes: |x| (x as i16).to_le_bytes().to_vec(),
            slope: 0.5,
            inter: 10.0,
            dtype: "f32",
            value: |n| stored(n) * 3.0,
        },
    ]
}

/// The value the file means for a case's stored value.
fn meant(c: &Case, x: f64) -> f64 {
    let scaled = c.slope != 0.0 && (c.slope != 1.0 || c.inter != 0.0);
    if scaled {
        x * f64::from(c.slope) + f64::from(c.inter)
    } else {
        x
    }
}

/// Decode a slice body by its `X-Dtype` as the browser does (little-endian).
fn decode(dtype: &str, body: &[u8]) -> Vec<f64> {
    match dtype {
        "u8" => body.iter().map(|&b| f64::from(b)).collect(),
        "u16" => body
            .chunks_exact(2)
            .map(|b| f64::from(u16::from_le_bytes([b[0], b[1]])))
            .collect(),
        "i16" => body
            .chunks_exact(2)
            .map(|b| f64::from(i16::from_le_bytes([b[0], b[1]])))
            .collect(),
        "f32" => body
            .chunks_exact(4)
            .map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
            .collect(),
        other => panic!("unexpected X-Dtype {other}"),
    }
}

#[test]
fn every_file_voxel_type_is_served_in_the_files_units_along_every_axis() {
    let dir = tempfile::tempdir().unwrap();
    let n = DIMS.iter().product::<usize>();
    for c in cases() {
        let data: Vec<u8> = (0..n).flat_map(|v| (c.bytes)((c.value)(v))).collect();
        std::fs::write(
            dir.path().join(format!("{}.nii", c.name)),
            nifti(c.code, c.bitpix, &data, c.slope, c.inter),
        )
        .unwrap();
    }
    let server = serve(config(dir.path()));
    let client = signed_in(&server, "alice");
    let cells = client.get("/api/cells").unwrap().json();
    assert_eq!(cells.as_array().unwrap().len(), cases().len(), "{cells}");
    for c in cases() {
        let want =
            |i: usize, j: usize, k: usize| meant(&c, (c.value)(i + DIMS[0] * (j + DIMS[1] * k)));
        let detail = client.get(&format!("/api/cells/{}", c.name)).unwrap();
        expect(&detail, 200);
        let d = detail.json();
        assert_eq!(d["dtype"], c.dtype, "{}", c.name);
        let all: Vec<f64> = (0..n).map(|v| meant(&c, (c.value)(v))).collect();
        let lo = all.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = all.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(
            (d["min"].as_f64(), d["max"].as_f64()),
            (Some(lo), Some(hi)),
            "{}: range",
            c.name
        );
        let h = client
            .get(&format!("/api/cells/{}/histogram", c.name))
            .unwrap()
            .json();
        assert_eq!(h["min"].as_f64(), Some(lo), "{}", c.name);
        let counts: Vec<u64> = serde_json::from_value(h["counts"].clone()).unwrap();
        assert_eq!(
            counts.iter().sum::<u64>(),
            n as u64,
            "{}: every voxel counted",
            c.name
        );
        let bw = h["bin_width"].as_f64().unwrap();
        let top = (((hi - lo) / bw).floor() as usize).min(255);
        assert!(
            counts[0] >= 1 && counts[top] >= 1 && counts[top + 1..].iter().all(|&k| k == 0),
            "{}: the minimum in the first bin, the maximum in bin {top}",
            c.name
        );
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            for index in 0..DIMS[axis.dim()] {
                let a = client
                    .get(&format!("/api/cells/{}/slices/{axis}/{index}", c.name))
                    .unwrap();
                expect(&a, 200);
                let (w, hgt, dtype) = a.slice_header.clone().expect("slice headers");
                assert_eq!(dtype, c.dtype);
                let got = decode(&dtype, &a.body);
                assert_eq!(got.len(), w * hgt, "{} {axis}={index}: body size", c.name);
                for v in 0..hgt {
                    for u in 0..w {
                        let [i, j, k] = axis.voxel(index, u, v);
                        assert_eq!(
                            got[u + w * v],
                            want(i, j, k),
                            "{} {axis}={index} pixel ({u}, {v}) = voxel ({i}, {j}, {k})",
                            c.name
                        );
                    }
                }
            }
        }
    }
}
