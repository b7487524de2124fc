#!/usr/bin/env bash
# Cross-checks interslice's file formats with SimpleITK, nibabel and tifffile:
# files we write must be read by them with the same array, spacing and origin,
# and files they write must be read by us with the same values.
# Creates (once) a Python venv under target/pyenv with the libraries it needs.
set -euo pipefail
cd "$(dirname "$0")/.."

need="SimpleITK nibabel numpy tifffile pynrrd=nrrd"
. scripts/pyenv.sh
"$venv/bin/python" scripts/crosscheck_formats.py --bin "$bin"
