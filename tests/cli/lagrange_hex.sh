#!/usr/bin/env bash
# Lagrange hexahedra of order 3 and 4 (VTK type 72), written by VTK itself (python3-paraview's VTK): the
# points are placed with VTK's own node numbering (vtkHigherOrderHexahedron.PointIndexFromIJK), so the
# reader's numbering is checked against an independent one. Two cells share a face under a curved map.
# Each is split whole: every node a vertex (no point unused), p^3 sub-hexahedra per cell, none mirrored,
# and the file checks clean (a wrong numbering folds sub-hexahedra over each other).
source "$(dirname "$0")/common.sh" "$@"

for order in 3 4; do
    cli_py - "$WORK/lagrange$order.vtu" "$order" <<'EOF' || fail "VTK could not write the Lagrange hexahedra"
import sys
import vtk_write
from vtkmodules.vtkCommonDataModel import vtkHigherOrderHexahedron, VTK_LAGRANGE_HEXAHEDRON
path, p = sys.argv[1], int(sys.argv[2])
g = vtk_write.Grid(2, lambda x: x[0] + 2 * x[1] + 3 * x[2])
def point(gi, j, k):  # one point per global lattice position: the shared face's points once
    r, s, t = gi / p, j / p, k / p
    x = (1.5 * r + 0.3 * s + 0.1 * t, 0.2 * r + 1.4 * s - 0.2 * t + 0.1 * r * r, 0.1 * r + 0.4 * s + 1.5 * t)
    return g.point((gi, j, k), x)
for cell in range(2):
    conn = [0] * (p + 1) ** 3
    for i in range(p + 1):
        for j in range(p + 1):
            for k in range(p + 1):
                conn[vtkHigherOrderHexahedron.PointIndexFromIJK(i, j, k, [p, p, p])] = point(cell * p + i, j, k)
    g.cell(VTK_LAGRANGE_HEXAHEDRON, conn)
g.write(path)
EOF
    convert_checked "$WORK/lagrange$order.vtu" "$WORK/lagrange$order.tpk" --json > "$WORK/l.json" 2> "$WORK/err"
    "$PY" - "$WORK/l.json" "$order" <<'EOF' || fail "order $order: $(cat "$WORK/l.json")"
import json, sys
d, p = json.load(open(sys.argv[1])), int(sys.argv[2])
points = (2 * p + 1) * (p + 1) ** 2
assert d["source_points"] == points and d["vertices"] == points, (d["source_points"], d["vertices"], points)
assert d["mirrored_cells"] == 0 and d["higher_order"] == {"mode": "split", "cells": 2, "added_points": 0}, d
s = d["cells_split"]
assert s["hexahedron_into_5"] + s["hexahedron_into_6"] == 2 * p ** 3, s
EOF
    ! grep -q "reduced" "$WORK/err" || fail "order $order: cells reduced to corners: $(cat "$WORK/err")"
    "$TPK" check "$WORK/lagrange$order.tpk" > "$WORK/check.txt" || fail "order $order: check: $(cat "$WORK/check.txt")"
done
echo "ok"
