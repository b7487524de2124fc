#!/usr/bin/env bash
# Fetch the development data of the interpolation benchmark (`interslice bench`)
# from package registries, check their checksums and unpack them into a cache
# under the target dir. Prints the folder. Re-running is free once cached.
#
#   stardist 0.9.1 wheel (PyPI): stardist/data/images/img3d.tif + mask3d.tif
#     (synthetic 3D nuclei with their label mask; 0.9.2 has the same files but
#     no wheel for every Python, so the pinned 0.9.1 wheel is used)
#   pyradiomics 3.1.0 sdist (PyPI): data/*_image.nrrd + *_label.nrrd
#     (CT lung1/lung2 in HU with lesion labels, MR brain1/brain2/breast1)
#   insighttoolkit5-examples (Debian): KmeansTest_T1UCharRaw.nii.gz and its
#     k-means segmentation KmeansTest_T1KmeansPrelimSegmentation.nii.gz
#   nilearn 0.10.3 wheel (PyPI): the MNI ICBM152 2009a template bundled with it,
#     T1 and grey / white matter probability maps, 197x233x189 at 1 mm
#     (nilearn/datasets/data/mni_icbm152_{t1,gm,wm}_tal_nlin_sym_09a_converted.nii.gz)
#
# Usage: scripts/fetch-interp-data.sh [--only stardist|pyradiomics|itk|mni]...
set -euo pipefail
target="${CARGO_TARGET_DIR:-target}"
cache="$target/interp-data"
mkdir -p "$cache/downloads"
cache="$(cd "$cache" && pwd)"
dl="$cache/downloads"

want_all=1
declare -A want=()
while [ $# -gt 0 ]; do
  case "$1" in
    --only) want["$2"]=1; want_all=0; shift 2 ;;
    *) echo "usage: $0 [--only stardist|pyradiomics|itk|mni]..." >&2; exit 2 ;;
  esac
done
wanted() { [ "$want_all" = 1 ] || [ -n "${want[$1]:-}" ]; }

STARDIST_WHL="stardist-0.9.1-cp311-cp311-manylinux_2_17_x86_64.manylinux2014_x86_64.whl"
STARDIST_SHA="1f2caf3a071c1ead1b0cbbf9614ff2c82967be1bd22764f097871fb9bbd2718f"
RADIOMICS_TGZ="pyradiomics-3.1.0.tar.gz"
RADIOMICS_SHA="24722c962a6bbd09bc39c1c67dbffe92435f9692a421fabaae8a6b4511eb48e4"
ITK_DEB="insighttoolkit5-examples_5.2.1-5+deb12u1_all.deb"
ITK_SHA="6ca1f323eac0b3cba50e786bbf0f2c76ed44b52ecb9e7aeea808ccc42bf09f69"
NILEARN_WHL="nilearn-0.10.3-py3-none-any.whl"
NILEARN_SHA="353bc3c4a73b20ade1d6a35287236c9cccd4f293f9aed75c4fc37110c02ebbb5"

check() { # file sha
  local got
  got="$(sha256sum "$1" | cut -d' ' -f1)"
  if [ "$got" != "$2" ]; then
    echo "error: checksum mismatch for $1 (got $got, want $2)" >&2
    rm -f "$1"
    exit 1
  fi
}

unreachable() {
  echo "error: could not download $1 from its package registry (offline?); the interpolation benchmark needs it" >&2
  exit 1
}

if wanted stardist && [ ! -f "$cache/stardist/mask3d.tif" ]; then
  if [ ! -f "$dl/$STARDIST_WHL" ]; then
    python3 -m pip download -q --disable-pip-version-check --no-deps \
      --only-binary=:all: --python-version 3.11 --platform manylinux2014_x86_64 \
      stardist==0.9.1 -d "$dl" >/dev/null 2>&1 || unreachable "stardist==0.9.1"
  fi
  check "$dl/$STARDIST_WHL" "$STARDIST_SHA"
  mkdir -p "$cache/stardist.tmp"
  python3 - "$dl/$STARDIST_WHL" "$cache/stardist.tmp" <<'EOF'
import sys, zipfile
z = zipfile.ZipFile(sys.argv[1])
for name in ("img3d.tif", "mask3d.tif"):
    with open(f"{sys.argv[2]}/{name}", "wb") as f:
        f.write(z.read(f"stardist/data/images/{name}"))
EOF
  rm -rf "$cache/stardist" && mv "$cache/stardist.tmp" "$cache/stardist"
fi

if wanted pyradiomics && [ ! -f "$cache/pyradiomics/lung2_label.nrrd" ]; then
  if [ ! -f "$dl/$RADIOMICS_TGZ" ]; then
    python3 -m pip download -q --disable-pip-version-check --no-deps --no-binary pyradiomics \
      --use-deprecated=legacy-resolver pyradiomics==3.1.0 -d "$dl" >/dev/null 2>&1 \
      || unreachable "pyradiomics==3.1.0"
  fi
  check "$dl/$RADIOMICS_TGZ" "$RADIOMICS_SHA"
  rm -rf "$cache/pyradiomics.tmp" && mkdir -p "$cache/pyradiomics.tmp"
  tar -xzf "$dl/$RADIOMICS_TGZ" -C "$cache/pyradiomics.tmp" --strip-components=2 \
    --wildcards 'pyradiomics-3.1.0/data/*.nrrd'
  rm -rf "$cache/pyradiomics" && mv "$cache/pyradiomics.tmp" "$cache/pyradiomics"
fi

if wanted itk && [ ! -f "$cache/itk/T1_kmeans.nii.gz" ]; then
  if [ ! -f "$dl/$ITK_DEB" ]; then
    get_deb() { (cd "$dl" && apt-get download "insighttoolkit5-examples=5.2.1-5+deb12u1" >/dev/null 2>&1); }
    # A fresh machine has no package lists yet: as root, fetch them once.
    get_deb || { [ "$(id -u)" = 0 ] && apt-get update -qq >/dev/null 2>&1 && get_deb; } \
      || unreachable "insighttoolkit5-examples (run apt-get update first)"
  fi
  check "$dl/$ITK_DEB" "$ITK_SHA"
  rm -rf "$cache/itk.tmp" && mkdir -p "$cache/itk.tmp"
  d=./usr/share/doc/insighttoolkit5-examples/examples/Data
  dpkg-deb --fsys-tarfile "$dl/$ITK_DEB" | tar -x -C "$cache/itk.tmp" \
    "$d/KmeansTest_T1UCharRaw.nii.gz" "$d/KmeansTest_T1KmeansPrelimSegmentation.nii.gz"
  mv "$cache/itk.tmp/$d/KmeansTest_T1UCharRaw.nii.gz" "$cache/itk.tmp/T1.nii.gz"
  mv "$cache/itk.tmp/$d/KmeansTest_T1KmeansPrelimSegmentation.nii.gz" "$cache/itk.tmp/T1_kmeans.nii.gz"
  rm -rf "$cache/itk.tmp/usr"
  rm -rf "$cache/itk" && mv "$cache/itk.tmp" "$cache/itk"
fi

if wanted mni && [ ! -f "$cache/mni/wm.nii.gz" ]; then
  if [ ! -f "$dl/$NILEARN_WHL" ]; then
    python3 -m pip download -q --disable-pip-version-check --no-deps \
      --only-binary=:all: nilearn==0.10.3 -d "$dl" >/dev/null 2>&1 || unreachable "nilearn==0.10.3"
  fi
  check "$dl/$NILEARN_WHL" "$NILEARN_SHA"
  rm -rf "$cache/mni.tmp" && mkdir -p "$cache/mni.tmp"
  python3 - "$dl/$NILEARN_WHL" "$cache/mni.tmp" <<'EOF'
import sys, zipfile
z = zipfile.ZipFile(sys.argv[1])
for name in ("t1", "gm", "wm"):
    src = f"nilearn/datasets/data/mni_icbm152_{name}_tal_nlin_sym_09a_converted.nii.gz"
    with open(f"{sys.argv[2]}/{name}.nii.gz", "wb") as f:
        f.write(z.read(src))
EOF
  rm -rf "$cache/mni" && mv "$cache/mni.tmp" "$cache/mni"
fi

echo "$cache"
