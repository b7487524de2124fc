#!/usr/bin/env bash
# Prints the path of the `interslice` binary the script tests run, building it
# first if needed. It is the one `cargo test --workspace` builds: building it
# with `cargo build -p interslice-cli` instead would resolve the dependencies'
# features for that package alone and compile many of them a second time
# (twice the disk and time of a clean run). PROFILE=release builds and prints
# the release binary instead.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${CARGO_TARGET_DIR:-$PWD/target}"
if [ "${PROFILE:-debug}" = release ]; then
  cargo build -q --release -p interslice-cli >&2
  echo "$(cd "$target/release" && pwd)/interslice"
else
  cargo test -q --workspace --no-run >&2
  echo "$(cd "$target/debug" && pwd)/interslice"
fi
