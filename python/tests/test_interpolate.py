"""`interpolate` gives the command line's output voxel for voxel."""

import json

import numpy as np
import pytest

import interslice


def drawn_list(path):
    return [int(line) for line in path.read_text().split() if line.strip()]


def test_methods_list_the_default_first(cli):
    ms = interslice.methods()
    assert ms[0]["name"] == interslice.DEFAULT_METHOD and ms[0]["default"]
    assert sum(m["default"] for m in ms) == 1
    listed = [line.split()[0] for line in cli("interpolate", "--list").stdout.splitlines() if line.strip()]
    # The CLI also lists the image-guided method: it needs an image, and is
    # what interpolate(image=...) uses without a method.
    assert listed[-1] == "image-guided"
    assert [m["name"] for m in ms] == listed[:-1]


@pytest.mark.parametrize("method", [None, "linear", "shape-based"])
def test_interpolate_equals_the_cli(tmp_path, cli, phantom_files, method):
    f = phantom_files
    out = tmp_path / "full.nii.gz"
    args = ["interpolate", f["sparse"], "--drawn", f["drawn"], "--out", out]
    if method:
        args += ["--method", method]
    cli(*args)
    want, _ = interslice.read(out)
    sparse, meta = interslice.read(f["sparse"])
    got = interslice.interpolate(sparse, drawn=drawn_list(f["drawn"]), axis="z", spacing=meta["spacing"], method=method)
    assert got.dtype == sparse.dtype
    np.testing.assert_array_equal(got, want)
    # The drawn slices are kept exactly.
    d = drawn_list(f["drawn"])
    np.testing.assert_array_equal(got[:, :, d], sparse[:, :, d])


def test_without_drawn_the_nonempty_slices_are_drawn(tmp_path, cli, phantom_files):
    f = phantom_files
    cli("interpolate", f["sparse"], "--out", tmp_path / "a.nii.gz", "--method", "linear")
    sparse, meta = interslice.read(f["sparse"])
    got = interslice.interpolate(sparse, spacing=meta["spacing"], method="linear")
    np.testing.assert_array_equal(got, interslice.read(tmp_path / "a.nii.gz")[0])


def test_other_axes_dtypes_and_layouts(tmp_path, cli, phantom_files):
    labels, meta = interslice.read(phantom_files["labels"])
    sparse = np.zeros_like(labels)
    drawn = list(range(2, labels.shape[0], 6))
    sparse[drawn] = labels[drawn]
    interslice.write(tmp_path / "sx.nii.gz", sparse, meta)
    (tmp_path / "d.txt").write_text("\n".join(map(str, drawn)))
    cli("interpolate", tmp_path / "sx.nii.gz", "--axis", "x", "--drawn", tmp_path / "d.txt", "--out", tmp_path / "o.nii.gz")
    want, _ = interslice.read(tmp_path / "o.nii.gz")
    for arr in (sparse, np.ascontiguousarray(sparse), sparse.astype(np.int32), sparse.astype(np.uint16)):
        got = interslice.interpolate(arr, drawn=drawn, axis=0, spacing=meta["spacing"])
        assert got.dtype == arr.dtype
        np.testing.assert_array_equal(got, want)


def test_interpolate_with_the_image_equals_the_cli(tmp_path, cli, phantom_files):
    f = phantom_files
    out = tmp_path / "guided.nii.gz"
    cli("interpolate", f["sparse"], "--drawn", f["drawn"], "--image", f["image"], "--out", out)
    want, _ = interslice.read(out)
    sparse, meta = interslice.read(f["sparse"])
    image, _ = interslice.read(f["image"])
    got = interslice.interpolate(sparse, drawn=drawn_list(f["drawn"]), spacing=meta["spacing"], image=image)
    np.testing.assert_array_equal(got, want)
    # Any numeric dtype of the image gives the same result.
    again = interslice.interpolate(
        sparse, drawn=drawn_list(f["drawn"]), spacing=meta["spacing"], image=image.astype(np.float64)
    )
    np.testing.assert_array_equal(again, want)


@pytest.mark.parametrize("with_image", [False, True])
def test_confidence_equals_the_cli(tmp_path, cli, phantom_files, with_image):
    f = phantom_files
    out, conf = tmp_path / "out.nii.gz", tmp_path / "conf.nii.gz"
    args = ["interpolate", f["sparse"], "--drawn", f["drawn"], "--out", out, "--confidence", conf]
    sparse, meta = interslice.read(f["sparse"])
    image = None
    if with_image:
        args += ["--image", f["image"]]
        image, _ = interslice.read(f["image"])
    cli(*args)
    d = drawn_list(f["drawn"])
    got, got_conf = interslice.interpolate(sparse, drawn=d, spacing=meta["spacing"], image=image, confidence=True)
    np.testing.assert_array_equal(got, interslice.read(out)[0])
    assert got_conf.dtype == np.float32 and got_conf.shape == sparse.shape
    np.testing.assert_array_equal(got_conf, interslice.read(conf)[0])
    # Sure on the drawn slices, guessing somewhere between them, never below a coin toss.
    assert np.all(got_conf[:, :, d] == 1.0)
    assert got_conf.min() >= 0.5 and got_conf.min() < 0.75
    # Without confidence the labels are the same.
    np.testing.assert_array_equal(
        got, interslice.interpolate(sparse, drawn=d, spacing=meta["spacing"], image=image)
    )


def test_advise_equals_the_cli(cli, phantom_files):
    f = phantom_files
    want = json.loads(cli("advise", f["sparse"], "--drawn", f["drawn"], "--count", 4, "--json").stdout)
    sparse, meta = interslice.read(f["sparse"])
    got = interslice.advise(sparse, drawn=drawn_list(f["drawn"]), spacing=meta["spacing"], count=4)
    assert got == want
    assert len(got["suggestions"]) == 4
    drawn = set(drawn_list(f["drawn"]))
    assert all(s["slice"] not in drawn for s in got["suggestions"])
    assert 0.5 < got["predicted_dice"] <= 1.0


def test_only_the_drawn_slices_are_read(phantom_files):
    sparse, meta = interslice.read(phantom_files["sparse"])
    d = drawn_list(phantom_files["drawn"])
    want = interslice.interpolate(sparse, drawn=d, spacing=meta["spacing"], method="shape-based")
    # A value that is no label, on a slice that is not drawn, is never read
    # (the slices between the drawn ones are the output's, not the input's).
    skipped = next(z for z in range(d[0], d[-1]) if z not in d)
    noisy = sparse.astype(np.float32)
    noisy[:, :, skipped] = 0.5
    got = interslice.interpolate(noisy, drawn=d, spacing=meta["spacing"], method="shape-based")
    np.testing.assert_array_equal(got, want.astype(np.float32))
    # On a drawn slice it is an error.
    noisy[3, 3, d[1]] = 0.5
    with pytest.raises(interslice.Error, match="integer labels"):
        interslice.interpolate(noisy, drawn=d, spacing=meta["spacing"], method="shape-based")
