#!/usr/bin/env python3
"""Side-by-side: ITK's morphological contour interpolation vs interslice.

Usage: itk_compare.py GROUND_TRUTH.nii.gz [--skip 9] [--label 2] [--axis z]

Keeps the first and last non-empty slices of GROUND_TRUTH and every (k+1)-th
slice along the axis (as `interslice study` does), then interpolates the same
sparse volume with ITK (`itk.morphological_contour_interpolator`, from the pip
packages `itk` and `itk-morphologicalcontourinterpolation`) and with
`interslice interpolate` (default method and shape-based), and prints the
wall time and the Dice of the studied label for each. Not part of the tests.
Needs the release binary (`cargo build --release -p interslice-cli`).
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import itk
import numpy as np


def dice(a, b):
    s = a.sum() + b.sum()
    return 2.0 * np.logical_and(a, b).sum() / s if s else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("ground_truth")
    ap.add_argument("--skip", type=int, default=9)
    ap.add_argument("--label", type=int, default=2)
    ap.add_argument("--axis", default="z", choices="xyz")
    ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "../../target/release/interslice"))
    a = ap.parse_args()

    img = itk.imread(a.ground_truth)
    gt = itk.array_view_from_image(img).astype(np.uint8)  # (z, y, x)
    ax = {"z": 0, "y": 1, "x": 2}[a.axis]
    nonempty = [i for i in range(gt.shape[ax]) if np.take(gt, i, axis=ax).any()]
    first, last = nonempty[0], nonempty[-1]
    drawn = list(range(first, last + 1, a.skip + 1))
    if drawn[-1] != last:
        drawn.append(last)
    sparse = np.zeros_like(gt)
    idx = [slice(None)] * 3
    for d in drawn:
        idx[ax] = d
        sparse[tuple(idx)] = gt[tuple(idx)]
    truth = gt == a.label
    rows = []

    # ITK: the studied label only (the filter interpolates labels together
    # too, but slowly; one label keeps the comparison fair to it).
    one = np.where(sparse == a.label, 1, 0).astype(np.uint8)
    s_img = itk.image_from_array(one)
    s_img.CopyInformation(img)
    t = time.perf_counter()
    out = itk.morphological_contour_interpolator(s_img, axis=2 - ax, label=1)
    dt = time.perf_counter() - t
    rows.append(("itk morphological contour interpolation", dt, dice(itk.array_view_from_image(out) == 1, truth)))

    with tempfile.TemporaryDirectory() as tmp:
        sp = os.path.join(tmp, "sparse.nii.gz")
        s_img = itk.image_from_array(np.where(sparse == a.label, a.label, 0).astype(np.uint8))
        s_img.CopyInformation(img)
        itk.imwrite(s_img, sp)
        for method in ["shape-aligned", "shape-based"]:
            o = os.path.join(tmp, f"{method}.nii.gz")
            t = time.perf_counter()
            subprocess.run([a.bin, "interpolate", sp, "--out", o, "--method", method, "--axis", a.axis], check=True)
            dt = time.perf_counter() - t
            res = itk.array_view_from_image(itk.imread(o))
            rows.append((f"interslice {method} (incl. file I/O)", dt, dice(res == a.label, truth)))

    print(f"{a.ground_truth}: label {a.label}, k={a.skip}, {len(drawn)} drawn slices along {a.axis}")
    for name, dt, d in rows:
        print(f"{name:48s} {dt:8.3f} s   Dice {d:.4f}")


if __name__ == "__main__":
    sys.exit(main())
