#!/usr/bin/env bash
# Builds everything (the web UI, then the release binary that embeds it) and
# starts the main job on the built-in demo data: `interslice demo` writes three
# synthetic cells (with their exact labels in ground_truth/) to demo-data/project
# and serves them for tracing. Open the printed URL, sign in with a name, trace.
# Existing tracings in demo-data/project are kept between runs.
#
# Environment: DEMO_DIR (project folder), BIND (default 127.0.0.1:8080).
set -euo pipefail
cd "$(dirname "$0")/.."

dir="${DEMO_DIR:-demo-data/project}"
bind="${BIND:-127.0.0.1:8080}"

echo "== building the web UI"
scripts/build-web.sh
echo "== building interslice (release)"
cargo build --release -q -p interslice-cli
bin="${CARGO_TARGET_DIR:-target}/release/interslice"

echo "== serving the demo cells"
exec "$bin" demo "$dir" --bind "$bind"
