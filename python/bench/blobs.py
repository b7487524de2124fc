"""The irregular blob pairs the speed comparisons run on.

Origin: the reference speed measurements of the project (``speed_ref.py
--dump-inputs``, helpers ``smooth_field`` and ``blob_pair`` of its
``common.py``); reproduced here so the benchmark needs nothing beside the
repository. Same seed, same arrays: the sha256 of each pair is checked
against the reference's.

Arrays are uint8 ``[z, y, x]`` (SimpleITK's order), spacing (x, y, z) =
(0.35, 0.35, 0.5) µm, with an empty 2-voxel margin.

``python blobs.py DIR`` writes them as NIfTI (needs the interslice package);
``--raw`` also writes ``blob{n}_{gt,pred}.u8``, the bare voxels with x fastest,
which the criterion benchmarks of interslice-core read (``INTERSLICE_BLOBS=DIR``).
"""

import hashlib

import numpy as np
from scipy import ndimage as ndi

SPACING_XYZ = (0.35, 0.35, 0.5)

#: sha256 of the raw [z, y, x] uint8 bytes of the reference's inputs.
SHA256 = {
    (256, "gt"): "f5111328d63262b14c91443bd6e3cce5157c36fe6f82a128b44284488239e7f2",
    (256, "pred"): "d05fdd977d20b11810d431d57b6b3b74639cf78d615d3fdc0138d95b720023b8",
    (512, "gt"): "9ec199fe2f69cee7ac6058beeee53f9f9f6c5c9dc56372c3b7a4bfefeb7a601e",
    (512, "pred"): "eb598a0cf20fd1fa6ef3b28f62f1fb6b9c0c4976ba6ce6916ba3656369129b54",
}


def smooth_field(shape, rng, sigma_vox):
    f = rng.standard_normal(size=shape, dtype=np.float32)
    f = ndi.gaussian_filter(f, sigma=sigma_vox, mode="reflect", truncate=3.0)
    f -= f.mean()
    f /= f.std()
    return f


def blob_pair(n, feature_phys=3.0, perturb=0.4, level=0.6, margin=2):
    """(gt, pred), uint8 [z, y, x] of n³: gt = smooth(a) > level, pred adds a
    finer smooth field to a before thresholding."""
    rng = np.random.default_rng(700 + n)
    sp = tuple(reversed(SPACING_XYZ))
    sig = [feature_phys / s for s in sp]
    shape = (n, n, n)
    a = smooth_field(shape, rng, sig)
    b = smooth_field(shape, rng, [s * 0.5 for s in sig])
    gt = a > level
    b *= perturb
    b += a
    del a
    pr = b > level
    del b
    for m in (gt, pr):
        m[:margin] = 0
        m[-margin:] = 0
        m[:, :margin] = 0
        m[:, -margin:] = 0
        m[:, :, :margin] = 0
        m[:, :, -margin:] = 0
    return gt.astype(np.uint8), pr.astype(np.uint8)


def sha256_u8(a):
    return hashlib.sha256(np.ascontiguousarray(a, dtype=np.uint8).tobytes()).hexdigest()


def checked_pair(n):
    """The pair of size n, with a warning when it differs from the reference's."""
    g, p = blob_pair(n)
    for role, a in (("gt", g), ("pred", p)):
        want = SHA256.get((n, role))
        if want and sha256_u8(a) != want:
            print(f"warning: blob{n}_{role} differs from the reference input (numpy/scipy version?)")
    return g, p


if __name__ == "__main__":
    import argparse
    import os

    ap = argparse.ArgumentParser(
        description="write the blob pairs as NIfTI (for `interslice evaluate`) and, with --raw, "
        "as raw bytes (for the criterion benchmarks of interslice-core)"
    )
    ap.add_argument("out", help="folder to write blob{n}_{gt,pred}.nii.gz (and .u8) into")
    ap.add_argument("--sizes", default="256,512")
    ap.add_argument(
        "--raw",
        action="store_true",
        help="also write blob{n}_{gt,pred}.u8: the n³ voxels as uint8, x fastest (the NIfTI "
        "voxel order); without the interslice package installed, only these are written",
    )
    args = ap.parse_args()
    try:
        import interslice
    except ImportError:
        if not args.raw:
            raise
        interslice = None
        print("interslice is not installed: writing the raw files only")
    os.makedirs(args.out, exist_ok=True)
    for n in (int(s) for s in args.sizes.split(",")):
        g, p = checked_pair(n)
        for role, a in (("gt", g), ("pred", p)):
            if interslice is not None:
                path = os.path.join(args.out, f"blob{n}_{role}.nii.gz")
                interslice.write(path, a.T, {"spacing": SPACING_XYZ, "unit": "µm"})
                print(path, sha256_u8(a))
            if args.raw:
                # [z, y, x] C order is x fastest: the bytes as they are.
                path = os.path.join(args.out, f"blob{n}_{role}.u8")
                tmp = path + ".part"
                with open(tmp, "wb") as f:
                    f.write(np.ascontiguousarray(a, dtype=np.uint8).tobytes())
                os.replace(tmp, path)
                print(path, sha256_u8(a))
