#!/usr/bin/env bash
# Mutation test of every volume and contours reader: thousands of seeded
# variants of valid files (truncations, byte flips, hostile header values,
# huge dims, bad spacing, data files outside the folder, compression bombs)
# are read by the real `interslice` binary under a 4 GiB address-space limit
# and a timeout; each must succeed or fail with one line `error: ...` and
# exit status 1 (crates/io/tests/integration/mutation.rs). MUTATION_SEED and
# MUTATION_VARIANTS change the set (defaults: a fixed seed, 3000 variants).
set -euo pipefail
cd "$(dirname "$0")/.."

INTERSLICE_BIN="$(scripts/built-binary.sh)" \
  cargo test -q --workspace --test integration -- --ignored --nocapture mutation::
