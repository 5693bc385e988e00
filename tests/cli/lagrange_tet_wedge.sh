#!/usr/bin/env bash
# Lagrange tetra (VTK type 71) and wedges (73) of order 3 and 4, written by VTK itself (python3-paraview's
# VTK): each node is placed where VTK's own cell says it sits (vtkLagrangeTetra/vtkLagrangeWedge
# GetParametricCoords), so the reader's numbering is checked against an independent one. Two cells of each
# kind share a face under a curved map (a tetra pair across a triangle, a wedge pair across a quad). Each is
# split whole: every node a vertex (no point added or unused), p^3 tetra per tetra and p^3 wedges (3 tets
# each) per wedge, none mirrored, the field at every vertex its node's value, and the file checks clean (a
# wrong numbering folds pieces over each other).
source "$(dirname "$0")/common.sh" "$@"

for kind in tetra wedge; do
    for order in 3 4; do
        "$PY" - "$WORK/$kind$order.vtu" "$kind" "$order" <<'EOF2' || fail "VTK could not write the Lagrange ${kind}s"
import sys
from vtkmodules.vtkCommonCore import vtkPoints, vtkDoubleArray
from vtkmodules.vtkCommonDataModel import (vtkUnstructuredGrid, vtkLagrangeTetra, vtkLagrangeWedge,
                                           VTK_LAGRANGE_TETRAHEDRON, VTK_LAGRANGE_WEDGE)
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter
path, kind, p = sys.argv[1], sys.argv[2], int(sys.argv[3])
if kind == "tetra":
    n, vtk_type, cell = (p + 1) * (p + 2) * (p + 3) // 6, VTK_LAGRANGE_TETRAHEDRON, vtkLagrangeTetra()
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
grid, points, field, ids = vtkUnstructuredGrid(), vtkPoints(), vtkDoubleArray(), {}
field.SetName("f")
def point(X):  # one point per position on the lattice (multiples of 1/p): the shared face's points once
    key = tuple(round(v * p) for v in X)
    if key not in ids:
        x, y, z = X
        x = (1.5 * x + 0.3 * y + 0.1 * z, 0.2 * x + 1.4 * y - 0.2 * z + 0.1 * x * x, 0.1 * x + 0.4 * y + 1.5 * z)
        ids[key] = points.InsertNextPoint(*x)
        field.InsertNextValue(x[0] + 2 * x[1] + 3 * x[2] + x[0] * x[1])
    return ids[key]
grid.Allocate(2)
for c in range(2):
    conn = [point(place(c, pc[3 * k], pc[3 * k + 1], pc[3 * k + 2])) for k in range(n)]
    grid.InsertNextCell(vtk_type, n, conn)
shared = (p + 1) * (p + 2) // 2 if kind == "tetra" else (p + 1) ** 2
assert points.GetNumberOfPoints() == 2 * n - shared, (points.GetNumberOfPoints(), 2 * n - shared)
grid.SetPoints(points)
grid.GetPointData().AddArray(field)
w = vtkXMLUnstructuredGridWriter()
w.SetFileName(path)
w.SetInputData(grid)
w.SetDataModeToAscii()
assert w.Write() == 1
EOF2
        convert_checked "$WORK/$kind$order.vtu" "$WORK/$kind$order.tpk" --json > "$WORK/l.json" 2> "$WORK/err" ||
            fail "$kind order $order: convert: $(cat "$WORK/err")"
        "$PY" - "$WORK/l.json" "$kind" "$order" <<'EOF2' || fail "$kind order $order: $(cat "$WORK/l.json")"
import json, sys
d, kind, p = json.load(open(sys.argv[1])), sys.argv[2], int(sys.argv[3])
n = (p + 1) * (p + 2) * (p + 3) // 6 if kind == "tetra" else (p + 1) ** 2 * (p + 2) // 2
points = 2 * n - ((p + 1) * (p + 2) // 2 if kind == "tetra" else (p + 1) ** 2)
assert d["source_points"] == points and d["vertices"] == points, (d["source_points"], d["vertices"], points)
assert d["mirrored_cells"] == 0 and d["higher_order"] == {"mode": "split", "cells": 2, "added_points": 0}, d
assert d["tets"] == 2 * p ** 3 * (1 if kind == "tetra" else 3), (d["tets"], p)
EOF2
        ! grep -q "reduced" "$WORK/err" || fail "$kind order $order: cells reduced to corners: $(cat "$WORK/err")"
        "$TPK" check "$WORK/$kind$order.tpk" > "$WORK/check.txt" || fail "$kind order $order: check: $(cat "$WORK/check.txt")"
    done
done
echo "ok"
