#!/usr/bin/env bash
# Lagrange hexahedra of order 2, 3 and 4 (VTK type 72), written by VTK itself (python3-paraview's VTK): the
# points are placed with VTK's own node numbering (vtkHigherOrderHexahedron.PointIndexFromIJK), so the
# reader's numbering is checked against an independent one. Two cells share a face under a curved map.
# Each is split whole: every node a vertex (no point unused), p^3 sub-hexahedra per cell, none mirrored,
# and the file checks clean (a wrong numbering folds sub-hexahedra over each other). --max-error bounds
# orders 2, 3 and 4 (degree 6, 9 and 12; check --against agrees), and voxels; order 5 (degree 15) is
# refused by name.
source "$(dirname "$0")/common.sh" "$@"

cat > "$WORK/writer.py" <<'EOF'
import math, sys
import vtk_write
from vtkmodules.vtkCommonDataModel import vtkHigherOrderHexahedron, VTK_LAGRANGE_HEXAHEDRON
path, p = sys.argv[1], int(sys.argv[2])
g = vtk_write.Grid(2, lambda x: x[0] + 2 * x[1] + 3 * x[2] + math.sin(2 * x[0]) * math.cos(x[1]) + x[2] * x[2])
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
for order in 2 3 4; do
    cli_py - "$WORK/lagrange$order.vtu" "$order" < "$WORK/writer.py" || fail "VTK could not write the Lagrange hexahedra"
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
    # --max-error bounds them against their own map and interpolant (degree 3 p: 9 and 12): at 0.1% (order
    # 3) and 0.3% (order 4: a degree-12 bound costs about 1 ms a tet), check --against (sampling VTK's
    # cells through their own functions) finds the bound met and no more than it sampled, where the plain
    # split is off by more (0.017 and 0.0078)
    bound=0.001
    [ "$order" = 4 ] && bound=0.003
    bound_beats_plain "order $order" "$WORK/lagrange$order.vtu" "$WORK/lagrange$order.tpk" $bound
done
# voxels (VTK type 11: corners 2, 3 and 6, 7 swapped against a hexahedron's), two sharing a face: bounded
# as hexahedra, and check --against samples both through the same trilinear map (it skipped voxels, and
# Lagrange cells of order 2 above, and called an unsampled file's bound met)
cli_py - "$WORK/voxels.vtu" <<'EOF' || fail "VTK could not write the voxels"
import math, sys
import vtk_write
from vtkmodules.vtkCommonDataModel import VTK_VOXEL
g = vtk_write.Grid(2, lambda x: math.sin(3 * x[0]) * math.cos(2 * x[1]) + x[2] * x[2])
for c in range(2):
    g.cell(VTK_VOXEL, [g.point((c + i, j, k), (c + i, 0.8 * j, 1.2 * k)) for k in (0, 1) for j in (0, 1) for i in (0, 1)])
g.write(sys.argv[1])
EOF
convert_checked "$WORK/voxels.vtu" "$WORK/voxels.tpk" --max-error 0.001 2> "$WORK/err" ||
    fail "voxels: convert --max-error 0.001: $(cat "$WORK/err")"
"$TPK" check "$WORK/voxels.tpk" --against "$WORK/voxels.vtu" --samples 8 > "$WORK/against.txt" 2>&1 ||
    fail "voxels: check --against: $(cat "$WORK/against.txt")"
grep -q "1024 samples in 2 source cells" "$WORK/against.txt" && grep -q "bound recorded in META: 0.001: met" "$WORK/against.txt" ||
    fail "voxels: check --against did not sample both cells: $(cat "$WORK/against.txt")"
# order 5 (degree 15, over the Bernstein tables' 12): refused with --max-error by name, nothing written
cli_py - "$WORK/lagrange5.vtu" 5 < "$WORK/writer.py" || fail "VTK could not write the Lagrange hexahedra"
expect_exit 2 "$TPK" convert "$WORK/lagrange5.vtu" "$WORK/bad.tpk" --max-error 1%
expect_stderr "cell 0 is a Lagrange hexahedron (VTK type 72"
[ ! -e "$WORK/bad.tpk" ] || fail "order 5: a refused conversion left $WORK/bad.tpk"
echo "ok"
