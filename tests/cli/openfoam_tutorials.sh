#!/usr/bin/env bash
# OpenFOAM tutorials as their users have them (issue 40), meshed here by their own blockMesh and
# snappyHexMesh, 0.orig as 0: checkMesh passes, `tetpack check` finds no 3xx/4xx error in the case and no
# error in the converted file, the region counts agree and every field is kept (tests/openfoam/tutorials.py;
# the whole corpus: bench/openfoam_tutorials.sh). windAroundBuildings as shipped (185,237 cells, $kInlet in
# 0/k, #includeEtc) converts with k, epsilon, nut, p and U; freePiston's fields are binary without an arch,
# read through #include and $:internalField.T; the others use #include, $internalField and ${..}.
source "$(dirname "$0")/common.sh"
command -v blockMesh > /dev/null && command -v snappyHexMesh > /dev/null || skip "openfoam not installed"
[ -d /usr/share/doc/openfoam-examples/examples ] || skip "openfoam-examples not installed"
export WM_PROJECT_DIR=${WM_PROJECT_DIR:-/usr/share/openfoam}
set +e
"$PY" "$SRC/tests/openfoam/tutorials.py" "$TPK" "$WORK/cases" --budget 600 --json "$WORK/rows.json" \
    incompressible/simpleFoam/windAroundBuildings combustion/coldEngineFoam/freePiston \
    basic/scalarTransportFoam/pitzDaily DNS/dnsFoam/boxTurb16 IO/systemCall \
    heatTransfer/buoyantBoussinesqSimpleFoam/iglooWithFridges
rc=$?
set -e
[ $rc -eq 0 ] || fail "a tutorial failed (above)"
"$PY" - "$WORK/rows.json" <<'PY' || fail "windAroundBuildings"
import json, sys
rows = {r["tutorial"]: r for r in json.load(open(sys.argv[1]))}
w = rows["incompressible/simpleFoam/windAroundBuildings"]
print("windAroundBuildings: %d cells, %d tets, fields %s, %d kept, %d flat tets, convert %.1f s" % (
    w["cells"], w["tets"], w["fields"], w["fields_kept"], w["flat_tets"], w["convert_seconds"]))
assert w["verdict"] == "ok" and w["cells"] == 185237 and w["fields"] == "5/5" and w["fields_kept"] == 5, w
assert rows["combustion/coldEngineFoam/freePiston"]["fields"] == "8/8", rows["combustion/coldEngineFoam/freePiston"]
assert all(r["verdict"] == "ok" for r in rows.values()), rows
PY
echo "$(grep -c tutorial "$WORK/rows.json") passed, 0 failed"
