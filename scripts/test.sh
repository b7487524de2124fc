#!/usr/bin/env bash
# Runs every test of interslice: formatting, the web UI build (so the binary
# the tests build embeds the current UI), lints, the Rust test suite, then
# every scripts/test-*.sh (cross-checks with Python libraries, the web unit
# and end-to-end tests). Each of those installs what it needs.
set -euo pipefail
cd "$(dirname "$0")/.."

# Each stage's heading also says how long the stage before it took, so a slow
# stage shows in any log of a run.
stage_start=$SECONDS
stage() {
  [ -z "${stage_name:-}" ] || echo "-- $stage_name took $((SECONDS - stage_start)) s"
  stage_name="$1"
  stage_start=$SECONDS
  [ -z "$1" ] || echo "== $1"
}

stage "cargo fmt --check"
cargo fmt --all --check
stage "web UI build"
scripts/build-web.sh
export WEB_BUILT=1
stage "cargo clippy"
cargo clippy --workspace --all-targets -- -D warnings
stage "cargo doc"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet
stage "cargo test"
cargo test --workspace --no-fail-fast
for t in scripts/test-*.sh; do
  [ -e "$t" ] || continue
  stage "$t"
  bash "$t"
done
stage ""
echo "all tests passed in $SECONDS s"
