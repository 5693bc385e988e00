#!/usr/bin/env bash
# Polyhedra written by an independent writer: meshio 5 turns sfepy's 1000 hexahedra into polyhedra (six
# quads each) in a zlib-compressed binary VTU; tetpack reads and converts it to the same vertices and
# boundary as the hexahedra themselves (no inner faces: the polyhedra cut shared quads alike), 6 tets
# per polyhedron (a cone from its smallest vertex), no point added.
source "$(dirname "$0")/common.sh" "$@"
"$PY" - "$DATA/sfepy/cube_medium_hexa.mesh" "$WORK/poly.vtu" <<'PYEOF'
import sys
import meshio, numpy as np
src = meshio.read(sys.argv[1])
hexes = np.concatenate([c.data for c in src.cells if c.type == "hexahedron"])
quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
cells = [[h[list(q)] for q in quads] for h in hexes]
meshio.Mesh(src.points, [("polyhedron8", cells)]).write(sys.argv[2])
PYEOF
convert_checked "$DATA/sfepy/cube_medium_hexa.mesh" "$WORK/h.tpk" --json > "$WORK/h.json"
convert_checked "$WORK/poly.vtu" "$WORK/p.tpk" --json > "$WORK/p.json"
"$PY" - "$WORK/h.json" "$WORK/p.json" <<'PYEOF'
import json, sys
h, p = (json.load(open(f)) for f in sys.argv[1:3])
assert p["source_cells"] == 1000 and p["tets"] == 6000 and p["steiner_cells"] == 0, p
assert p["vertices"] == h["vertices"] and p["shell_faces"] == h["shell_faces"], (h, p)
PYEOF
echo "1 passed, 0 failed"
