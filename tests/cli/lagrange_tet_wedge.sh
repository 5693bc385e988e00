#!/usr/bin/env bash
# Lagrange tetra (VTK type 71) of order 3, 4, 7 and 10 and wedges (73) of order 3, 4, 5 and 7, and the 15-node
# Lagrange tetra (order 2 with face and body centres), written by VTK itself (python3-paraview's VTK): each
# node is placed where VTK's own cell says it sits (vtkLagrangeTetra/vtkLagrangeWedge
# GetParametricCoords), so the reader's numbering is checked against an independent one. Two cells of each
# kind share a face under a curved map (a tetra pair across a triangle, a wedge pair across a quad). Each is
# split whole: every node a vertex (no point added or unused), p^3 tetra per tetra (20 per 15-node one)
# and p^3 wedges (3 tets each) per wedge, none mirrored, the field at every vertex its node's value, and
# the file checks clean (a wrong numbering folds pieces over each other). --max-error bounds the tetra of
# order 3, 4, 7 and 10 and the wedges of order 3, 4 and 5 (degree 10 for the order-5 wedge; check --against
# agrees); the order-7 wedge (degree 14, over the Bernstein tables' 12) and the 15-node tetra are refused
# with it by name.
source "$(dirname "$0")/common.sh" "$@"

for case in tetra:3 tetra:4 tetra:7 tetra:10 wedge:3 wedge:4 wedge:5 wedge:7 tetra15:2; do
    kind=${case%:*} order=${case#*:}
    cli_py - "$WORK/$kind$order.vtu" "$kind" "$order" <<'EOF2' || fail "VTK could not write the Lagrange ${kind}s"
import sys
import vtk_write
from vtkmodules.vtkCommonDataModel import (vtkLagrangeTetra, vtkLagrangeWedge, VTK_LAGRANGE_TETRAHEDRON,
                                           VTK_LAGRANGE_WEDGE)
path, kind, p = sys.argv[1], sys.argv[2], int(sys.argv[3])
if kind.startswith("tetra"):
    n, vtk_type, cell = (p + 1) * (p + 2) * (p + 3) // 6, VTK_LAGRANGE_TETRAHEDRON, vtkLagrangeTetra()
    n = 15 if kind == "tetra15" else n
    # two tetra sharing the face (1,0,0) (0,1,0) (0,0,1); x = P0 + r (P1 - P0) + s (P2 - P0) + t (P3 - P0)
    cells = [((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)), ((1, 1, 1), (0, 1, 0), (1, 0, 0), (0, 0, 1))]
    def place(c, r, s, t):
        P = cells[c]
        return tuple(P[0][a] + r * (P[1][a] - P[0][a]) + s * (P[2][a] - P[0][a]) + t * (P[3][a] - P[0][a]) for a in range(3))
else:
    n, vtk_type, cell = (p + 1) ** 2 * (p + 2) // 2, VTK_LAGRANGE_WEDGE, vtkLagrangeWedge()
    # two wedges sharing the quad over the edge (1,0)-(0,1): triangle map in (r, s), height t
    cells = [((0, 0), (1, 0), (0, 1)), ((1, 1), (0, 1), (1, 0))]
    def place(c, r, s, t):
        P = cells[c]
        return tuple(P[0][a] + r * (P[1][a] - P[0][a]) + s * (P[2][a] - P[0][a]) for a in range(2)) + (t,)
cell.GetPointIds().SetNumberOfIds(n)
cell.GetPoints().SetNumberOfPoints(n)
if kind == "wedge":
    cell.SetOrder(p, p, p, n)
cell.Initialize()
pc = cell.GetParametricCoords()
g = vtk_write.Grid(2, lambda x: x[0] + 2 * x[1] + 3 * x[2] + x[0] * x[1])
def point(X):  # one point per position (multiples of 1/p, p <= 10): the shared face's points once
    x, y, z = X
    x = (1.5 * x + 0.3 * y + 0.1 * z, 0.2 * x + 1.4 * y - 0.2 * z + 0.1 * x * x, 0.1 * x + 0.4 * y + 1.5 * z)
    return g.point(tuple(round(v * 5040) for v in X), x)
for c in range(2):
    g.cell(vtk_type, [point(place(c, pc[3 * k], pc[3 * k + 1], pc[3 * k + 2])) for k in range(n)])
shared = {"tetra": (p + 1) * (p + 2) // 2, "tetra15": 7, "wedge": (p + 1) ** 2}[kind]
assert g.points.GetNumberOfPoints() == 2 * n - shared, (g.points.GetNumberOfPoints(), 2 * n - shared)
g.write(path)
EOF2
    convert_checked "$WORK/$kind$order.vtu" "$WORK/$kind$order.tpk" --json > "$WORK/l.json" 2> "$WORK/err" ||
        fail "$kind order $order: convert: $(cat "$WORK/err")"
    "$PY" - "$WORK/l.json" "$kind" "$order" <<'EOF2' || fail "$kind order $order: $(cat "$WORK/l.json")"
import json, sys
d, kind, p = json.load(open(sys.argv[1])), sys.argv[2], int(sys.argv[3])
n = {"tetra": (p + 1) * (p + 2) * (p + 3) // 6, "tetra15": 15, "wedge": (p + 1) ** 2 * (p + 2) // 2}[kind]
points = 2 * n - {"tetra": (p + 1) * (p + 2) // 2, "tetra15": 7, "wedge": (p + 1) ** 2}[kind]
assert d["source_points"] == points and d["vertices"] == points, (d["source_points"], d["vertices"], points)
assert d["mirrored_cells"] == 0 and d["higher_order"] == {"mode": "split", "cells": 2, "added_points": 0}, d
assert d["tets"] == 2 * {"tetra": p ** 3, "tetra15": 20, "wedge": 3 * p ** 3}[kind], (d["tets"], p)
EOF2
    ! grep -q "reduced" "$WORK/err" || fail "$kind order $order: cells reduced to corners: $(cat "$WORK/err")"
    "$TPK" check "$WORK/$kind$order.tpk" > "$WORK/check.txt" || fail "$kind order $order: check: $(cat "$WORK/check.txt")"
    if [ "$kind" = tetra ] || { [ "$kind" = wedge ] && [ "$order" -le 6 ]; }; then
        # the Lagrange tetra of order 3-10 and wedges of order 3-6 are bounded against their own map and
        # interpolant (degree p, 2p): at 0.1%, check --against (sampling VTK's cells through their own
        # functions) finds the bound met and at most 0.001 sampled, where the plain split is off by more
        # (tetra 0.0050 and 0.0016, wedge 0.0025 and 0.0015). The order-7 and -10 tetra's and the
        # order-5 wedge's plain splits are within 0.001 (0.00093, 0.00043, 0.00082): tighter bounds there,
        # met at 0.00015, 0.00019 and 0.00039 sampled (order 10: 2000 tets refined into 4326 in 1.7 s).
        bound=0.001
        case $kind$order in tetra7) bound=0.0003 ;; tetra10) bound=0.00035 ;; wedge5) bound=0.0006 ;; esac
        bound_beats_plain "$kind order $order" "$WORK/$kind$order.vtu" "$WORK/$kind$order.tpk" $bound
        continue
    fi
    # --max-error has no bound for these cells' functions yet: refused by name, nothing written
    expect_exit 2 "$TPK" convert "$WORK/$kind$order.vtu" "$WORK/bad.tpk" --max-error 1%
    expect_stderr "cell 0 is a Lagrange ${kind%15} (VTK type 7"
    [ ! -e "$WORK/bad.tpk" ] || fail "$kind order $order: a refused conversion left $WORK/bad.tpk"
done
echo "ok"
