#!/usr/bin/env bash
# VTK's biquadratic-quadratic hexahedron (type 33, 24 nodes) and triquadratic pyramid (37, 19 nodes), written
# by VTK itself (python3-paraview's VTK): node k sits where VTK's own cell puts it (GetParametricCoords), under
# a curved map, with a cubic field. Three hexahedra: A and B share an x face (its centre a node of both), A
# and C a z face (its centre a point neither has: made once). Two pyramids of a cube's centre share a side
# (its centre a node of both). Split whole: every node a vertex, the 8 points the hexahedra lack added at
# VTK's own map of them and valued by VTK's own interpolation (vtkCell.EvaluateLocation), no mirrored cell,
# check clean; --max-error 1% bounds the hexahedra (degree 5) and check --against agrees; the pyramids are
# refused with it.
source "$(dirname "$0")/common.sh" "$@"

cli_py - "$WORK" <<'EOF2' || fail "VTK could not write the cells"
import sys, json
import vtk_write
from vtkmodules.vtkCommonCore import mutable
from vtkmodules.vtkCommonDataModel import (vtkBiQuadraticQuadraticHexahedron, vtkTriQuadraticPyramid,
                                           VTK_BIQUADRATIC_QUADRATIC_HEXAHEDRON, VTK_TRIQUADRATIC_PYRAMID)
work = sys.argv[1]
def phi(X):
    x, y, z = X
    return (1.5 * x + 0.3 * y + 0.1 * z, 0.2 * x + 1.4 * y - 0.2 * z + 0.1 * x * x, 0.1 * x + 0.4 * y + 1.5 * z + 0.05 * y * y)
def field(x):
    return x[0] + 2 * x[1] - x[2] + 0.5 * x[0] * x[1] * x[2] + 0.3 * x[0] ** 3
def write(path, cls, vtk_type, cells, place):
    proto = cls()
    n = proto.GetNumberOfPoints()
    pc = proto.GetParametricCoords()
    ref = [tuple(pc[3 * k:3 * k + 3]) for k in range(n)]
    lo, hi = min(r[2] for r in ref), max(r[2] for r in ref)  # VTK 9.2 lists the pyramid's t in [0.5, 1]
    ref = [(r[0], r[1], (r[2] - lo) / (hi - lo)) for r in ref]
    g = vtk_write.Grid(len(cells), field)
    for c in range(len(cells)):
        conn = []
        for r in ref:
            X = place(cells[c], r)
            conn.append(g.point(tuple(round(v * 24) for v in X), phi(X)))
        g.cell(vtk_type, conn)
    return g.write(path), ref
# hexahedra: unit cubes at these corners, parametric (r, s, t) -> corner + (r, s, t)
hexes = [(0, 0, 0), (1, 0, 0), (0, 0, 1)]
grid, ref = write(work + "/hex24.vtu", vtkBiQuadraticQuadraticHexahedron, VTK_BIQUADRATIC_QUADRATIC_HEXAHEDRON,
                  hexes, lambda o, r: tuple(o[a] + r[a] for a in range(3)))
assert grid.GetNumberOfPoints() == 3 * 24 - 9 - 8, grid.GetNumberOfPoints()
# the points the split adds: the z faces' and the cells' centres, where VTK's cell maps them, with its value
added = {}
for c in range(3):
    cell = grid.GetCell(c)
    for r in ((0.5, 0.5, 0), (0.5, 0.5, 1), (0.5, 0.5, 0.5)):
        x, w = [0.0] * 3, [0.0] * 24
        cell.EvaluateLocation(mutable(0), r, x, w)
        value = sum(w[k] * grid.GetPointData().GetArray("f").GetValue(cell.GetPointId(k)) for k in range(24))
        added[tuple(round(v, 9) for v in x)] = (x, value)
assert len(added) == 8, len(added)
json.dump(list(added.values()), open(work + "/added.json", "w"))
# pyramids: two of the six a unit cube's centre makes, sharing the side (0,0,0) (1,0,0) centre; the reference
# pyramid (base [0,1]^2 at t = 0, apex (1/2, 1/2, 1)) mapped by x = P0 + r (P1 - P0) + s (P3 - P0) + t (apex - base centre)
pyramids = [((0, 0, 0), (1, 0, 0), (0, 1, 0)), ((0, 0, 0), (0, 0, 1), (1, 0, 0))]
def place_pyramid(P, r):
    P0, P1, P3 = P
    mid = tuple(P0[a] + 0.5 * (P1[a] - P0[a]) + 0.5 * (P3[a] - P0[a]) for a in range(3))
    return tuple(P0[a] + r[0] * (P1[a] - P0[a]) + r[1] * (P3[a] - P0[a]) + r[2] * (0.5 - mid[a]) for a in range(3))
grid, ref = write(work + "/pyramid19.vtu", vtkTriQuadraticPyramid, VTK_TRIQUADRATIC_PYRAMID, pyramids, place_pyramid)
assert grid.GetNumberOfPoints() == 2 * 19 - 7, grid.GetNumberOfPoints()
EOF2

for kind in hex24 pyramid19; do
    convert_checked "$WORK/$kind.vtu" "$WORK/$kind.tpk" --json > "$WORK/$kind.json" 2> "$WORK/err" ||
        fail "$kind: convert: $(cat "$WORK/err")"
    ! grep -q "reduced" "$WORK/err" || fail "$kind: cells reduced to corners: $(cat "$WORK/err")"
    "$TPK" check "$WORK/$kind.tpk" > "$WORK/check.txt" || fail "$kind: check: $(cat "$WORK/check.txt")"
    "$TPK" export "$WORK/$kind.tpk" --vtu "$WORK/${kind}_out.vtu" > /dev/null || fail "$kind: export"
done
"$PY" - "$WORK" <<'EOF2' || fail "split: $(cat "$WORK/hex24.json") $(cat "$WORK/pyramid19.json")"
import sys, json
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
work = sys.argv[1]
for kind, points, cells, added in (("hex24", 55, 3, 8), ("pyramid19", 31, 2, 0)):
    d = json.load(open("%s/%s.json" % (work, kind)))
    assert d["source_points"] == points and d["vertices"] == points + added, (kind, d["vertices"])
    assert d["mirrored_cells"] == 0, d
    assert d["higher_order"] == {"mode": "split", "cells": cells, "added_points": added}, d
# the added points: at VTK's map of the face and cell centres, with VTK's interpolated value
r = vtkXMLUnstructuredGridReader()
r.SetFileName(work + "/hex24_out.vtu")
r.Update()
g = r.GetOutput()
f = g.GetPointData().GetArray("f")
for x, value in json.load(open(work + "/added.json")):
    best = min(range(g.GetNumberOfPoints()), key=lambda v: sum((g.GetPoint(v)[a] - x[a]) ** 2 for a in range(3)))
    dist = sum((g.GetPoint(best)[a] - x[a]) ** 2 for a in range(3)) ** 0.5
    assert dist < 1e-6, ("no vertex at", x, dist)
    assert abs(f.GetValue(best) - value) < 1e-5 * (1 + abs(value)), ("value at", x, f.GetValue(best), value)
EOF2

# --max-error bounds the 24-node hexahedra (their functions have degree 5) and the file meets it
convert_checked "$WORK/hex24.vtu" "$WORK/bounded.tpk" --max-error 1% > /dev/null 2> "$WORK/err" ||
    fail "hex24 --max-error: $(cat "$WORK/err")"
"$TPK" check "$WORK/bounded.tpk" --against "$WORK/hex24.vtu" > "$WORK/against.txt" ||
    fail "hex24: check --against: $(cat "$WORK/against.txt")"
expect_exit 2 "$TPK" convert "$WORK/pyramid19.vtu" "$WORK/bad.tpk" --max-error 1%
expect_stderr "cell 0 is a triquadratic pyramid (VTK type 37"
[ ! -e "$WORK/bad.tpk" ] || fail "a refused conversion left $WORK/bad.tpk"
echo "ok"
