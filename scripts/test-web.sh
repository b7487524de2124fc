#!/usr/bin/env bash
# The web UI's tests: exact npm dependencies, unit tests (vitest), typecheck and
# build, then the release binary (which embeds the fresh web/dist) and the
# end-to-end suites in headless Chromium against the real `interslice demo`.
#
#   SCREENSHOTS=docs/screenshots bash scripts/test-web.sh   # also refresh the screenshots
#   E2E_FIGURES=figures.json ...                            # keep the measured figures
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

if ! command -v npm >/dev/null; then
  echo "error: npm (Node.js 20) is needed for the web UI tests" >&2
  exit 1
fi

echo "-- npm ci"
(cd web && npm ci --no-audit --no-fund --loglevel=error)
echo "-- vitest"
(cd web && npx vitest run)
echo "-- typecheck and build"
(cd web && npm run build --silent)

echo "-- release binary (embeds web/dist)"
cargo build --release -p interslice-cli

if [ ! -x /usr/bin/chromium ]; then
  echo "-- installing chromium"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq chromium >/dev/null
fi

echo "-- end-to-end (headless Chromium, real server)"
[ -n "${SCREENSHOTS:-}" ] && export SCREENSHOTS="$(realpath -m "$SCREENSHOTS")"
[ -n "${E2E_FIGURES:-}" ] && export E2E_FIGURES="$(realpath -m "$E2E_FIGURES")"
export INTERSLICE_BIN="$root/target/release/interslice"
(cd web && npm run e2e --silent)
