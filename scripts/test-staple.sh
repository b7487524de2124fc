#!/usr/bin/env bash
# Compares `interslice staple` with SimpleITK's STAPLEImageFilter on the same
# raters (synthetic flips with known sensitivity/specificity, noisy copies of a
# phantom nucleus, boundary disagreement, five raters): estimates, probability
# maps and consensus must agree (scripts/staple_sitk.py).
# Creates (once) a Python venv under target/pyenv with the libraries it needs.
set -euo pipefail
cd "$(dirname "$0")/.."

target="${CARGO_TARGET_DIR:-target}"
venv="$target/pyenv"
need="SimpleITK numpy"
if ! "$venv/bin/python" -c "import SimpleITK, numpy" 2>/dev/null; then
  echo "setting up $venv ($need)"
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check $need
fi

cargo build -q -p interslice-cli
"$venv/bin/python" scripts/staple_sitk.py --bin "$target/debug/interslice"
