#!/usr/bin/env bash
# XDMF written by real tools: meshio (HDF5 and XML data, Mixed topologies, a TimeSeries with xi:include)
# from real meshes of ../shared/data and a Gmsh mesh with pyramids. tetpack takes XDMF's node order for
# tetrahedra, pyramids, wedges and hexahedra to be VTK's. meshio writes XDMF connectivity as it holds it
# (no permutation), so a mapping error shows as mirrored cells: every file must convert with
# "mirrored_cells": 0 and split exactly as the source file does through tetpack's own Gmsh and Medit
# readers (node orders checked on their own). Where VTK's XDMF reader (vtkXdmf3Reader) is installed, it
# must also return the connectivity meshio wrote, unpermuted. (meshio's .vtu is no reference: meshio 5
# writes wedges into VTU as [0,2,1,3,5,4], which VTK's own wedge volume finds negative.)
source "$(dirname "$0")/common.sh" "$@"
command -v gmsh >/dev/null || skip "gmsh not installed"
cat > "$WORK/pyr.geo" <<'GEO'
// A box of tets whose two recombined (quad) faces Gmsh joins to the tets with pyramids.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Mesh.MeshSizeMax = 0.3;
Recombine Surface{1, 2};
GEO
gmsh -3 "$WORK/pyr.geo" -format msh41 -o "$WORK/pyr.msh" -v 1 >/dev/null
"$PY" - "$DATA" "$WORK" <<'PYEOF'
import os, sys
import meshio, numpy as np
data, work = sys.argv[1:3]
def volume_blocks(m, keep=("tetra", "pyramid", "wedge", "hexahedron")):
    return [c for c in m.cells if c.type in keep]
def with_fields(points, blocks, extra=()):
    # u: a point field linear in x, y, z; id: a cell field numbering the cells in file order.
    cells = [(c.type, c.data) for c in blocks] + list(extra)
    n = 0
    ids = []
    for _, d in cells:
        ids.append(np.arange(n, n + len(d), dtype=float))
        n += len(d)
    u = points[:, 0] + 2 * points[:, 1] + 3 * points[:, 2]
    return meshio.Mesh(points, cells, point_data={"u": u}, cell_data={"id": ids})
tet = meshio.read(data + "/sfepy/cube_medium_tetra.mesh")
hexa = meshio.read(data + "/sfepy/cube_medium_hexa.mesh")
t3 = meshio.read(data + "/gmsh/t3_hex_prism_ascii41.msh")
pyr = meshio.read(work + "/pyr.msh")
cases = {
    "tet": with_fields(tet.points, volume_blocks(tet)),
    "hex": with_fields(hexa.points, volume_blocks(hexa)),
    "wedge": with_fields(t3.points, volume_blocks(t3, ("wedge",))),
    # Mixed: tets and wedges, with Gmsh's surface triangles and quads (dropped by tetpack).
    "mixed": with_fields(t3.points, volume_blocks(t3) + [c for c in t3.cells if c.type in ("triangle", "quad")]),
    "pyr": with_fields(pyr.points, volume_blocks(pyr)),
}
for name, m in cases.items():
    meshio.write("%s/%s.xdmf" % (work, name), m)               # HDF5 data
meshio.write(work + "/hex_xml.xdmf", cases["hex"], data_format="XML")
# A time series as FEniCS users write it: the mesh once, each step's fields xi:include it. (The writer
# puts its .h5 in the current directory.)
m = cases["tet"]
os.chdir(work)
with meshio.xdmf.TimeSeriesWriter("series.xdmf") as w:
    w.write_points_cells(m.points, m.cells)
    for t in (0.0, 0.5, 2.0):
        w.write_data(t, point_data={"u": m.point_data["u"] * (1 + t)}, cell_data={"id": [d + t for d in m.cell_data["id"]]})
PYEOF
# VTK, where its XDMF reader is installed, reads meshio's XDMF with the node order meshio wrote.
"$PY" - "$WORK" <<'PYEOF'
import sys
import meshio, numpy as np
import vtk
work = sys.argv[1]
if not hasattr(vtk, "vtkXdmf3Reader"):
    print("VTK %s has no vtkXdmf3Reader: that cross-check is skipped" % vtk.vtkVersion.GetVTKVersion())
    sys.exit(0)
from vtk.util.numpy_support import vtk_to_numpy
vtk_types = {"tetra": 10, "pyramid": 14, "wedge": 13, "hexahedron": 12, "triangle": 5, "quad": 9}
for name in ("tet", "hex", "wedge", "mixed", "pyr"):
    reader = vtk.vtkXdmf3Reader()
    reader.SetFileName("%s/%s.xdmf" % (work, name))
    reader.Update()
    grid = reader.GetOutputDataObject(0)
    types = vtk_to_numpy(grid.GetCellTypesArray())
    conn = vtk_to_numpy(grid.GetCells().GetConnectivityArray())
    m = meshio.read("%s/%s.xdmf" % (work, name))
    assert (types == np.concatenate([np.full(len(c.data), vtk_types[c.type]) for c in m.cells])).all(), name
    assert (conn == np.concatenate([c.data.ravel() for c in m.cells])).all(), "%s: VTK permutes the nodes" % name
PYEOF
# check_case NAME SOURCE CELLS [options]: NAME.xdmf converts with no mirrored cell, CELLS volume cells
# and the fields u and id, and splits exactly as SOURCE (the mesh meshio read; "" for none) does.
check_case() {
    local name=$1 source=$2 cells=$3
    shift 3
    convert_checked "$WORK/$name.xdmf" "$WORK/$name.tpk" --json --cell-to-point "$@" > "$WORK/$name.json"
    echo '{}' > "$WORK/${name}_src.json"
    [ -z "$source" ] || convert_checked "$source" "$WORK/${name}_src.tpk" --json "$@" > "$WORK/${name}_src.json"
    "$PY" - "$WORK/$name.json" "$WORK/${name}_src.json" "$cells" <<'PYEOF'
import json, sys
x, src = (json.load(open(f)) for f in sys.argv[1:3])
assert x["mirrored_cells"] == 0, x                 # every cell positively oriented as read
assert x["source_cells"] == int(sys.argv[3]), x
assert x["fields"] == 2, x                         # u, and id averaged to the points
for key in src and ("vertices", "tets", "shell_faces", "cells_split", "mirrored_cells", "folds_cut"):
    assert x[key] == src[key], (key, x[key], src[key])
PYEOF
}
check_case tet "$DATA/sfepy/cube_medium_tetra.mesh" 1782
check_case hex "$DATA/sfepy/cube_medium_hexa.mesh" 1000
check_case wedge "" 12308
check_case mixed "$DATA/gmsh/t3_hex_prism_ascii41.msh" 34028
# Gmsh's pyramids overlap some of its tets (folded faces, found alike in the .msh): cut there.
check_case pyr "$WORK/pyr.msh" 2603 --cut-folds
grep -q '"pyramid_into_2":89' "$WORK/pyr.json" || fail "pyr.xdmf: expected 89 pyramids split"
for f in mixed wedge; do
    grep -q '"wedge_into_3":12308' "$WORK/$f.json" || fail "$f.xdmf: expected 12308 wedges split"
done
# Mixed also dropped Gmsh's surface cells, with a warning that counts them.
"$TPK" convert "$WORK/mixed.xdmf" "$WORK/m2.tpk" 2> "$WORK/err" >/dev/null
expect_stderr "dropped cells that are not volumes"
# XML data gives the same file as HDF5 data.
convert_checked "$WORK/hex_xml.xdmf" "$WORK/hex_xml.tpk" --json --cell-to-point > "$WORK/hex_xml.json"
"$TPK" export "$WORK/hex.tpk" --vtu "$WORK/hex_back.vtu"
"$TPK" export "$WORK/hex_xml.tpk" --vtu "$WORK/hex_xml_back.vtu"
"$PY" - "$WORK/hex_back.vtu" "$WORK/hex_xml_back.vtu" <<'PYEOF'
import sys
import meshio, numpy as np
a, b = (meshio.read(f) for f in sys.argv[1:3])
assert np.array_equal(a.points, b.points) and np.array_equal(a.cells[0].data, b.cells[0].data)
assert sorted(a.point_data) == sorted(b.point_data) and "u" in a.point_data, sorted(a.point_data)
for k in a.point_data:
    assert np.array_equal(a.point_data[k], b.point_data[k]), k
PYEOF
# The time series: 3 steps at their times, u's values at each step where meshio put them.
convert_checked "$WORK/series.xdmf" "$WORK/series.tpk" --json > "$WORK/series.json"
"$TPK" export "$WORK/series.tpk" --vtu "$WORK/series_back.vtu"
"$PY" - "$WORK/series.json" "$WORK/series_back.vtu" <<'PYEOF'
import json, sys
import meshio, numpy as np
j = json.load(open(sys.argv[1]))
assert j["steps"] == 3 and j["mirrored_cells"] == 0 and j["source_cells"] == 1782, j
m = meshio.read(sys.argv[2])
p = m.points
for k, t in enumerate((0.0, 0.5, 2.0)):
    want = (p[:, 0] + 2 * p[:, 1] + 3 * p[:, 2]) * (1 + t)
    got = m.point_data["u_t%d" % k]
    assert np.allclose(got, want, rtol=1e-6, atol=1e-5), (k, abs(got - want).max())
PYEOF
"$TPK" info "$WORK/series.tpk" | grep -q "u .*point 3 step" || fail "series.tpk: expected u with 3 steps"
echo "1 passed, 0 failed"
