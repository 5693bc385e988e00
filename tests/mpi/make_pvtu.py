#!/usr/bin/python3
"""Decompose a real mesh into the pieces of a .pvtu, as a solver writes one file per rank.

usage: make_pvtu.py INPUT OUT.pvtu PIECES [--global-ids] [--no-point-data]

The volume cells are sorted by the x of their centroid and cut into PIECES slabs of equal count (a
decomposition unrelated to tetpack's Hilbert cut); each piece keeps the points its cells use, renumbered,
with their point data, and is written as a .vtu by meshio. With --global-ids each piece also carries the
point field GlobalPointIds (the point's index in INPUT), as decomposers (ParaView's D3, VTK's
vtkGenerateGlobalIds) write it; without, the pieces share boundary points only by their coordinates.
--no-point-data leaves out INPUT's point data (meshio reads Medit vertex refs as point data, which tetpack's
own Medit reader does not keep, so the pieces would carry a field the single-file conversion has not).
"""
import os
import sys

import meshio
import numpy as np

VOLUME = {"tetra", "hexahedron", "wedge", "pyramid"}


def scalar(values):
    """A scalar point field as a 1-D array (meshio reads VTK scalars as (n, 1)), or None."""
    v = np.asarray(values)
    if v.ndim == 2 and v.shape[1] == 1:
        v = v[:, 0]
    return v if v.ndim == 1 else None


def main():
    src, out, pieces = sys.argv[1], sys.argv[2], int(sys.argv[3])
    mesh = meshio.read(src)
    global_ids = "--global-ids" in sys.argv[4:]
    if "--no-point-data" in sys.argv[4:]:
        mesh.point_data = {}
    blocks = [(b.type, np.asarray(b.data)) for b in mesh.cells if b.type in VOLUME]
    kinds = np.concatenate([np.full(len(d), i) for i, (_, d) in enumerate(blocks)])
    rows = np.concatenate([np.arange(len(d)) for _, d in blocks])
    centroid_x = np.concatenate([mesh.points[d][:, :, 0].mean(axis=1) for _, d in blocks])
    order = np.argsort(centroid_x, kind="stable")
    stem = os.path.splitext(os.path.basename(out))[0]
    folder = os.path.dirname(out) or "."
    names = []
    for k in range(pieces):
        chosen = order[len(order) * k // pieces:len(order) * (k + 1) // pieces]
        piece_blocks = [(kind, d[np.sort(rows[chosen][kinds[chosen] == i])])
                        for i, (kind, d) in enumerate(blocks) if np.any(kinds[chosen] == i)]
        used = np.unique(np.concatenate([d.ravel() for _, d in piece_blocks]))
        local = np.full(len(mesh.points), -1, dtype=np.int64)
        local[used] = np.arange(len(used))
        point_data = {name: scalar(v)[used] for name, v in mesh.point_data.items() if scalar(v) is not None}
        if global_ids:
            point_data["GlobalPointIds"] = used.astype(np.float64)
        name = "%s_%d.vtu" % (stem, k)
        meshio.write(os.path.join(folder, name),
                     meshio.Mesh(mesh.points[used], [(kind, local[d]) for kind, d in piece_blocks],
                                 point_data=point_data), binary=True)
        names.append(name)
    with open(out, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="0.1">\n'
                '  <PUnstructuredGrid GhostLevel="0">\n    <PPoints>\n'
                '      <PDataArray type="Float64" NumberOfComponents="3"/>\n    </PPoints>\n')
        for name in names:
            f.write('    <Piece Source="%s"/>\n' % name)
        f.write("  </PUnstructuredGrid>\n</VTKFile>\n")


main()
