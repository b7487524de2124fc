#!/usr/bin/env bash
# Generates web/generated/api-schema.d.ts, the TypeScript types of the HTTP API,
# from the OpenAPI document the server itself serves (GET /api/openapi.json),
# with openapi-typescript (a web/ dev dependency). The server is started with
# `interslice serve` on an empty temporary folder and a free loopback port.
#
#   scripts/gen-api-types.sh           # rewrite web/generated/api-schema.d.ts
#   scripts/gen-api-types.sh --check   # fail if it differs from what the binary says
#
# The binary: INTERSLICE_BIN, else ${CARGO_TARGET_DIR:-target}/${PROFILE:-debug}/interslice.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
check=0
[ "${1:-}" = --check ] && check=1
bin="${INTERSLICE_BIN:-${CARGO_TARGET_DIR:-$root/target}/${PROFILE:-debug}/interslice}"
if [ ! -x "$bin" ]; then
  echo "error: $bin not found: build it with cargo build -p interslice-cli" >&2
  exit 1
fi
out=web/generated/api-schema.d.ts
tmp=$(mktemp -d)
pid=
cleanup() {
  if [ -n "$pid" ]; then
    kill "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT

port=$(node -e 'const s=require("net").createServer();s.listen(0,"127.0.0.1",()=>{console.log(s.address().port);s.close()})')
mkdir "$tmp/project"
"$bin" serve "$tmp/project" --bind "127.0.0.1:$port" --db "$tmp/db.sqlite" >"$tmp/log" 2>&1 &
pid=$!
for _ in $(seq 1 300); do
  if curl -sf "http://127.0.0.1:$port/api/openapi.json" -o "$tmp/openapi.json"; then break; fi
  if ! kill -0 "$pid" 2>/dev/null; then
    echo "error: interslice serve exited:" >&2
    cat "$tmp/log" >&2
    exit 1
  fi
  sleep 0.2
done
if [ ! -s "$tmp/openapi.json" ]; then
  echo "error: no answer from GET /api/openapi.json in 60 s" >&2
  exit 1
fi

(cd web && npx --no-install openapi-typescript "$tmp/openapi.json" -o "$tmp/api-schema.d.ts" >/dev/null)
if [ "$check" = 1 ]; then
  if ! diff -u "$out" "$tmp/api-schema.d.ts"; then
    echo "error: $out is not what the server's OpenAPI document gives: run scripts/gen-api-types.sh" >&2
    exit 1
  fi
  echo "$out matches the server's OpenAPI document"
else
  mv "$tmp/api-schema.d.ts" "$out"
  echo "wrote $out"
fi
