# Sourced by the scripts/test-*.sh that check interslice against Python
# libraries: makes (once) a venv under target/pyenv with the packages named in
# $need, sets $venv and $bin (the test profile's interslice, built if needed).
target="${CARGO_TARGET_DIR:-target}"
venv="$target/pyenv"
imports="$(echo "$need" | tr ' ' ',')"
if ! "$venv/bin/python" -c "import $imports" 2>/dev/null; then
  echo "setting up $venv ($need)"
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check $need
fi
cargo build -q -p interslice-cli
bin="$target/debug/interslice"
