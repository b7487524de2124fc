#!/usr/bin/env bash
# Runs every test of interslice: formatting, the web UI build (so the binary
# the tests build embeds the current UI), lints, the Rust test suite, then
# every scripts/test-*.sh (cross-checks with Python libraries, the web unit
# and end-to-end tests). Each of those installs what it needs.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo fmt --check"
cargo fmt --all --check
echo "== web UI build"
scripts/build-web.sh
export WEB_BUILT=1
echo "== cargo clippy"
cargo clippy --workspace --all-targets -- -D warnings
echo "== cargo doc"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet
echo "== cargo test"
cargo test --workspace --no-fail-fast
for t in scripts/test-*.sh; do
  [ -e "$t" ] || continue
  echo "== $t"
  bash "$t"
done
echo "all tests passed"
