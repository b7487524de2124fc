#!/usr/bin/env bash
# Tests the Python package in python/ (its Rust crate is a workspace member,
# formatted and linted with the rest by scripts/test.sh): builds the wheel
# with maturin, installs it with the napari extra into a venv under the
# target dir, and runs its pytest suite (round trips through every format,
# evaluate and interpolate against the command line, errors, the GIL, and
# the napari dock widget headless with Qt offscreen).
#
# Creates (once) the venv $target/pyenv-package with napari[pyqt5], pytest,
# pytest-qt and maturin from PyPI, and installs (as root, once, only when
# missing) the Debian libraries Qt's offscreen platform needs.
set -euo pipefail
cd "$(dirname "$0")/.."
repo="$PWD"
target="${CARGO_TARGET_DIR:-$repo/target}"
mkdir -p "$target"
target="$(cd "$target" && pwd)"
# python/ is a member of the main workspace whose dependencies' features are
# pinned to the workspace's (python/Cargo.toml): maturin, building it alone
# into the main target dir, reuses every dependency `cargo test --workspace`
# compiled instead of compiling them all a second time.
export CARGO_TARGET_DIR="$target"
venv="$target/pyenv-package"
py="$venv/bin/python"

need="napari[pyqt5] pytest pytest-qt pyyaml maturin>=1.9,<2"
if ! "$py" -c "import napari, PyQt5, pytest, pytestqt, yaml, maturin" 2>/dev/null; then
  echo "setting up $venv ($need)"
  python3 -m venv "$venv"
  if ! "$py" -m pip install -q --disable-pip-version-check $need; then
    echo "error: could not install $need from PyPI (is it reachable?)" >&2
    exit 1
  fi
fi

# Qt's offscreen platform still loads libGL, EGL, fontconfig, xkbcommon and
# dbus, and napari's canvas needs an OpenGL context, which the offscreen
# platform takes from an X display: the tests run under Xvfb (Mesa renders).
libs="xvfb xauth libgl1 libgl1-mesa-dri libegl1 libglib2.0-0 libfontconfig1 libxkbcommon0 libdbus-1-3"
qt_ok() {
  command -v xvfb-run >/dev/null &&
    QT_QPA_PLATFORM=offscreen xvfb-run -a "$py" -c \
      "from qtpy.QtWidgets import QApplication; QApplication([])" >/dev/null 2>&1
}
if ! qt_ok; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "installing what Qt offscreen and napari's canvas need: $libs"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $libs >/dev/null
  fi
  if ! qt_ok; then
    echo "error: Qt cannot start offscreen under Xvfb; install $libs" >&2
    exit 1
  fi
fi

echo "== python/: wheel"
# The dev profile (optimised dependencies, as in the workspace) reuses what
# `cargo build` compiled; `pip install ./python` builds the release wheel.
rm -rf "$target/wheels-python"
"$venv/bin/maturin" build -q --strip --profile dev -m python/Cargo.toml -i "$py" -o "$target/wheels-python"
"$py" -m pip install -q --disable-pip-version-check --force-reinstall --no-deps "$target"/wheels-python/interslice-*.whl

INTERSLICE_BIN="$(scripts/built-binary.sh)"
export INTERSLICE_BIN

echo "== python/: pytest"
QT_QPA_PLATFORM=offscreen xvfb-run -a "$py" -m pytest -q -p no:cacheprovider python/tests
