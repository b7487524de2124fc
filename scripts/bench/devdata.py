"""The development masks of `interslice bench`, under its protocol.

Shared by the anchors that run outside the binary (`random_walker_anchor.py`,
`mci_anchor.py`): each mask cropped to its box grown by 8 voxels, the first
and last non-empty z slices and every (k+1)-th slice from the first drawn,
Dice on the skipped slices only. The data come from
`scripts/fetch-interp-data.sh`; the noisy phantom is generated inside
`interslice bench` and is not covered here.
"""
import numpy as np

import interslice

MARGIN = 8


# The AAL structures of `interslice bench` (its `AAL_STRUCTURES`).
AAL_STRUCTURES = [
    (37, "hippocampus-l"), (38, "hippocampus-r"), (41, "amygdala-l"), (42, "amygdala-r"),
    (71, "caudate-l"), (72, "caudate-r"), (73, "putamen-l"), (74, "putamen-r"),
    (75, "pallidum-l"), (76, "pallidum-r"), (77, "thalamus-l"), (78, "thalamus-r"),
]


def cases(data, t1, mni=False, aal=False):
    """(name, mask, image) of every development mask with an image, as
    `interslice bench` names them (the T1 classes only with `t1`, the MNI
    template's grey and white matter only with `mni`, the AAL structures
    only with `aal`)."""
    sd = data / "stardist"
    if (sd / "mask3d.tif").is_file():
        lab, _ = interslice.read(sd / "mask3d.tif")
        img, _ = interslice.read(sd / "img3d.tif")
        yield "stardist-all", lab > 0, img
    pr = data / "pyradiomics"
    for name in ["lung1", "lung2", "brain1", "brain2", "breast1"]:
        if (pr / f"{name}_label.nrrd").is_file():
            lab, _ = interslice.read(pr / f"{name}_label.nrrd")
            img, _ = interslice.read(pr / f"{name}_image.nrrd")
            yield name, lab > 0, img
    itk = data / "itk"
    if t1 and (itk / "T1_kmeans.nii.gz").is_file():
        lab, _ = interslice.read(itk / "T1_kmeans.nii.gz")
        img, _ = interslice.read(itk / "T1.nii.gz")
        for c in sorted(set(np.unique(lab)) - {0}):
            yield f"T1-class{c}", lab == c, img
    tpl = data / "mni"
    if mni and (tpl / "wm.nii.gz").is_file():
        img, _ = interslice.read(tpl / "t1.nii.gz")
        for cls, name in [("gm", "mni-grey"), ("wm", "mni-white")]:
            prob, _ = interslice.read(tpl / f"{cls}.nii.gz")
            # As `interslice bench`: more likely than not (0..255 for 0..1).
            yield name, prob.astype(np.float32) > 127.5, img
    atlas = data / "aal"
    if aal and (atlas / "aal.nii.gz").is_file():
        lab, _ = interslice.read(atlas / "aal.nii.gz")
        img, _ = interslice.read(atlas / "ch2.nii.gz")
        for label, name in AAL_STRUCTURES:
            yield f"aal-{name}", lab == label, img


def cropped(mask, img):
    """Mask and image cut to the mask's box grown by MARGIN voxels."""
    idx = np.argwhere(mask)
    lo = np.maximum(idx.min(0) - MARGIN, 0)
    hi = np.minimum(idx.max(0) + MARGIN + 1, mask.shape)
    box = tuple(slice(a, b) for a, b in zip(lo, hi))
    return mask[box], img[box].astype(np.float32)


def drawn_and_skipped(mask, k):
    """The drawn z slices (first and last non-empty, every (k+1)-th from the
    first) and the skipped ones between the first and the last."""
    zs = [z for z in range(mask.shape[2]) if mask[:, :, z].any()]
    first, last = zs[0], zs[-1]
    drawn = list(range(first, last + 1, k + 1))
    if drawn[-1] != last:
        drawn.append(last)
    skipped = [z for z in range(first, last + 1) if z not in drawn]
    return drawn, skipped


def dice_skipped(result, mask, skipped):
    """Dice of `result` against `mask` on the skipped slices (1 if both are
    empty there)."""
    a, b = result[:, :, skipped], mask[:, :, skipped]
    total = a.sum() + b.sum()
    return 2 * (a & b).sum() / total if total else 1.0
