# Sourced by the scripts/test-*.sh that check interslice against Python
# libraries: makes (once) a venv under target/pyenv with the packages named in
# $need, sets $venv and $bin (the test profile's interslice, built if needed).
# An entry of $need is a PyPI name, or NAME=MODULE when the import name
# differs (pynrrd=nrrd).
target="${CARGO_TARGET_DIR:-target}"
venv="$target/pyenv"
imports="$(for p in $need; do echo "${p##*=}"; done | paste -sd, -)"
packages="$(for p in $need; do echo "${p%%=*}"; done | paste -sd' ' -)"
if ! "$venv/bin/python" -c "import $imports" 2>/dev/null; then
  echo "setting up $venv ($need)"
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check $packages
fi
bin="$(scripts/built-binary.sh)"
