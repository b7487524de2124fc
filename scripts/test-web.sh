#!/usr/bin/env bash
# Web UI tests: install (npm ci), typecheck, unit tests (vitest), production
# build, then the end-to-end test in headless Chromium against a real
# `interslice demo` server. Screenshots go to docs/screenshots when
# SCREENSHOTS=1. Idempotent; exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

if ! command -v node >/dev/null 2>&1; then
  echo "node is required (Node 20 or newer)" >&2
  exit 1
fi
if [ ! -x /usr/bin/chromium ]; then
  if [ "$(id -u)" = 0 ]; then
    (apt-get update -qq && apt-get install -y -qq chromium) >/dev/null
  else
    echo "/usr/bin/chromium is missing (apt-get install chromium)" >&2
    exit 1
  fi
fi

cd web
echo "== web: npm ci"
npm ci --no-audit --no-fund --loglevel=error
echo "== web: typecheck"
npx tsc --noEmit
echo "== web: unit tests"
npx vitest run
echo "== web: build"
npx vite build --logLevel warn

cd "$root"
echo "== web: server binary"
# The server embeds web/dist at build time, so build it after the web build.
# Debug by default (it shares the artifacts of `cargo test`); WEB_E2E_PROFILE=release
# for figures representative of a release build.
profile="${WEB_E2E_PROFILE:-debug}"
if [ "$profile" = release ]; then
  cargo build --release -q -p interslice-cli
else
  cargo build -q -p interslice-cli
fi
bin="${CARGO_TARGET_DIR:-$root/target}/$profile/interslice"

echo "== web: end-to-end (headless Chromium)"
shots=()
if [ "${SCREENSHOTS:-0}" = 1 ]; then shots=(--shots "$root/docs/screenshots"); fi
timeout 420 node web/e2e/run.mjs --bin "$bin" "${shots[@]}"
