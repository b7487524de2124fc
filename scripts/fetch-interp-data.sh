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
#   mricron-data (Debian): the AAL atlas (Tzourio-Mazoyer et al. 2002), brain
#     structures delineated by hand on the T1 of one subject (the MNI "colin27"
#     single subject, ch2), with that T1, both 181x217x181 at 1 mm
#     (usr/share/mricron/templates/aal.nii.gz, ch2.nii.gz)
#
# Usage: scripts/fetch-interp-data.sh [--only stardist|pyradiomics|itk|mni|aal]...
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
    *) echo "usage: $0 [--only stardist|pyradiomics|itk|mni|aal]..." >&2; exit 2 ;;
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
MRICRON_VERSION="1.2.20211006+dfsg-4"
MRICRON_DEB="mricron-data_${MRICRON_VERSION}_all.deb"
MRICRON_SHA="d40aa0ed66cf89bf6cafa049ad3884703c9d975c2ee2737525b7196528df9d6f"

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

# A Debian package pinned to its version, into the downloads; a fresh
# machine has no package lists yet: as root, they are fetched once.
get_deb() { # package=version
  (cd "$dl" && apt-get download "$1" >/dev/null 2>&1) \
    || { [ "$(id -u)" = 0 ] && apt-get update -qq >/dev/null 2>&1 \
      && (cd "$dl" && apt-get download "$1" >/dev/null 2>&1); } \
    || unreachable "${1%%=*} (run apt-get update first)"
}

if wanted itk && [ ! -f "$cache/itk/T1_kmeans.nii.gz" ]; then
  [ -f "$dl/$ITK_DEB" ] || get_deb "insighttoolkit5-examples=5.2.1-5+deb12u1"
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

if wanted aal && [ ! -f "$cache/aal/aal.nii.gz" ]; then
  [ -f "$dl/$MRICRON_DEB" ] || get_deb "mricron-data=$MRICRON_VERSION"
  check "$dl/$MRICRON_DEB" "$MRICRON_SHA"
  rm -rf "$cache/aal.tmp" && mkdir -p "$cache/aal.tmp"
  d=./usr/share/mricron/templates
  dpkg-deb --fsys-tarfile "$dl/$MRICRON_DEB" | tar -x -C "$cache/aal.tmp" \
    "$d/aal.nii.gz" "$d/ch2.nii.gz"
  mv "$cache/aal.tmp/$d/aal.nii.gz" "$cache/aal.tmp/$d/ch2.nii.gz" "$cache/aal.tmp/"
  rm -rf "$cache/aal.tmp/usr"
  rm -rf "$cache/aal" && mv "$cache/aal.tmp" "$cache/aal"
fi

echo "$cache"
