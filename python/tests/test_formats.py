"""read/write round trips through every format, geometry included, and the
axis order: arrays are [x, y, z] like nibabel, Fortran-ordered."""

import numpy as np
import pytest

import interslice

META = {
    "spacing": (0.35, 0.5, 1.25),
    "unit": "µm",
    "origin": (1.5, -2.0, 3.25),
    "direction": ((0.0, 1.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
}

# (name, dtypes it writes, keeps origin/direction)
FORMATS = [
    ("v.nii", ["uint8", "uint16", "int16", "float32"]),
    ("v.nii.gz", ["uint8", "uint16", "int16", "float32"]),
    ("v.nrrd", ["uint8", "uint16", "int16", "float32"]),
    ("v.mha", ["uint8", "uint16", "int16", "float32"]),
    ("v.mhd", ["uint8", "uint16", "int16", "float32"]),
    ("v.tif", ["uint8", "uint16", "int16", "float32"]),
    ("slices", ["uint8", "uint16"]),
]


def volume(dtype, shape=(7, 5, 4)):
    rng = np.random.default_rng(7)
    info = np.iinfo(dtype) if np.dtype(dtype).kind in "iu" else None
    if info is None:
        a = rng.normal(size=shape).astype(dtype) * 100
    else:
        a = rng.integers(info.min, info.max, size=shape, endpoint=True, dtype=dtype)
    return a


@pytest.mark.parametrize("name,dtypes", FORMATS, ids=[f[0] for f in FORMATS])
def test_round_trip_every_format(tmp_path, name, dtypes):
    for dtype in dtypes:
        a = volume(dtype)
        path = tmp_path / f"{dtype}_{name}"
        interslice.write(path, a, META)
        b, meta = interslice.read(path)
        assert b.dtype == a.dtype, (name, dtype)
        assert b.shape == a.shape
        np.testing.assert_array_equal(b, a)
        assert b.flags.f_contiguous
        np.testing.assert_allclose(meta["spacing"], META["spacing"], rtol=1e-6)
        assert meta["unit"] == "µm"
        np.testing.assert_allclose(meta["origin"], META["origin"], rtol=1e-6)
        np.testing.assert_allclose(meta["direction"], META["direction"], atol=1e-6)


def test_c_ordered_and_strided_arrays_write_the_same_volume(tmp_path):
    a = volume("uint16", (6, 5, 4))
    interslice.write(tmp_path / "f.nii", np.asfortranarray(a), META)
    interslice.write(tmp_path / "c.nii", np.ascontiguousarray(a), META)
    big = np.zeros((12, 5, 8), dtype=np.uint16)
    big[::2, :, ::2] = a
    interslice.write(tmp_path / "s.nii", big[::2, :, ::2], META)
    for n in ("f", "c", "s"):
        np.testing.assert_array_equal(interslice.read(tmp_path / f"{n}.nii")[0], a)


def test_bool_is_written_as_uint8_and_meta_is_optional(tmp_path):
    m = volume("uint8") > 128
    interslice.write(tmp_path / "m.nrrd", m)
    b, meta = interslice.read(tmp_path / "m.nrrd")
    assert b.dtype == np.uint8
    np.testing.assert_array_equal(b, m.astype(np.uint8))
    assert meta["spacing"] == (1.0, 1.0, 1.0)


def test_slice_z_is_the_last_index(tmp_path, cli):
    """A file the command line writes reads back [x, y, z]: `info` reports
    dims (nx, ny, nz) and the array has that shape."""
    a = np.zeros((9, 6, 3), dtype=np.uint8)
    a[:, :, 2] = 7  # slice z = 2
    interslice.write(tmp_path / "a.nii.gz", a, META)
    cli("convert", tmp_path / "a.nii.gz", tmp_path / "b.mha")
    b, _ = interslice.read(tmp_path / "b.mha")
    assert b.shape == (9, 6, 3)
    assert (b[:, :, 2] == 7).all() and (b[:, :, :2] == 0).all()


def test_detached_nrrd_is_read(tmp_path):
    a = volume("int16", (4, 3, 2))
    (tmp_path / "v.raw").write_bytes(np.asfortranarray(a).tobytes(order="F"))
    (tmp_path / "v.nhdr").write_text(
        "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\n"
        "space: left-posterior-superior\nspace directions: (0.5,0,0) (0,0.5,0) (0,0,2)\n"
        "space origin: (0,0,0)\ndata file: v.raw\n"
    )
    b, meta = interslice.read(tmp_path / "v.nhdr")
    np.testing.assert_array_equal(b, a)
    assert meta["spacing"] == (0.5, 0.5, 2.0)


def test_reference_case_matches_its_header(cli_json):
    from conftest import CASES

    path = CASES / "blob64_um_gt.nii.gz"
    a, meta = interslice.read(path)
    info = cli_json("info", path, "--json")
    assert list(a.shape) == list(info["dims"])
    np.testing.assert_allclose(meta["spacing"], info["spacing"])
    assert a.sum() == sum(c["voxels"] for c in info["labels"] if c["label"] != 0)
