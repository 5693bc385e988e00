#!/usr/bin/env bash
# --cell-to-point on all-tet input (the converter takes the connectivity over as its tet array): every
# output point carries the mean of the cell values around its source point, checked with meshio.
source "$(dirname "$0")/common.sh"
src=$DATA/sfepy/piezo_mesh_micro.vtk
convert_checked "$src" "$WORK/p.tpk" --cell-to-point --quiet || fail "convert --cell-to-point failed"
"$TPK" export "$WORK/p.tpk" --vtu "$WORK/p.vtu" || fail "export failed"
$PY - "$src" "$WORK/p.vtu" <<'PY' || fail "cell-to-point values differ from the mean of the cells around each point"
import sys
import meshio
import numpy as np
src, out = meshio.read(sys.argv[1]), meshio.read(sys.argv[2])
tets = src.cells_dict["tetra"]
cell_values = np.asarray(src.cell_data_dict["mat_id"]["tetra"], dtype=float).reshape(-1)
total = np.zeros(len(src.points)); count = np.zeros(len(src.points))
for k in range(4):
    np.add.at(total, tets[:, k], cell_values)
    np.add.at(count, tets[:, k], 1)
expected = (total / np.maximum(count, 1))[out.point_data["source_point"].astype(int)]
got = out.point_data["mat_id"]
assert len(np.unique(cell_values)) > 1, "the test needs a cell field with more than one value"
err = np.abs(got - expected).max()
print("max |difference| = %g over %d points" % (err, len(got)))
sys.exit(0 if err <= 1e-5 * max(1.0, np.abs(expected).max()) else 1)
PY
