# tetpack convert repairs (issues 4 and 9): orientation is a labeling, turned over by default and counted
# (--strict-orientation refuses it; --reorient is still accepted); folds are refused by name or cut with
# --cut-folds; --drop-degenerate and --merge-duplicates[=TOL] fix, print what they did in the summary, and
# record it in META's "repairs". Every file written passes the 6xx checks (convert_checked, common.sh).
source "$(dirname "$0")/common.sh"

repairs() { # repairs FILE.tpk PYTHON-EXPRESSION-ON-r: check META's repairs object through tetpack info
    "$TPK" info "$1" --json > "$WORK/info.json"
    "$PY" -c "import json,sys; r=json.load(open('$WORK/info.json'))['metadata']['repairs']; assert $2, r"
}

# Inverted tets: turned over and counted by default (and with the old --reorient); with
# --strict-orientation exit 2 naming a cell, its points and the count.
expect_exit 2 "$TPK" convert "$DATA/hard/inverted_tets.vtk" "$WORK/i.tpk" --strict-orientation
expect_stderr "inverted_tets.vtk: cell [0-9]* is inverted (negative volume): points [0-9]* ("
expect_stderr "135 of 1348 tets are inverted; without --strict-orientation they are turned over"
[ ! -e "$WORK/i.tpk" ] || fail "output left behind"
for old in "" --reorient; do
    convert_checked "$DATA/hard/inverted_tets.vtk" "$WORK/i.tpk" $old > "$WORK/out"
    grep -q "orientation: 135 inverted tets and 0 mirrored cells turned over" "$WORK/out" || { cat "$WORK/out"; fail "summary"; }
    repairs "$WORK/i.tpk" "r['reorient']=={'requested':True,'inverted_tets':135,'mirrored_cells':0} and not r['merge_duplicates']['requested']"
done

# A mirrored hexahedron (sfepy's slab lists 97 of its 603 hexahedra in the mirrored order): turned over.
convert_checked "$DATA/sfepy/matrix_fiber_rand.vtk" "$WORK/m.tpk" --json > "$WORK/m.json"
"$PY" -c "import json; d=json.load(open('$WORK/m.json')); assert d['mirrored_cells']==97 and d['repairs']['reorient']['mirrored_cells']==97, d"
expect_exit 2 "$TPK" convert "$DATA/sfepy/matrix_fiber_rand.vtk" "$WORK/m.tpk" --strict-orientation
expect_stderr "97 of 603 split cells are mirrored; without --strict-orientation they are turned over"

# Degenerate tets: dropped and counted. 10 slivers are inverted in float32 and would fold against a
# neighbour turned over (the old --reorient wrote those folds): bad cells, left out with --skip-bad-cells.
expect_exit 2 "$TPK" convert "$DATA/hard/degenerate_tets.vtk" "$WORK/d.tpk" --reorient
expect_stderr "has a repeated vertex: points"
expect_exit 2 "$TPK" convert "$DATA/hard/degenerate_tets.vtk" "$WORK/d.tpk" --drop-degenerate --reorient
expect_stderr "turning it over would fold it against its neighbour: the face of points"
expect_stderr "10 inverted tets are such bad cells"
convert_checked "$DATA/hard/degenerate_tets.vtk" "$WORK/d.tpk" --drop-degenerate --skip-bad-cells > "$WORK/out"
grep -q "repair --drop-degenerate: 20 zero-volume tets and 0 cells collapsed by merging dropped" "$WORK/out" || { cat "$WORK/out"; fail "summary"; }
grep -q "10 bad cells skipped" "$WORK/out" || { cat "$WORK/out"; fail "summary lacks the bad cells"; }
repairs "$WORK/d.tpk" "r['drop_degenerate']=={'requested':True,'degenerate_tets':20,'collapsed_cells':0} and r['reorient']['inverted_tets']==0"

# A clean file: the summary says no repair was asked for, META says none was made.
convert_checked "$DATA/sfepy/cylinder.vtk" "$WORK/c.tpk" > "$WORK/out"
grep -q "repairs: none asked for" "$WORK/out" || { cat "$WORK/out"; fail "summary"; }
repairs "$WORK/c.tpk" "r['reorient']['requested'] and r['reorient']['inverted_tets']==0 and r['cut_folds']=={'requested':False,'folded_faces':0}"
shell=$("$PY" -c "import json; print(json.load(open('$WORK/info.json'))['shell_faces'])")

# Duplicate points: sfepy's cylinder with each tet given its own 4 points (exact copies), and again with
# every copy moved by up to 5e-9 m per axis (the diagonal is 0.115 m).
"$PY" - "$DATA/sfepy/cylinder.vtk" "$WORK" <<'EOF'
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
tets = m.cells_dict["tetra"]
pts = m.points[tets.reshape(-1)]
conn = np.arange(len(pts)).reshape(-1, 4)
meshio.write(sys.argv[2] + "/split.vtk", meshio.Mesh(pts, [("tetra", conn)]), binary=False)
rng = np.random.default_rng(7)
near = pts + rng.uniform(-5e-9, 5e-9, pts.shape)
meshio.write(sys.argv[2] + "/near.vtk", meshio.Mesh(near, [("tetra", conn)]), binary=False)
EOF
convert_checked "$WORK/split.vtk" "$WORK/s.tpk" --json > "$WORK/s.json"
"$PY" -c "import json; d=json.load(open('$WORK/s.json')); assert d['shell_faces']==4*1348 and d['merged_vertices']==0, d"
convert_checked "$WORK/split.vtk" "$WORK/s.tpk" --merge-duplicates > "$WORK/out"
grep -q "repair --merge-duplicates: $((4 * 1348 - 354)) points merged into a twin with equal coordinates" "$WORK/out" || { cat "$WORK/out"; fail "summary"; }
repairs "$WORK/s.tpk" "r['merge_duplicates']=={'requested':True,'tolerance':0,'merged_vertices':4*1348-354}"
"$PY" -c "import json; d=json.load(open('$WORK/info.json')); assert d['shell_faces']==$shell and d['vertices']==354, d"

convert_checked "$WORK/near.vtk" "$WORK/n.tpk" --merge-duplicates --json > "$WORK/n.json"
"$PY" -c "import json; d=json.load(open('$WORK/n.json')); assert d['merged_vertices']==0 and d['shell_faces']==4*1348, d"
convert_checked "$WORK/near.vtk" "$WORK/n.tpk" --merge-duplicates=1e-6 --json > "$WORK/n.json"
"$PY" -c "import json; d=json.load(open('$WORK/n.json')); assert d['merged_vertices']==4*1348-354 and d['shell_faces']==$shell, d"
repairs "$WORK/n.tpk" "r['merge_duplicates']=={'requested':True,'tolerance':1e-6,'merged_vertices':4*1348-354}"
# A tolerance that merges distinct points collapses cells: refused by name, or dropped and counted.
expect_exit 2 "$TPK" convert "$WORK/near.vtk" "$WORK/n.tpk" --merge-duplicates=0.05
expect_stderr "collapses when duplicate points are merged: its points"
expect_stderr "pass --drop-degenerate to remove them"

# Usage errors.
expect_exit 2 "$TPK" convert "$WORK/split.vtk" "$WORK/x.tpk" --merge-duplicates=abc
expect_stderr "--merge-duplicates=TOL expects 1e-15 <= TOL <= 1"
expect_exit 2 "$TPK" convert "$WORK/split.vtk" "$WORK/x.tpk" --merge-duplicates=2
expect_exit 2 "$TPK" convert "$WORK/split.vtk" "$WORK/x.tpk" --merge-duplicates=1e-16
expect_exit 2 "$TPK" convert "$WORK/split.vtk" "$WORK/x.tpk" --merge-duplicates=
expect_exit 2 "$TPK" convert "$WORK/split.vtk" "$WORK/x.tpk" --merge-duplicatesX
# (Into a file first: grep -q stops reading at the first match, and pipefail would see the writer's SIGPIPE.)
"$TPK" convert --help > "$WORK/help"
grep -q -- "--merge-duplicates\[=TOL\]" "$WORK/help" || fail "help lacks --merge-duplicates"
grep -q -- "--reorient .*accepted for old command lines" "$WORK/help" || fail "help lacks --reorient"
grep -q -- "--strict-orientation" "$WORK/help" || fail "help lacks --strict-orientation"
grep -q -- "--cut-folds" "$WORK/help" || fail "help lacks --cut-folds"
echo "1 passed, 0 failed"
