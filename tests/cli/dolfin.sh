#!/usr/bin/env bash
# Legacy DOLFIN XML: meshio writes sfepy's tet mesh as dolfin-xml (no "<?xml" line), which converts to
# the same tets as the .mesh itself; DOLFIN's own files (tests/cli/dolfin/README.md) convert with their
# domains as a cell field, hexahedra without a point added or a cell turned over (the vertex-order map);
# gzipped and misnamed files are told by content. Every output passes the 6xx checks.
source "$(dirname "$0")/common.sh" "$@"
FIX="$SRC/tests/cli/dolfin"

"$PY" -c "import meshio; m = meshio.read('$DATA/sfepy/cube_medium_tetra.mesh'); meshio.Mesh(m.points, [c for c in m.cells if c.type == 'tetra']).write('$WORK/t.xml', file_format='dolfin-xml')" 2> /dev/null
head -c 7 "$WORK/t.xml" | grep -q "<dolfin" || fail "meshio wrote no DOLFIN XML"
convert_checked "$DATA/sfepy/cube_medium_tetra.mesh" "$WORK/m.tpk" --json > "$WORK/m.json"
convert_checked "$WORK/t.xml" "$WORK/t.tpk" --json > "$WORK/t.json"
gzip -c "$WORK/t.xml" > "$WORK/t.xml.gz"
convert_checked "$WORK/t.xml.gz" "$WORK/g.tpk" --json > "$WORK/g.json"
cp "$WORK/t.xml" "$WORK/t.mesh_from_fenics" # no known extension: "<dolfin" tells
convert_checked "$WORK/t.mesh_from_fenics" "$WORK/n.tpk" --json > "$WORK/n.json"
"$PY" - "$WORK" <<'PYEOF' || fail "meshio's dolfin-xml gives another mesh"
import json, sys
m, t, g, n = (json.load(open("%s/%s.json" % (sys.argv[1], k))) for k in "mtgn")
for k in ("source_cells", "tets", "vertices", "shell_faces", "cells_split", "inverted_fixed", "mirrored_cells"):
    assert m[k] == t[k] == g[k] == n[k], (k, m[k], t[k], g[k], n[k])
PYEOF

convert_checked "$FIX/unit_cube_tets.xml" "$WORK/d.tpk" --field m --json > "$WORK/d.json"
convert_checked "$FIX/unit_cube_hexes.xml" "$WORK/h.tpk" --json > "$WORK/h.json"
"$PY" - "$WORK/d.json" "$WORK/h.json" <<'PYEOF' || fail "DOLFIN's files"
import json, sys
d, h = (json.load(open(f)) for f in sys.argv[1:3])
assert d["source_cells"] == 48 and d["tets"] == 48 and d["fields"] == 1 and d["inverted_fixed"] > 0, d
s = h["cells_split"]
assert h["source_cells"] == 8 and s["hexahedron_into_5"] + s["hexahedron_into_6"] == 8, h
assert h["steiner_cells"] == 0 and h["mirrored_cells"] == 0 and h["bad_cells_skipped"] == 0, h
PYEOF

# A .vtu named .xml still reads as VTU (the DOLFIN row's sniff looks for "<dolfin").
"$PY" -c "import meshio; meshio.read('$DATA/sfepy/cube_medium_hexa.mesh').write('$WORK/v.vtu')"
cp "$WORK/v.vtu" "$WORK/v.xml"
convert_checked "$WORK/v.xml" "$WORK/v.tpk" --json > "$WORK/v.json"
grep -q '"source_cells":1000' "$WORK/v.json" || fail "a VTU named .xml"
# Broken: the file and line, what was expected and what was found.
sed 's/v2="72"/v2="seventy-two"/' "$WORK/t.xml" > "$WORK/bad.xml"
expect_exit 2 "$TPK" convert "$WORK/bad.xml" "$WORK/x.tpk"
expect_stderr "bad.xml: line [0-9]*: <tetrahedron>: expected v2 to be an integer from 0 to 447, found 'seventy-two'"
echo "1 passed, 0 failed"
