#!/usr/bin/env bash
# The image-guided interpolation on real data: fetches stardist's synthetic 3D
# nuclei (a PyPI wheel of about 3 MB) and ITK's example T1 with its k-means
# classes (a Debian package of 1.7 MB), the MNI template with its grey and
# white matter (the nilearn wheel, 10 MB) and the AAL atlas with the T1 it was
# traced on (Debian's mricron-data, 16 MB), checksummed and cached under the
# target dir, and runs crates/interp/tests/integration/image_data.rs on them.
set -euo pipefail
cd "$(dirname "$0")/.."
data="$(scripts/fetch-interp-data.sh --only stardist --only itk --only mni --only aal)"
INTERSLICE_INTERP_DATA="$data" cargo test -q --workspace --test integration -- image_data::
