"""Shared fixtures: the repository, its reference cases and the `interslice`
binary (the tests compare the bindings with the command line)."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "tests" / "fixtures" / "refs" / "cases"


def _binary() -> Path | None:
    env = os.environ.get("INTERSLICE_BIN")
    if env:
        return Path(env)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for p in (target / "debug" / "interslice", target / "release" / "interslice"):
        if p.is_file():
            return p
    found = shutil.which("interslice")
    return Path(found) if found else None


@pytest.fixture(scope="session")
def cli():
    """Run the `interslice` command: cli(*args) -> CompletedProcess (text)."""
    exe = _binary()
    if exe is None or not exe.is_file():
        pytest.fail("the interslice binary was not found: set INTERSLICE_BIN (scripts/test-python-package.sh does)")

    def run(*args, check=True):
        p = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError(f"interslice {' '.join(map(str, args))} failed: {p.stderr}")
        return p

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    def run(*args):
        return json.loads(cli(*args).stdout)

    return run


def case_pairs():
    """(name, gt path, pred path) of every reference case."""
    if not CASES.is_dir():
        raise RuntimeError(f"reference cases not found at {CASES}")
    out = []
    for gt in sorted(CASES.glob("*_gt.nii.gz")):
        name = gt.name[: -len("_gt.nii.gz")]
        out.append((name, gt, CASES / f"{name}_pred.nii.gz"))
    return out


@pytest.fixture(scope="session")
def phantom_files(tmp_path_factory, cli):
    """A 48³ phantom cell traced on every 5th slice by the command line:
    labels, sparse tracing and the drawn list."""
    d = tmp_path_factory.mktemp("phantom")
    cli("phantom", "--out", d, "--count", 1, "--size", 48, "--seed", 3)
    labels = d / "cell_001_labels.nii.gz"
    assert labels.is_file(), list(d.iterdir())
    cli("contours", "extract", labels, "--every", 5, "--out", d / "traced.json")
    cli("contours", "rasterize", d / "traced.json", "--out", d / "sparse.nii.gz", "--drawn-out", d / "drawn.txt")
    return {"dir": d, "labels": labels, "image": d / "cell_001.nii.gz", "sparse": d / "sparse.nii.gz", "drawn": d / "drawn.txt"}
