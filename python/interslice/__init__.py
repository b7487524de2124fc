"""interslice for Python: slice interpolation and segmentation metrics on
numpy arrays, computed by interslice's Rust core.

Arrays are indexed ``[x, y, z]`` (nibabel's order) with ``spacing=(sx, sy,
sz)``. SimpleITK's ``GetArrayFromImage`` gives ``[z, y, x]``: pass its ``.T``
(a view, no copy) with ``image.GetSpacing()``.

>>> import interslice
>>> labels, meta = interslice.read("cell_labels.nii.gz")
>>> m = interslice.evaluate(labels, labels, meta["spacing"], label=2, unit=meta["unit"])
>>> m["dice"]
1.0

Every error is an ``interslice.Error`` (a ``ValueError``) whose message is the
one line the ``interslice`` command prints.
"""

from ._native import (
    DEFAULT_METHOD,
    DEFAULT_TOLERANCE,
    Error,
    advise,
    evaluate,
    interpolate,
    methods,
    overlap,
    phantom,
    read,
    staple,
    threshold,
    write,
)

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_METHOD",
    "DEFAULT_TOLERANCE",
    "Error",
    "advise",
    "evaluate",
    "interpolate",
    "methods",
    "overlap",
    "phantom",
    "read",
    "staple",
    "threshold",
    "write",
]
