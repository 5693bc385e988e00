#!/usr/bin/env bash
# Abaqus .inp files written by real tools. gmsh writes the boundary-layer mesh (tests/cli/sphere_bl.geo)
# as C3D4/C3D6/C3D8, and as C3D10/C3D15/C3D20 when second order: no cell may come out mirrored (the
# node-order map is right; gmsh's own .vtk of this mesh has every prism mirrored, tests/cli/folds.sh),
# the second-order file gives the same tets with --higher-order corners, and by default each cell split
# whole into 8 (tetra, wedges, hexahedra at their mid-edge nodes and added face and cell centres), none
# mirrored: the C3D10/C3D15/C3D20 node orders are right. meshio writes sfepy's meshes (C3D8RH with an *ELSET, C3D4):
# the same tets as converting the .mesh itself; read through an *INCLUDE from another folder too.
# gmsh's 27-node hexahedra (C3D27) give the same tets as gmsh's .msh of the same mesh.
source "$(dirname "$0")/common.sh" "$@"
command -v gmsh > /dev/null || fail "gmsh not installed (./dev deps installs it)"

summary() { # the --json fields the asserts below use, as one line
    "$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); s=d['cells_split']; print(d['tets'], d['mirrored_cells'], s['tetra'], s['wedge_into_3'], s['hexahedron_into_5']+s['hexahedron_into_6'], d['fields'])" "$1"
}

# The mesh has folded faces of its own (tests/cli/folds.sh): cut them to convert.
gmsh -3 -nt 1 "$SRC/tests/cli/sphere_bl.geo" -format inp -o "$WORK/bl.inp" > "$WORK/gmsh.log" 2>&1 ||
    { tail "$WORK/gmsh.log"; fail "gmsh failed"; }
gmsh -3 -nt 1 -order 2 -string "Mesh.SecondOrderIncomplete=1;" "$SRC/tests/cli/sphere_bl.geo" -format inp \
    -o "$WORK/bl2.inp" > "$WORK/gmsh.log" 2>&1 || { tail "$WORK/gmsh.log"; fail "gmsh failed (order 2)"; }
grep -q "type=C3D6," "$WORK/bl.inp" && grep -q "type=C3D20," "$WORK/bl2.inp" || fail "gmsh wrote other element types"
convert_checked "$WORK/bl.inp" "$WORK/bl.tpk" --cut-folds --field elset --json > "$WORK/bl.json" 2> "$WORK/err"
convert_checked "$WORK/bl2.inp" "$WORK/bl2.tpk" --cut-folds --field elset --higher-order corners --json \
    > "$WORK/bl2.json" 2> "$WORK/err"
convert_checked "$WORK/bl2.inp" "$WORK/bl2s.tpk" --cut-folds --field elset --json > "$WORK/bl2s.json" 2> "$WORK/err"
read -r tets mirrored tetra wedges hexes fields < <(summary "$WORK/bl.json")
[ "$mirrored" -eq 0 ] || fail "bl.inp: $mirrored cells mirrored: the C3D4/C3D6/C3D8 node order is wrong"
[ "$tetra" -gt 0 ] && [ "$wedges" -gt 0 ] && [ "$hexes" -gt 0 ] || fail "bl.inp: not every solid kind read"
[ "$fields" -eq 1 ] || fail "bl.inp: no elset field"
[ "$(summary "$WORK/bl2.json")" = "$tets 0 $tetra $wedges $hexes 1" ] ||
    fail "bl2.inp (second order) differs: $(summary "$WORK/bl2.json") vs $tets 0 $tetra $wedges $hexes 1"
[ "$(summary "$WORK/bl2s.json")" = "$((8 * tets)) 0 $((8 * tetra)) $((8 * wedges)) $((8 * hexes)) 1" ] ||
    fail "bl2.inp split whole: $(summary "$WORK/bl2s.json"), expected 8 x ($tets 0 $tetra $wedges $hexes 1)"
"$TPK" info "$WORK/bl2s.tpk" | grep -q '"higher_order":"split"' || fail "bl2s.tpk: META lacks higher_order split"
"$TPK" info "$WORK/bl2.tpk" | grep -q '"higher_order":"corners"' || fail "bl2.tpk: META lacks higher_order corners"
grep -q "dropped [0-9]* elements that are not solids" "$WORK/err" || fail "the surface elements were not counted"
# Gzipped: the same mesh, and the warning names the file read.
gzip -c "$WORK/bl.inp" > "$WORK/blz.inp.gz"
convert_checked "$WORK/blz.inp.gz" "$WORK/blz.tpk" --cut-folds --field elset --json > "$WORK/blz.json" 2> "$WORK/err"
[ "$(summary "$WORK/blz.json")" = "$(summary "$WORK/bl.json")" ] || fail "blz.inp.gz differs from bl.inp"
grep -q "warning: .*blz.inp.gz: dropped [0-9]* elements" "$WORK/err" || { cat "$WORK/err"; fail "the warning names no .gz"; }

# meshio: hexahedra with an element set, and tets; the same tets as the .mesh gives.
"$PY" - "$DATA/sfepy" "$WORK" <<'PYEOF'
import sys, meshio, numpy as np
src, work = sys.argv[1], sys.argv[2]
for name in ("cube_medium_hexa", "cube_medium_tetra"):
    m = meshio.read("%s/%s.mesh" % (src, name))
    cells = [(c.type, c.data) for c in m.cells if c.type in ("hexahedron", "tetra")]
    n = len(cells[0][1])
    meshio.Mesh(m.points, cells, cell_sets={"half": [np.arange(0, n, 2)]}).write("%s/%s.inp" % (work, name))
PYEOF
grep -q "TYPE=C3D8" "$WORK/cube_medium_hexa.inp" && grep -q "^\*ELSET" "$WORK/cube_medium_hexa.inp" ||
    fail "meshio wrote no C3D8 or *ELSET"
for name in cube_medium_hexa cube_medium_tetra; do
    convert_checked "$DATA/sfepy/$name.mesh" "$WORK/m.tpk" --json > "$WORK/m.json"
    convert_checked "$WORK/$name.inp" "$WORK/i.tpk" --field elset --json > "$WORK/i.json"
    "$PY" - "$WORK/m.json" "$WORK/i.json" "$name" <<'PYEOF' || fail "$name.inp"
import json, sys
m, i = (json.load(open(f)) for f in sys.argv[1:3])
assert i["mirrored_cells"] == 0 and m["mirrored_cells"] == 0, (sys.argv[3], m, i)
for k in ("source_cells", "tets", "vertices", "shell_faces", "cells_split"):
    assert i[k] == m[k], (sys.argv[3], k, m[k], i[k])
assert i["fields"] == 1, i
PYEOF
done

# *INCLUDE from a file in another folder, relative to the including file.
mkdir -p "$WORK/model/parts"
mv "$WORK/cube_medium_hexa.inp" "$WORK/model/parts/hexa.inp"
printf '*HEADING\n main file\n** the mesh\n*INCLUDE, INPUT=parts/hexa.inp\n' > "$WORK/model/main.inp"
convert_checked "$WORK/model/main.inp" "$WORK/inc.tpk" --json > "$WORK/inc.json"
convert_checked "$DATA/sfepy/cube_medium_hexa.mesh" "$WORK/m.tpk" --json > "$WORK/m.json"
"$PY" -c "import json; a,b=(json.load(open(f)) for f in ('$WORK/inc.json','$WORK/m.json')); assert a['source_cells']==1000 and a['tets']==b['tets'], (a,b)" ||
    fail "main.inp with *INCLUDE"
# A missing include names the including file and line.
printf '*NODE\n1, 0, 0, 0\n*INCLUDE, INPUT=nowhere.inp\n' > "$WORK/model/bad.inp"
expect_exit 2 "$TPK" convert "$WORK/model/bad.inp" "$WORK/bad.tpk"
expect_stderr "bad.inp:3: \*INCLUDE: .*nowhere.inp: cannot open"
# C3D27, as gmsh writes its 27-node hexahedra: a quarter annulus of hexahedra (curved faces) at order 2,
# written as .inp and as .msh. Kept whole (node 21 the centroid, 22-27 the face centres): the same tets
# as gmsh's .msh of it, to the bit; every node of a hexahedron a tet vertex; check --against the .inp finds every sampled
# point inside, and --max-error 0.001 refines the curved cells (their split alone is 0.7% of the diagonal
# off the map) and meets its bound.
cat > "$WORK/annulus.geo" <<'GEOEOF'
Point(1) = {1, 0, 0}; Point(2) = {2, 0, 0}; Point(3) = {0, 2, 0}; Point(4) = {0, 1, 0}; Point(5) = {0, 0, 0};
Line(1) = {1, 2}; Circle(2) = {2, 5, 3}; Line(3) = {3, 4}; Circle(4) = {4, 5, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 3} = 3; Transfinite Curve{2, 4} = 5; Transfinite Surface{1}; Recombine Surface{1};
Extrude {0, 0, 0.5} { Surface{1}; Layers{2}; Recombine; }
GEOEOF
for ext in inp msh; do
    gmsh -3 -nt 1 -order 2 "$WORK/annulus.geo" -format "$ext" -o "$WORK/a27.$ext" > "$WORK/gmsh.log" 2>&1 ||
        { tail "$WORK/gmsh.log"; fail "gmsh failed (annulus, $ext)"; }
    convert_checked "$WORK/a27.$ext" "$WORK/a27_$ext.tpk" --json > "$WORK/a27_$ext.json" 2> "$WORK/err"
    ! grep -q "C3D20" "$WORK/err" || fail "a27.$ext: $(cat "$WORK/err")"
done
grep -q "type=C3D27" "$WORK/a27.inp" || fail "gmsh wrote no C3D27"
"$PY" - "$WORK/a27_inp.json" <<'PYEOF' || fail "a27.inp not split whole"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["source_cells"] == 16 and d["tets"] == 16 * 48 and d["mirrored_cells"] == 0, d
assert d["higher_order"]["mode"] == "split" and d["higher_order"]["added_points"] == 0, d
PYEOF
"$TPK" check "$WORK/a27_inp.tpk" --json > "$WORK/check.json" || true
"$PY" - "$WORK/check.json" <<'PYEOF' || fail "a27.inp: some node is no tet's vertex"
import json, sys
f = [x for x in json.load(open(sys.argv[1]))["findings"] if x.get("name") == "unused_vertex" and x.get("count")]
# gmsh's 2 stray geometry points: the arcs' centre (0, 0) at both ends of the extrusion, in no hexahedron
assert not f or (f[0]["count"] == 2 and all(e["at"][:2] == [0, 0] for e in f[0]["examples"])), f
PYEOF
keys "$WORK/a27_inp.keys" "$WORK/a27_inp.tpk"
keys "$WORK/a27_msh.keys" "$WORK/a27_msh.tpk"
cmp -s "$WORK/a27_inp.keys" "$WORK/a27_msh.keys" ||
    fail "a27.inp gives other tets than gmsh's .msh of it: $(head -1 "$WORK/a27_inp.keys") vs $(head -1 "$WORK/a27_msh.keys")"
"$TPK" check "$WORK/a27_inp.tpk" --against "$WORK/a27.inp" --samples 8 --json > "$WORK/against.json" ||
    fail "check --against a27.inp: exit $?"
"$PY" -c "import json,sys; a=json.load(open(sys.argv[1])); assert a['outside']==0 and a['samples']>0, a" "$WORK/against.json" ||
    fail "a27.inp: samples outside the split file"
convert_checked "$WORK/a27.inp" "$WORK/a27_me.tpk" --max-error 0.001 --json > "$WORK/a27_me.json" 2> "$WORK/err" ||
    fail "--max-error 0.001: $(cat "$WORK/err")"
"$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); assert d['tets'] > 768, d['tets']" "$WORK/a27_me.json" ||
    fail "a27.inp --max-error 0.001: not refined"
"$TPK" check "$WORK/a27_me.tpk" --against "$WORK/a27.inp" --samples 8 > "$WORK/against.txt" 2>&1 ||
    fail "check --against a27.inp (--max-error 0.001): $(cat "$WORK/against.txt")"
grep -q "bound recorded in META: 0.001: met" "$WORK/against.txt" || fail "a27.inp --max-error 0.001: $(cat "$WORK/against.txt")"
# gmsh writes its 18-node prisms (order 2, complete) under TYPE=C3D6, 18 node ids each: refused at the
# first such element, by its line, not read as three elements' worth of wrong ones.
gmsh -3 -nt 1 -order 2 "$SRC/tests/cli/hexprism.geo" -format inp -o "$WORK/hp.inp" > "$WORK/gmsh.log" 2>&1 ||
    { tail "$WORK/gmsh.log"; fail "gmsh failed (hexprism)"; }
expect_exit 2 "$TPK" convert "$WORK/hp.inp" "$WORK/hp.tpk"
expect_stderr "hp.inp:[0-9]*: element [0-9]* (C3D6): expected 6 node ids, found 15 or more"
[ ! -e "$WORK/hp.tpk" ] || fail "hp.inp: a refused conversion left a file"
# A C3D27 with a face node left out (0: the manual's 21-node minimum is the C3D20's and the centroid) is
# read as its C3D20, and says so: a one-element unit cube with its 27 lattice nodes, node 27 left out.
"$PY" - "$WORK/c3d27.inp" <<'PYEOF'
import sys
c = [(0,0,0),(1,0,0),(1,1,0),(0,1,0),(0,0,1),(1,0,1),(1,1,1),(0,1,1)]
e = [(0,1),(1,2),(2,3),(3,0),(4,5),(5,6),(6,7),(7,4),(0,4),(1,5),(2,6),(3,7)]
p = c + [tuple((c[a][k] + c[b][k]) / 2 for k in range(3)) for a, b in e]
p += [(0.5,0.5,0.5),(0.5,0.5,0),(0.5,0.5,1),(0.5,0,0.5),(1,0.5,0.5),(0.5,1,0.5),(0,0.5,0.5)]
with open(sys.argv[1], "w") as f:
    f.write("*NODE\n" + "".join("%d, %g, %g, %g\n" % ((i + 1,) + q) for i, q in enumerate(p)))
    ids = [str(i + 1) for i in range(26)] + ["0"]
    f.write("*ELEMENT, TYPE=C3D27\n1, " + ", ".join(ids[:15]) + ",\n" + ", ".join(ids[15:]) + "\n")
PYEOF
convert_checked "$WORK/c3d27.inp" "$WORK/c3d27.tpk" --json > "$WORK/c3d27.json" 2> "$WORK/err"
grep -q "1 C3D27 elements with face nodes left out (0) read as C3D20" "$WORK/err" ||
    fail "c3d27.inp: no warning that the C3D27 is read as C3D20: $(cat "$WORK/err")"
echo "1 passed, 0 failed"
