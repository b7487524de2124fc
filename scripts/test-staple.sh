#!/usr/bin/env bash
# Compares `interslice staple` with SimpleITK's STAPLEImageFilter on the same
# raters (synthetic flips with known sensitivity/specificity, noisy copies of a
# phantom nucleus, boundary disagreement, five raters): estimates, probability
# maps and consensus must agree (scripts/staple_sitk.py).
# Creates (once) a Python venv under target/pyenv with the libraries it needs.
set -euo pipefail
cd "$(dirname "$0")/.."

need="SimpleITK numpy"
. scripts/pyenv.sh
"$venv/bin/python" scripts/staple_sitk.py --bin "$bin"
