# Orientation is a labeling (issue 9): OpenFOAM lists every prism in the mirrored node order (foamToVTK
# keeps it). blockMesh makes 32 prisms and 96 hexahedra (tests/cli/openfoam_prisms/), foamToVTK writes
# them; convert turns the prisms over by default, counts them, and writes a file that passes every 6xx
# check; --strict-orientation refuses them by name. Needs Debian's openfoam; exits 77 (skipped) without.
source "$(dirname "$0")/common.sh"
command -v blockMesh > /dev/null && command -v foamToVTK > /dev/null || skip "openfoam not installed"
export WM_PROJECT_DIR=${WM_PROJECT_DIR:-/usr/share/openfoam}

cp -r "$SRC/tests/cli/openfoam_prisms" "$WORK/case"
mkdir -p "$WORK/case/constant"
(cd "$WORK/case" && blockMesh > log.blockMesh 2>&1 && foamToVTK > log.foamToVTK 2>&1) ||
    { tail "$WORK/case/log."*; fail "OpenFOAM failed"; }
vtu="$WORK/case/VTK/case_0/internal.vtu"

convert_checked "$vtu" "$WORK/of.tpk" --json > "$WORK/of.json"
"$PY" -c "
import json; d = json.load(open('$WORK/of.json')); s = d['cells_split']
assert s['wedge_into_3'] == 32 and s['hexahedron_into_5'] + s['hexahedron_into_6'] == 96, s
assert d['mirrored_cells'] == 32 and d['repairs']['reorient'] == {'requested': True, 'inverted_tets': 0, 'mirrored_cells': 32}, d
assert d['folds_cut'] == 0 and d['tets'] == 3 * 32 + 6 * s['hexahedron_into_6'] + 5 * s['hexahedron_into_5'], d
" || fail "summary"
convert_checked "$vtu" "$WORK/of.tpk" > "$WORK/out"
grep -q "orientation: 0 inverted tets and 32 mirrored cells turned over" "$WORK/out" || { cat "$WORK/out"; fail "text summary"; }

expect_exit 2 "$TPK" convert "$vtu" "$WORK/strict.tpk" --strict-orientation
expect_stderr "internal.vtu: cell [0-9]* (a wedge) is mirrored"
expect_stderr "32 of 128 split cells are mirrored; without --strict-orientation they are turned over"
[ ! -e "$WORK/strict.tpk" ] || fail "output left behind"
echo "1 passed, 0 failed"
