#!/usr/bin/env bash
# The command-line pipeline, without the browser: builds interslice (release)
# and runs the whole job on the built-in demo data: synthetic cell-CT volumes
# with their exact labels, a sparse tracing of every 5th slice, interpolation
# of the rest, the metrics against the truth, a surface mesh, and the
# interpolation study. Everything lands in demo-data/pipeline/ (override with
# DEMO_DIR). Idempotent: re-running regenerates the same files.
set -euo pipefail
cd "$(dirname "$0")/.."

out="${DEMO_DIR:-demo-data/pipeline}"
echo "== building (release)"
cargo build --release -q -p interslice-cli
bin="${CARGO_TARGET_DIR:-target}/release/interslice"
mkdir -p "$out"

echo "== 1. three synthetic cells (intensities + exact labels)"
"$bin" phantom --out "$out" --count 3 --size 128 --seed 1
"$bin" info "$out/cell_001.nii.gz"
"$bin" info "$out/cell_001_labels.nii.gz"

echo "== 2. a tracer draws every 5th slice of cell 1 (contours file), painted into a sparse volume"
"$bin" contours extract "$out/cell_001_labels.nii.gz" --every 5 --author demo \
  --out "$out/cell_001_traced.json"
"$bin" contours rasterize "$out/cell_001_traced.json" --out "$out/cell_001_sparse.nii.gz" \
  --drawn-out "$out/cell_001_drawn.txt"

echo "== 3. interpolate the skipped slices (default method; --list shows all)"
"$bin" interpolate --list
"$bin" interpolate "$out/cell_001_sparse.nii.gz" --drawn "$out/cell_001_drawn.txt" \
  --out "$out/cell_001_interpolated.nii.gz"

echo "== 4. measure the interpolation against the truth"
"$bin" evaluate "$out/cell_001_labels.nii.gz" "$out/cell_001_interpolated.nii.gz"

echo "== 5. the nucleus surface, in micrometres"
"$bin" mesh "$out/cell_001_interpolated.nii.gz" --label 2 --out "$out/cell_001_nucleus.stl"

echo "== 6. the study: every method, 0..9 skipped slices, against the truth (nucleus)"
"$bin" study "$out/cell_001_labels.nii.gz" --label 2 --out "$out/study"
echo
echo "done: results in $out/ (study summary: $out/study/summary.md)"
