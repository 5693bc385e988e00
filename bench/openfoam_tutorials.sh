#!/usr/bin/env bash
# Every openfoam-examples tutorial with a blockMeshDict, meshed as its Allrun meshes it (blockMesh, and
# surfaceFeatureExtract + snappyHexMesh -overwrite where it has their dictionaries, serially), 0.orig as 0:
# checkMesh, tetpack check on the case, convert with every field, check on the file (tests/openfoam/tutorials.py).
# Writes bench/out/openfoam_tutorials.md (the table) and .json; cases meshing in over BUDGET s (default 60)
# are listed as slow. Run on demand: about half an hour on 2 cores.
#   bench/openfoam_tutorials.sh [BUILD_DIR] [TUTORIAL...]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
shift || true
mkdir -p bench/out
WORK=${TPK_BENCH_DIR:-/tmp/tpk_openfoam_tutorials}
/usr/bin/python3 tests/openfoam/tutorials.py "$BUILD/tetpack" "$WORK" --budget "${BUDGET:-60}" \
    --table bench/out/openfoam_tutorials.md --json bench/out/openfoam_tutorials.json "$@"
