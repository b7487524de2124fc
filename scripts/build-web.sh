#!/usr/bin/env bash
# Builds the browser UI into web/dist (embedded into the binary by the next
# cargo build). Installs the exact npm dependencies of package-lock.json first.
set -euo pipefail
cd "$(dirname "$0")/../web"
if ! command -v npm >/dev/null; then
  echo "error: npm (Node.js 20) is needed to build the web UI" >&2
  exit 1
fi
npm ci --no-audit --no-fund --loglevel=error
npm run build --silent
