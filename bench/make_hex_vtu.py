#!/usr/bin/python3
"""Write an N x N x N grid of hexahedra as a binary VTU (zlib-compressed appended data, written by meshio)
with a point scalar, for issue 3's mixed-cell conversion benchmark (N = 216 gives about 10M hexahedra).
Interior points are jittered so cells are not all alike. Usage: make_hex_vtu.py N out.vtu"""
import sys

import meshio
import numpy as np


def main():
    n = int(sys.argv[1])
    rng = np.random.default_rng(7)
    g = np.arange(n + 1, dtype=np.float64)
    z, y, x = np.meshgrid(g, g, g, indexing="ij")
    pts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    inner = (pts > 0).all(axis=1) & (pts < n).all(axis=1)
    pts[inner] += rng.uniform(-0.2, 0.2, size=(inner.sum(), 3))
    i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    base = ((k * (n + 1) + j) * (n + 1) + i).ravel()
    dx, dy, dz = 1, n + 1, (n + 1) * (n + 1)
    hexes = np.stack([base, base + dx, base + dx + dy, base + dy,
                      base + dz, base + dx + dz, base + dx + dy + dz, base + dy + dz], axis=1)
    c = 0.5 * n
    scalar = np.sin(np.sqrt(((pts - c) ** 2).sum(axis=1)) * 0.3).astype(np.float32)
    mesh = meshio.Mesh(pts, [("hexahedron", hexes)], point_data={"wave": scalar})
    meshio.write(sys.argv[2], mesh, binary=True)
    print("%s: %d points, %d hexahedra" % (sys.argv[2], len(pts), len(hexes)), file=sys.stderr)


if __name__ == "__main__":
    main()
