#!/usr/bin/env bash
# Real test data that the repository does not carry, fetched from a package
# registry into a cache under the target dir, checked against a recorded
# sha256 and unpacked once. Prints the folder holding the files (last line of
# stdout), so any test can do `dir=$(scripts/fetch-data.sh pyradiomics)`.
#
#   pyradiomics   The `data/` folder of the pyradiomics 3.1.0 source
#                 distribution (PyPI; BSD-3-Clause): NRRD images with their
#                 label volumes. lung1/lung2: CT, int16 Hounsfield units,
#                 512x512 in-plane, 5 mm slices, a lesion label each;
#                 brain1/brain2: MR, int16, 256x256x25/23; breast1: MR, int16,
#                 45x120x21. Files: <case>_image.nrrd, <case>_label.nrrd.
#
# The cache is "${CARGO_TARGET_DIR:-target}/data" (DATA_CACHE overrides). The
# sdist's own metadata says 3.0.1a1, hence pip's legacy resolver below.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

name="${1:-}"
case "$name" in
  pyradiomics)
    version=3.1.0
    sdist="pyradiomics-$version.tar.gz"
    sha256=24722c962a6bbd09bc39c1c67dbffe92435f9692a421fabaae8a6b4511eb48e4
    ;;
  *)
    echo "usage: scripts/fetch-data.sh pyradiomics" >&2
    exit 2
    ;;
esac

target="${CARGO_TARGET_DIR:-$root/target}"
cache="${DATA_CACHE:-$target/data}"
out="$cache/$name-$version"
if [ -f "$out/.complete" ]; then
  echo "$out"
  exit 0
fi
mkdir -p "$cache"

# One fetch at a time per cache (tests may start together).
exec 9>"$cache/.$name.lock"
flock 9
if [ -f "$out/.complete" ]; then
  echo "$out"
  exit 0
fi

python=""
for p in python3 python; do
  if command -v "$p" >/dev/null && "$p" -m pip --version >/dev/null 2>&1; then
    python="$p"
    break
  fi
done
if [ -z "$python" ]; then
  echo "error: fetching the $name test data needs pip (python3 -m pip)" >&2
  exit 1
fi

work="$(mktemp -d "$cache/.$name.XXXXXX")"
trap 'rm -rf "$work"' EXIT
if [ ! -f "$cache/$sdist" ]; then
  echo "fetching $sdist from PyPI (once, into $cache)" >&2
  if ! "$python" -m pip download --quiet --disable-pip-version-check --no-deps \
    --no-binary pyradiomics --use-deprecated=legacy-resolver \
    -d "$work" "pyradiomics==$version" >"$work/pip.log" 2>&1; then
    echo "error: could not download pyradiomics==$version from PyPI (is the package registry reachable?); pip said:" >&2
    tail -n 5 "$work/pip.log" >&2
    exit 1
  fi
  if [ ! -f "$work/$sdist" ]; then
    echo "error: pip did not produce $sdist" >&2
    exit 1
  fi
  mv "$work/$sdist" "$cache/$sdist.part"
  mv "$cache/$sdist.part" "$cache/$sdist"
fi

got="$(sha256sum "$cache/$sdist" | cut -d' ' -f1)"
if [ "$got" != "$sha256" ]; then
  rm -f "$cache/$sdist"
  echo "error: $sdist has sha256 $got, expected $sha256 (removed; run again to fetch it anew)" >&2
  exit 1
fi

tar -xzf "$cache/$sdist" -C "$work" --wildcards "pyradiomics-$version/data/*.nrrd"
rm -rf "$out"
mv "$work/pyradiomics-$version/data" "$out"
touch "$out/.complete"
echo "$out"
