# Folds (issue 9): a real gmsh boundary-layer mesh (tests/cli/sphere_bl.geo: tets, prisms, hexahedra and
# pyramids) has tets on the same side of faces they share. convert refuses them by name, or cuts them
# with --cut-folds into a file that passes every 6xx check; its prisms come in the mirrored node order
# and are turned over by default. Needs Debian's gmsh; exits 77 (skipped) without it.
source "$(dirname "$0")/common.sh"
command -v gmsh > /dev/null || skip "gmsh not installed"

# One thread: gmsh's output is then reproducible.
gmsh -3 -nt 1 "$SRC/tests/cli/sphere_bl.geo" -format vtk -o "$WORK/bl.vtk" > "$WORK/gmsh.log" 2>&1 ||
    { tail "$WORK/gmsh.log"; fail "gmsh failed"; }

# The validator finds the folds in the source (305, exact, in float64) ...
"$TPK" check "$WORK/bl.vtk" --json --no-self-intersections --no-progress > "$WORK/src.json" || true
source_folds=$("$PY" -c "import json; print([f['count'] for f in json.load(open('$WORK/src.json'))['findings'] if f['id']==305][0])")
[ "$source_folds" -gt 0 ] || fail "the boundary-layer mesh has no folds any more: the test needs one"

# ... convert refuses them by name: count, the first face with its cells and points, and the option ...
expect_exit 2 "$TPK" convert "$WORK/bl.vtk" "$WORK/bl.tpk"
expect_stderr "bl.vtk: $source_folds folded faces (tets on the same side of a face they share"
expect_stderr "the first: the face of points [0-9]* (.*) is shared by cell [0-9]* (tet [0-9]*, fourth point"
expect_stderr "both fourth points on the same side of it; --cut-folds cuts the adjacency there"
[ ! -e "$WORK/bl.tpk" ] || fail "output left behind"

# ... and cuts them with --cut-folds: counted in the summary, --json and META; the file passes 6xx.
convert_checked "$WORK/bl.vtk" "$WORK/bl.tpk" --cut-folds --json > "$WORK/bl.json"
"$PY" - "$WORK/bl.json" "$source_folds" <<'PYEOF' || fail "summary"
import json, sys
d = json.load(open(sys.argv[1]))
split = d["cells_split"]
assert d["folds_cut"] == int(sys.argv[2]) and d["repairs"]["cut_folds"] == {"requested": True, "folded_faces": d["folds_cut"]}, d
assert split["tetra"] > 0 and split["pyramid_into_2"] > 0 and split["wedge_into_3"] > 0 and split["hexahedron_into_6"] + split["hexahedron_into_5"] > 0, split
assert d["mirrored_cells"] == split["wedge_into_3"] and d["repairs"]["reorient"]["mirrored_cells"] == d["mirrored_cells"], d
PYEOF
"$TPK" info "$WORK/bl.tpk" --json > "$WORK/info.json"
"$PY" -c "import json; r=json.load(open('$WORK/info.json'))['metadata']['repairs']; assert r['cut_folds']=={'requested':True,'folded_faces':$source_folds}, r"
convert_checked "$WORK/bl.vtk" "$WORK/bl.tpk" --cut-folds > "$WORK/out"
grep -q "repair --cut-folds: $source_folds folded faces cut" "$WORK/out" || { cat "$WORK/out"; fail "text summary"; }
# Both overlapping cells are rendered: the marcher leaves through a cut face and enters again.
"$TPK" render "$WORK/bl.tpk" -o "$WORK/bl.png" --size 64x64 > /dev/null || fail "render of a file with cut folds"

# A finer mesh (170k tets: the fold search runs on two workers): the same file whatever the thread count.
gmsh -3 -nt 1 -clscale 0.45 "$SRC/tests/cli/sphere_bl.geo" -format vtk -o "$WORK/fine.vtk" > "$WORK/gmsh.log" 2>&1 ||
    { tail "$WORK/gmsh.log"; fail "gmsh failed (fine mesh)"; }
convert_checked "$WORK/fine.vtk" "$WORK/f1.tpk" --cut-folds --threads 1 --quiet
convert_checked "$WORK/fine.vtk" "$WORK/f2.tpk" --cut-folds --threads 2 --quiet
cmp "$WORK/f1.tpk" "$WORK/f2.tpk" || fail "cut folds depend on the thread count"

# --strict-orientation refuses the mirrored prisms before any fold is looked at.
expect_exit 2 "$TPK" convert "$WORK/bl.vtk" "$WORK/bl.tpk" --cut-folds --strict-orientation
expect_stderr "(a wedge) is mirrored"
echo "1 passed, 0 failed"
