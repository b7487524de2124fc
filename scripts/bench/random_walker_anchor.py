#!/usr/bin/env python3
"""The random-walker anchor on the development data, for `interslice bench`.

Usage: random_walker_anchor.py [--data DIR] [--skips 1,3,5,9] [--beta 130] [--t1] [--mni] [--aal]

Runs scikit-image's `random_walker` on the intensity volume, seeded by the
drawn slices (inside the tracing: label 1, the rest of each drawn slice:
label 2), under the protocol of `interslice bench` (`devdata.py`: each mask
cropped to its box grown by 8 voxels, the first and last non-empty z slices
and every (k+1)-th slice from the first drawn, Dice on the skipped slices
only). This is
the idea of Biomedisa's smart interpolation and the image anchor of the
interpolation benchmark; compare its rows with `interslice bench --per-mask`.
The data come from `scripts/fetch-interp-data.sh` (DIR, default
target/interp-data); the noisy phantom is generated inside `interslice bench`
and is not covered here. The T1 classes (whole-brain boxes, tens of seconds
per run) only with --t1. Needs `interslice` (pip install ./python) and
scikit-image. Not part of the tests.
"""
import argparse
import time
from pathlib import Path

import numpy as np
from skimage.segmentation import random_walker

from devdata import cases, cropped, dice_skipped, drawn_and_skipped


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("target/interp-data"))
    ap.add_argument("--skips", default="1,3,5,9")
    ap.add_argument("--beta", type=float, default=130.0, help="random_walker's beta (its default)")
    ap.add_argument("--t1", action="store_true", help="also the T1 k-means classes (slow)")
    ap.add_argument("--mni", action="store_true", help="also the MNI grey and white matter (slow)")
    ap.add_argument("--aal", action="store_true", help="also the AAL structures")
    args = ap.parse_args()
    skips = [int(k) for k in args.skips.split(",")]
    print(f"| mask | {' | '.join(f'k={k}' for k in skips)} | s/run |")
    print(f"|---|{'---|' * len(skips)}---|")
    for name, mask, img in cases(args.data, args.t1, args.mni, args.aal):
        mask, img = cropped(mask, img)
        img = (img - img.mean()) / (img.std() + 1e-9)
        scores, secs = [], []
        for k in skips:
            drawn, skipped = drawn_and_skipped(mask, k)
            seeds = np.zeros(mask.shape, np.int32)
            for z in drawn:
                seeds[:, :, z] = np.where(mask[:, :, z], 1, 2)
            t = time.perf_counter()
            rw = random_walker(img, seeds, beta=args.beta, mode="cg_j", tol=1e-3) == 1
            secs.append(time.perf_counter() - t)
            scores.append(dice_skipped(rw, mask, skipped))
        cells = " | ".join(f"{d:.4f}" for d in scores)
        print(f"| {name} | {cells} | {np.mean(secs):.1f} |", flush=True)


if __name__ == "__main__":
    main()
