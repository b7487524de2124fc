"""Bad input raises interslice.Error (a ValueError) with the one-line text
the command line prints; nothing panics."""

import numpy as np
import pytest
from conftest import CASES

import interslice


def cli_error(cli, *args):
    p = cli(*args, check=False)
    assert p.returncode == 1, p
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), p.stderr
    return lines[0]


def one_line(e):
    text = str(e.value)
    assert "\n" not in text and text
    return text


def test_error_is_a_value_error():
    assert issubclass(interslice.Error, ValueError)


def test_missing_file(tmp_path, cli):
    path = tmp_path / "missing.nii.gz"
    with pytest.raises(interslice.Error) as e:
        interslice.read(path)
    assert one_line(e) in cli_error(cli, "info", path)


def test_truncated_file(tmp_path, cli):
    data = (CASES / "blob64_iso_gt.nii.gz").read_bytes()
    path = tmp_path / "cut.nii.gz"
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(interslice.Error) as e:
        interslice.read(path)
    assert one_line(e) in cli_error(cli, "info", path)


def test_unknown_format(tmp_path, cli):
    with pytest.raises(interslice.Error) as e:
        interslice.write(tmp_path / "v.xyz", np.zeros((2, 2, 2), np.uint8))
    assert "unknown volume format" in one_line(e)


def test_unknown_method(cli, tmp_path):
    with pytest.raises(interslice.Error) as e:
        interslice.interpolate(np.zeros((4, 4, 4), np.uint8), method="nope")
    text = one_line(e)
    src = CASES / "blob64_iso_gt.nii.gz"
    assert text in cli_error(cli, "interpolate", src, "--method", "nope", "--out", tmp_path / "o.nii")


def test_interpolation_errors():
    a = np.zeros((4, 4, 6), np.uint8)
    a[:, :, 1] = 1
    with pytest.raises(interslice.Error, match="at least two drawn slices"):
        interslice.interpolate(a)
    with pytest.raises(interslice.Error, match="out of range"):
        interslice.interpolate(a, drawn=[1, 9])
    with pytest.raises(interslice.Error, match="axis"):
        interslice.interpolate(a, axis="w")
    with pytest.raises(interslice.Error, match="labels 0..=65535"):
        interslice.interpolate(np.full((4, 4, 6), 0.5))
    with pytest.raises(interslice.Error, match="3-D"):
        interslice.interpolate(np.zeros((4, 4), np.uint8))
    with pytest.raises(interslice.Error, match="image and labels differ"):
        interslice.interpolate(a, drawn=[1, 4], image=np.zeros((4, 4, 5), np.float32))
    with pytest.raises(interslice.Error, match="at least two drawn slices"):
        interslice.advise(a)
    with pytest.raises(interslice.Error, match="count must be"):
        interslice.advise(a, drawn=[1, 4], count=0)


def test_evaluate_errors(cli, tmp_path):
    a = np.zeros((4, 4, 4), np.uint8)
    with pytest.raises(interslice.Error, match="differ: shape"):
        interslice.evaluate(a, np.zeros((4, 4, 5), np.uint8))
    with pytest.raises(interslice.Error) as e:
        interslice.evaluate(a, a, label=1, tolerance=-1.0)
    assert "tolerance must be a finite number >= 0" in one_line(e)
    with pytest.raises(interslice.Error, match="spacing"):
        interslice.evaluate(a, a, spacing=(1.0, 0.0, 1.0), label=1)
    with pytest.raises(interslice.Error, match="spacing must have 3 values"):
        interslice.evaluate(a, a, spacing=(1.0, 1.0))
    with pytest.raises(interslice.Error, match="numpy array"):
        interslice.evaluate([[1]], a)
    with pytest.raises(interslice.Error, match="unknown unit"):
        interslice.evaluate(a, a, label=1, unit="furlong")


def test_other_errors():
    a = np.zeros((4, 4, 4), np.uint8)
    with pytest.raises(interslice.Error, match="2 to 20 masks"):
        interslice.staple([a])
    with pytest.raises(interslice.Error, match="unknown segmentation method"):
        interslice.threshold(a, method="magic")
    with pytest.raises(interslice.Error, match="cannot write int64"):
        interslice.write("x.nii", a.astype(np.int64))
    with pytest.raises(interslice.Error, match="phantom size"):
        interslice.phantom(size=8)


def test_an_intensity_array_passed_as_labels_is_refused_before_any_work():
    rng = np.random.default_rng(1)
    noise = np.zeros((16, 16, 11), np.uint16)
    noise[:, :, ::5] = rng.integers(1, 60000, size=(16, 16, 3))
    for call in (interslice.interpolate, interslice.advise):
        with pytest.raises(interslice.Error) as e:
            call(noise, drawn=[0, 5, 10])
        text = one_line(e)
        assert "more than max_labels 255" in text and "is it an intensity image?" in text
    # Asked for, every label is interpolated.
    two = np.zeros((8, 8, 11), np.uint16)
    two[2:5, 2:5, ::5] = 300
    two[5:7, 5:7, ::5] = 301
    out = interslice.interpolate(two, drawn=[0, 5, 10], max_labels=2)
    assert set(np.unique(out)) == {0, 300, 301}
    with pytest.raises(interslice.Error):
        interslice.interpolate(two, drawn=[0, 5, 10], max_labels=1)
