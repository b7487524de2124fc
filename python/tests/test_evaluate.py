"""`evaluate` gives the command line's JSON (same keys, same values to
1e-12 relative) on
every reference case, with or without a label, whatever the array layout
and dtype; `overlap`, `staple` and `threshold` agree with the command line."""

import math

import numpy as np
import pytest
from conftest import CASES, case_pairs

import interslice

CASES_ALL = case_pairs()


def read_pair(gt, pred):
    g, meta = interslice.read(gt)
    p, _ = interslice.read(pred)
    return g, p, meta


@pytest.mark.parametrize("name,gt,pred", CASES_ALL, ids=[c[0] for c in CASES_ALL])
def test_evaluate_equals_the_cli_json(name, gt, pred, cli_json):
    g, p, meta = read_pair(gt, pred)
    want = cli_json("evaluate", gt, pred, "--label", 1, "--json")
    with pytest.warns(UserWarning) if want["tp"] + want["fp"] + want["fn"] == 0 else _nothing():
        got = interslice.evaluate(g, p, meta["spacing"], label=1, unit=meta["unit"])
    # Equal up to the last bits of sums that rayon may group differently
    # from one run to the next (the command line differs from itself there).
    close(got, want)
    assert list(got) == list(want), "keys in the command line's order"
    want_all = cli_json("evaluate", gt, pred, "--json")
    close(interslice.evaluate(g, p, meta["spacing"], unit=meta["unit"]), want_all)


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *a):
        return False


def close(a, b):
    """Equal dicts, floats to 1e-12 relative (sums in another order)."""
    assert a.keys() == b.keys()
    for k in a:
        x, y = a[k], b[k]
        if isinstance(x, dict):
            close(x, y)
        elif isinstance(x, float) and isinstance(y, float):
            assert math.isclose(x, y, rel_tol=1e-12, abs_tol=1e-12), (k, x, y)
        else:
            assert x == y, (k, x, y)


def test_layouts_and_dtypes_give_the_same_metrics():
    g, p, meta = read_pair(CASES / "blob64_mm_gt.nii.gz", CASES / "blob64_mm_pred.nii.gz")
    sp, unit = meta["spacing"], meta["unit"]
    want = interslice.evaluate(g, p, sp, label=1, unit=unit)
    # C order, read in place with the axes reversed.
    close(interslice.evaluate(np.ascontiguousarray(g), np.ascontiguousarray(p), sp, label=1, unit=unit), want)
    # SimpleITK's [z, y, x] array passed as its transpose.
    zyx_g, zyx_p = np.ascontiguousarray(g.T), np.ascontiguousarray(p.T)
    close(interslice.evaluate(zyx_g.T, zyx_p.T, sp, label=1, unit=unit), want)
    # A strided view is copied.
    big = np.zeros((g.shape[0] * 2,) + g.shape[1:], dtype=g.dtype)
    big[::2] = g
    close(interslice.evaluate(big[::2], p, sp, label=1, unit=unit), want)
    for dtype in (bool, np.uint16, np.int32, np.int64):
        close(interslice.evaluate(g.astype(dtype), p.astype(dtype), sp, label=1, unit=unit), want)
    # Mixed dtypes.
    close(interslice.evaluate(g.astype(np.uint16), p, sp, label=1, unit=unit), want)


def test_overlap_equals_evaluate_on_its_keys():
    g, p, meta = read_pair(CASES / "blob64_um_gt.nii.gz", CASES / "blob64_um_pred.nii.gz")
    full = interslice.evaluate(g, p, meta["spacing"], label=1, unit=meta["unit"])
    o = interslice.overlap(g, p, label=1, spacing=meta["spacing"], unit=meta["unit"])
    for k, v in o.items():
        assert full[k] == v, k
    close(interslice.overlap(np.ascontiguousarray(g), p, spacing=meta["spacing"], unit=meta["unit"]), o)


def test_staple_equals_the_cli(tmp_path, cli_json):
    g, p, meta = read_pair(CASES / "blob64_iso_gt.nii.gz", CASES / "blob64_iso_pred.nii.gz")
    third = np.roll(g, 2, axis=0)
    paths = []
    for i, m in enumerate((g, p, third)):
        paths.append(tmp_path / f"r{i}.nii.gz")
        interslice.write(paths[-1], m, meta)
    want = cli_json("staple", *paths, "--label", 1, "--out", tmp_path / "c.nii.gz", "--json")["labels"][0]
    consensus, stats = interslice.staple([g, p, third], label=1)
    np.testing.assert_array_equal(consensus, interslice.read(tmp_path / "c.nii.gz")[0])
    for k in ("prior", "iterations", "converged", "consensus_voxels"):
        assert stats[k] == want[k], k
    for r, w in zip(stats["raters"], want["raters"]):
        assert (r["sensitivity"], r["specificity"]) == (w["sensitivity"], w["specificity"])
    # Non-zero voxels are the foreground without a label.
    c2, _ = interslice.staple([g.astype(bool), p, third])
    np.testing.assert_array_equal(c2, consensus)


@pytest.mark.parametrize("method,extra", [("otsu", []), ("multi-otsu", ["--classes", "3"]), ("rosin", [])])
def test_threshold_equals_the_cli(tmp_path, cli_json, method, extra):
    src = CASES / "thresholds" / "u8_trimodal.nii.gz"
    img, meta = interslice.read(src)
    want = cli_json("segment", src, "--method", method, *extra, "--out", tmp_path / "s.nii.gz", "--json")
    labels, summary = interslice.threshold(
        img, method=method, classes=3 if extra else None, spacing=meta["spacing"], unit=meta["unit"]
    )
    want.pop("out")
    assert summary == want
    np.testing.assert_array_equal(labels, interslice.read(tmp_path / "s.nii.gz")[0])
