#!/usr/bin/env bash
# Cross-checks interslice's file formats with SimpleITK, nibabel and tifffile:
# files we write must be read by them with the same array, spacing and origin,
# and files they write must be read by us with the same values.
# Creates (once) a Python venv under target/pyenv with the libraries it needs.
set -euo pipefail
cd "$(dirname "$0")/.."

target="${CARGO_TARGET_DIR:-target}"
venv="$target/pyenv"
need="SimpleITK nibabel numpy tifffile"
if ! "$venv/bin/python" -c "import SimpleITK, nibabel, numpy, tifffile" 2>/dev/null; then
  echo "setting up $venv ($need)"
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check $need
fi

cargo build -q -p interslice-cli
"$venv/bin/python" scripts/crosscheck_formats.py --bin "$target/debug/interslice"
