#!/usr/bin/python3
"""Write an N x N x N grid of unit cubes, each split into 6 tets (Kuhn split, conforming), as a binary
(big-endian) VTK legacy file with one point scalar. Vertices are jittered so no tet is degenerate
and shuffled so the input is not already in a cache-friendly order. Usage: make_grid_vtk.py N out.vtk
With --stream (make_grid_vtk.py N out.vtk --stream), for grids past memory (N = 551: 1.0G tets), the points
are float32 and nothing is shuffled: points and cells are written a plane of cubes at a time, so memory
stays at the scalar (4 bytes a point) and one plane, and the file at 26 bytes a tet."""
import sys

import numpy as np


def kuhn_tets(n):
    i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    base = (i * (n + 1) + j) * (n + 1) + k
    base = base.reshape(-1)
    dx, dy, dz = (n + 1) * (n + 1), n + 1, 1
    c = [base + ((b >> 2) & 1) * dx + ((b >> 1) & 1) * dy + (b & 1) * dz for b in range(8)]
    # The 6 tets of a cube along the main diagonal 0 -> 7 (corner bits x,y,z).
    paths = [(0, 4, 6, 7), (0, 4, 5, 7), (0, 2, 6, 7), (0, 2, 3, 7), (0, 1, 5, 7), (0, 1, 3, 7)]
    return np.stack([np.stack([c[a] for a in p], axis=1) for p in paths], axis=1).reshape(-1, 4)


def main():
    n = int(sys.argv[1])
    out = sys.argv[2]
    rng = np.random.default_rng(12345)
    g = np.arange(n + 1, dtype=np.float64)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    pts = np.stack([x.reshape(-1), y.reshape(-1), z.reshape(-1)], axis=1)
    pts += rng.uniform(-0.15, 0.15, size=pts.shape)
    tets = kuhn_tets(n)
    perm = rng.permutation(len(pts))          # new id of old point
    tets = perm[tets]
    pts_new = np.empty_like(pts)
    pts_new[perm] = pts
    tets = tets[rng.permutation(len(tets))]
    c = 0.5 * n
    r = np.sqrt(((pts_new - c) ** 2).sum(axis=1))
    scalar = (np.sin(r * 0.5) * np.cos(pts_new[:, 2] * 0.2)).astype(">f4")
    nt = len(tets)
    with open(out, "wb") as f:
        f.write(b"# vtk DataFile Version 3.0\ntetpack benchmark grid\nBINARY\nDATASET UNSTRUCTURED_GRID\n")
        f.write(b"POINTS %d double\n" % len(pts_new))
        f.write(pts_new.astype(">f8").tobytes())
        f.write(b"\nCELLS %d %d\n" % (nt, nt * 5))
        cells = np.empty((nt, 5), dtype=">i4")
        cells[:, 0] = 4
        cells[:, 1:] = tets
        f.write(cells.tobytes())
        f.write(b"\nCELL_TYPES %d\n" % nt)
        f.write(np.full(nt, 10, dtype=">i4").tobytes())
        f.write(b"\nPOINT_DATA %d\nSCALARS wave float 1\nLOOKUP_TABLE default\n" % len(pts_new))
        f.write(scalar.tobytes())
        f.write(b"\n")
    print("%s: %d points, %d tets" % (out, len(pts_new), nt), file=sys.stderr)


def kuhn_slab(n, i):
    """The 6 tets of each cube of plane i (cubes (i, j, k)), as kuhn_tets numbers them."""
    j, k = np.meshgrid(np.arange(n, dtype=np.int64), np.arange(n, dtype=np.int64), indexing="ij")
    base = ((i * (n + 1) + j) * (n + 1) + k).reshape(-1)
    dx, dy, dz = (n + 1) * (n + 1), n + 1, 1
    c = [base + ((b >> 2) & 1) * dx + ((b >> 1) & 1) * dy + (b & 1) * dz for b in range(8)]
    paths = [(0, 4, 6, 7), (0, 4, 5, 7), (0, 2, 6, 7), (0, 2, 3, 7), (0, 1, 5, 7), (0, 1, 3, 7)]
    return np.stack([np.stack([c[a] for a in p], axis=1) for p in paths], axis=1).reshape(-1, 4)


def main_stream(n, out):
    rng = np.random.default_rng(12345)
    npts, nt = (n + 1) ** 3, 6 * n ** 3
    if npts > 2 ** 31 - 1:
        sys.exit("make_grid_vtk.py: %d points: VTK legacy ids are 32-bit" % npts)
    scalar = np.empty(npts, dtype=">f4")
    g = np.arange(n + 1, dtype=np.float64)
    c = 0.5 * n
    plane = (n + 1) * (n + 1)
    with open(out, "wb") as f:
        f.write(b"# vtk DataFile Version 3.0\ntetpack benchmark grid (streamed)\nBINARY\nDATASET UNSTRUCTURED_GRID\n")
        f.write(b"POINTS %d float\n" % npts)
        for i in range(n + 1):
            y, z = np.meshgrid(g, g, indexing="ij")
            pts = np.stack([np.full(plane, float(i)), y.reshape(-1), z.reshape(-1)], axis=1)
            pts += rng.uniform(-0.15, 0.15, size=pts.shape)
            r = np.sqrt(((pts - c) ** 2).sum(axis=1))
            scalar[i * plane:(i + 1) * plane] = np.sin(r * 0.5) * np.cos(pts[:, 2] * 0.2)
            f.write(pts.astype(">f4").tobytes())
        f.write(b"\nCELLS %d %d\n" % (nt, nt * 5))
        for i in range(n):
            tets = kuhn_slab(n, i)
            cells = np.empty((len(tets), 5), dtype=">i4")
            cells[:, 0] = 4
            cells[:, 1:] = tets
            f.write(cells.tobytes())
        f.write(b"\nCELL_TYPES %d\n" % nt)
        types = np.full(6 * n * n, 10, dtype=">i4").tobytes()
        for i in range(n):
            f.write(types)
        f.write(b"\nPOINT_DATA %d\nSCALARS wave float 1\nLOOKUP_TABLE default\n" % npts)
        f.write(scalar.tobytes())
        f.write(b"\n")
    print("%s: %d points, %d tets" % (out, npts, nt), file=sys.stderr)


if __name__ == "__main__":
    if "--stream" in sys.argv[1:]:
        args = [a for a in sys.argv[1:] if a != "--stream"]
        main_stream(int(args[0]), args[1])
    else:
        main()
