#!/usr/bin/env python3
"""ITK's morphological contour interpolation (MCI) as an anchor of `interslice bench`.

Usage: mci_anchor.py [--data DIR] [--skips 1,3,5,9] [--t1] [--mni] [--aal] [--against BENCH.json]

Runs `itk.morphological_contour_interpolator` (pip packages `itk` and
`itk-morphologicalcontourinterpolation`; Albu et al. 2008, Zukić et al.
2016) on the drawn slices of every development mask, under the protocol of
`interslice bench` (`devdata.py`), and prints its Dice on the skipped slices.
With `--against` (the `--json` of `interslice bench --per-mask`), also lists
every mask and k where a method of that run falls below MCI, and by how much.
Needs `interslice` (pip install ./python). Not part of the tests.
"""
import argparse
import json
import time
from pathlib import Path

import itk
import numpy as np

from devdata import cases, cropped, dice_skipped, drawn_and_skipped


def mci(mask, drawn):
    """MCI of the drawn slices of `mask` (x, y, z) along z, drawn slices kept."""
    sparse = np.zeros(mask.shape, np.uint8)
    sparse[:, :, drawn] = mask[:, :, drawn]
    # numpy (x, y, z) -> itk's (z, y, x) array, whose index axis 2 is z.
    image = itk.image_from_array(np.ascontiguousarray(sparse.transpose(2, 1, 0)))
    out = itk.morphological_contour_interpolator(image, axis=2, label=1)
    return itk.array_from_image(out).transpose(2, 1, 0) == 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("target/interp-data"))
    ap.add_argument("--skips", default="1,3,5,9")
    ap.add_argument("--t1", action="store_true", help="also the T1 k-means classes")
    ap.add_argument("--mni", action="store_true", help="also the MNI grey and white matter")
    ap.add_argument("--aal", action="store_true", help="also the AAL structures")
    ap.add_argument("--against", type=Path, help="JSON rows of `interslice bench --per-mask --json`")
    args = ap.parse_args()
    skips = [int(k) for k in args.skips.split(",")]
    print(f"| mask | {' | '.join(f'k={k}' for k in skips)} | s/run |")
    print(f"|---|{'---|' * len(skips)}---|")
    anchor = {}
    for name, mask, img in cases(args.data, args.t1, args.mni, args.aal):
        mask, _ = cropped(mask, img)
        scores, secs = [], []
        for k in skips:
            drawn, skipped = drawn_and_skipped(mask, k)
            t = time.perf_counter()
            result = mci(mask, drawn)
            secs.append(time.perf_counter() - t)
            scores.append(dice_skipped(result, mask, skipped))
            anchor[(name, k)] = scores[-1]
        cells = " | ".join(f"{d:.4f}" for d in scores)
        print(f"| {name} | {cells} | {np.mean(secs):.2f} |", flush=True)
    if args.against:
        rows = json.loads(args.against.read_text())
        below = {}
        for r in rows:
            key = (r["mask"], r["skip"])
            if key in anchor and r["dice_skipped"] < anchor[key] - 1e-4:
                below.setdefault(r["method"], []).append((r["mask"], r["skip"], anchor[key] - r["dice_skipped"]))
        methods = sorted({r["method"] for r in rows if (r["mask"], r["skip"]) in anchor})
        for m in methods:
            lost = below.get(m, [])
            detail = ", ".join(f"{n} k={k} by {d:.4f}" for n, k, d in lost)
            print(f"{m}: below MCI on {len(lost)} of {len(anchor)}{': ' + detail if lost else ''}")


if __name__ == "__main__":
    main()
