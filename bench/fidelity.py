#!/usr/bin/env python3
"""Sources and uniform subdivisions for the report's fidelity section (bench/report, section 6).

  fidelity.py source KIND IN OUT.vtk        a source mesh with a smooth, strongly varying point field "f"
  fidelity.py uniform SOURCE.vtk LEVEL OUT.vtk  every cell cut into (2^LEVEL)^3 (hexahedra) or 8^LEVEL
                                             (quadratic tetra) linear cells at its own lattice points,
                                             placed and valued by the cell's own map and interpolant

KIND: `tet10` reads a VTK legacy ASCII file of quadratic tetra (gmsh -order 2 -format vtk), `hex8` a
Medit .mesh of hexahedra. Uniform subdivision is what ParaView's "Nonlinear Subdivision Level" does to
a cell, here for the volume: the subdivided file is converted as usual, and `tetpack check --against`
measures it against the source, as it measures `convert --max-error`. Points that neighbouring cells
share (on a common edge or face) are made once: each lattice point is keyed by the source nodes that
carry it and its exact integer weights on them, which both cells compute alike.
Needs python3-numpy."""
import struct
import sys

import numpy as np

# VTK's quadratic tetra: corners 0-3, then mid-edges 01 12 20 03 13 23
TET10_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


def field(p):
    """The point field: smooth, a few periods over the box, so a linear tet interpolates it with an error of a few percent on these meshes."""
    lo, hi = p.min(axis=0), p.max(axis=0)
    u = (p - lo) / np.maximum(hi - lo, 1e-300)
    return np.sin(12.0 * u[:, 0]) * np.cos(9.0 * u[:, 1]) + np.exp(2.0 * u[:, 2]) * u[:, 0] ** 2


def read_vtk_ascii(path):
    tok = open(path).read().split()
    i = tok.index("POINTS")
    n = int(tok[i + 1])
    pts = np.array(tok[i + 3:i + 3 + 3 * n], dtype=float).reshape(n, 3)
    i = tok.index("CELLS")
    nc, size = int(tok[i + 1]), int(tok[i + 2])
    flat = np.array(tok[i + 3:i + 3 + size], dtype=np.int64)
    i = tok.index("CELL_TYPES")
    types = np.array(tok[i + 2:i + 2 + nc], dtype=int)
    cells, at = [], 0
    for c in range(nc):
        k = flat[at]
        cells.append(flat[at + 1:at + 1 + k])
        at += 1 + k
    return pts, cells, types


def read_medit_hex(path):
    tok = open(path).read().split()
    i = tok.index("Vertices")
    n = int(tok[i + 1])
    v = np.array(tok[i + 2:i + 2 + 4 * n], dtype=float).reshape(n, 4)[:, :3]
    i = tok.index("Hexahedra")
    m = int(tok[i + 1])
    h = np.array(tok[i + 2:i + 2 + 9 * m], dtype=np.int64).reshape(m, 9)[:, :8] - 1
    return v, h


def write_vtk(path, pts, cells, vtk_type, f):
    """VTK legacy binary (big-endian): cells of one type, the point field f."""
    n, per = cells.shape
    with open(path, "wb") as out:
        out.write(b"# vtk DataFile Version 3.0\ntetpack bench/fidelity.py\nBINARY\nDATASET UNSTRUCTURED_GRID\n")
        out.write(b"POINTS %d double\n" % len(pts))
        out.write(pts.astype(">f8").tobytes() + b"\n")
        out.write(b"CELLS %d %d\n" % (n, n * (per + 1)))
        conn = np.hstack([np.full((n, 1), per, dtype=np.int64), cells]).astype(">i4")
        out.write(conn.tobytes() + b"\n")
        out.write(b"CELL_TYPES %d\n" % n)
        out.write(np.full(n, vtk_type, dtype=">i4").tobytes() + b"\n")
        out.write(b"POINT_DATA %d\nSCALARS f double 1\nLOOKUP_TABLE default\n" % len(pts))
        out.write(np.asarray(f, dtype=">f8").tobytes() + b"\n")


def make_source(kind, src, out):
    if kind == "tet10":
        pts, cells, types = read_vtk_ascii(src)
        conn = np.array([c for c, t in zip(cells, types) if t == 24], dtype=np.int64)
        used = np.unique(conn)
        remap = np.full(len(pts), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        pts, conn, vtk_type = pts[used], remap[conn], 24
    elif kind == "hex8":
        pts, conn = read_medit_hex(src)
        vtk_type = 12
    else:
        sys.exit("fidelity.py: kind must be tet10 or hex8, got %s" % kind)
    write_vtk(out, pts, conn, vtk_type, field(pts))


def read_vtk_binary(path):
    data = open(path, "rb").read()

    def line_after(tag, at=0):
        i = data.index(tag, at)
        j = data.index(b"\n", i)
        return data[i:j].split(), j + 1

    head, at = line_after(b"POINTS")
    n = int(head[1])
    pts = np.frombuffer(data, ">f8", 3 * n, at).reshape(n, 3).astype(float)
    head, at = line_after(b"CELLS", at)
    nc, size = int(head[1]), int(head[2])
    flat = np.frombuffer(data, ">i4", size, at).astype(np.int64).reshape(nc, size // nc)
    head, at = line_after(b"CELL_TYPES", at)
    t = int(np.frombuffer(data, ">i4", 1, at)[0])
    _, at = line_after(b"LOOKUP_TABLE", at)
    f = np.frombuffer(data, ">f8", n, at).astype(float)
    return pts, flat[:, 1:], t, f


DIAGONALS = [((0, 1), (2, 3)), ((0, 2), (1, 3)), ((0, 3), (1, 2))]


def tet_lattice(level, diagonal):
    """Barycentric integer points (sum n = 2^level) of a tet lattice and its 8^level sub-tets, by red
    refinement: each tet into 4 corner tets and an octahedron cut along the diagonal joining the
    midpoints of edges DIAGONALS[diagonal] (of each tet's own corners: the corner tets keep their
    parent's corner order, so the cut stays parallel), every sub-tet positive."""
    n = 2 ** level
    tets = [((n, 0, 0, 0), (0, n, 0, 0), (0, 0, n, 0), (0, 0, 0, n))]
    ref = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    for _ in range(level):
        nxt = []
        for t in tets:
            m = {(a, b): tuple((x + y) // 2 for x, y in zip(t[a], t[b])) for a in range(4) for b in range(a + 1, 4)}
            nxt += [(t[0], m[0, 1], m[0, 2], m[0, 3]), (m[0, 1], t[1], m[1, 2], m[1, 3]),
                    (m[0, 2], m[1, 2], t[2], m[2, 3]), (m[0, 3], m[1, 3], m[2, 3], t[3])]
            p, q = DIAGONALS[diagonal]
            ring = [e for e in m if e not in (p, q)]
            cycle = [ring.pop(0)]
            while ring:  # consecutive ring edges share a corner
                k = next(i for i, e in enumerate(ring) if set(e) & set(cycle[-1]))
                cycle.append(ring.pop(k))
            for i in range(4):
                nxt.append((m[p], m[cycle[i]], m[cycle[(i + 1) % 4]], m[q]))
        tets = nxt
    out = []
    for t in tets:  # positive in the reference tet
        x = np.array(t, dtype=float) @ ref
        if np.linalg.det(x[1:] - x[0]) < 0:
            t = (t[0], t[2], t[1], t[3])
        out.append(t)
    points = sorted({p for t in out for p in t})
    index = {p: i for i, p in enumerate(points)}
    return np.array(points, dtype=np.int64), np.array([[index[p] for p in t] for t in out], dtype=np.int64)


def tet10_weights(bary):
    """Quadratic tetra shape functions at barycentric points (rows sum to 1)."""
    L = bary
    w = [L[:, i] * (2 * L[:, i] - 1) for i in range(4)] + [4 * L[:, a] * L[:, b] for a, b in TET10_EDGES]
    return np.stack(w, axis=1)


def hex_lattice(n):
    r = np.arange(n + 1)
    ijk = np.stack(np.meshgrid(r, r, r, indexing="ij"), axis=-1).reshape(-1, 3)  # x fastest last
    at = lambda i, j, k: (i * (n + 1) + j) * (n + 1) + k
    sub = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                sub.append([at(i, j, k), at(i + 1, j, k), at(i + 1, j + 1, k), at(i, j + 1, k),
                            at(i, j, k + 1), at(i + 1, j, k + 1), at(i + 1, j + 1, k + 1), at(i, j + 1, k + 1)])
    return ijk, np.array(sub, dtype=np.int64)


HEX_CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]


def lattice_group(pts, f, conn, corners, num, w, sub):
    """Points (positions, values, keys) and sub-cells of cells `conn` cut at one lattice: num the lattice
    points' integer weights on `corners` (their key), w the map's weights on all of a cell's nodes."""
    cells, P = len(conn), len(num)
    xyz = np.einsum("pk,ckd->cpd", w, pts[conn]).reshape(-1, 3)
    val = np.einsum("pk,ck->cp", w, f[conn]).reshape(-1)
    # key: (node id, integer weight) over the corners that carry the point, sorted by id, padded
    ids = np.broadcast_to(corners[:, None, :], (cells, P, corners.shape[1]))
    wts = np.broadcast_to(num[None, :, :], (cells, P, corners.shape[1]))
    ids = np.where(wts > 0, ids, np.iinfo(np.int64).max)
    order = np.argsort(ids, axis=2)
    key = np.concatenate([np.take_along_axis(ids, order, axis=2), np.take_along_axis(wts, order, axis=2)], axis=2)
    local = (np.arange(cells)[:, None, None] * P + sub[None, :, :]).reshape(-1, sub.shape[1])
    return xyz, val, key.reshape(cells * P, -1), local


def uniform(src, level, out):
    pts, conn, vtk_type, f = read_vtk_binary(src)
    n = 2 ** level
    groups = []
    if vtk_type == 24:
        # each cell's octahedra cut along its shortest mid-edge diagonal, as the converter's own split
        mid = {tuple(sorted(e)): 4 + i for i, e in enumerate(TET10_EDGES)}
        length = np.stack([np.linalg.norm(pts[conn[:, mid[p]]] - pts[conn[:, mid[q]]], axis=1) for p, q in DIAGONALS],
                          axis=1)
        choice = np.argmin(length, axis=1)
        for d in range(3):
            if np.any(choice == d):
                lat, sub = tet_lattice(level, d)
                groups.append(lattice_group(pts, f, conn[choice == d], conn[choice == d][:, :4], lat,
                                            tet10_weights(lat / n), sub))
        out_type = 10
    elif vtk_type == 12:
        lat, sub = hex_lattice(n)
        # trilinear weight of corner c at lattice point (i, j, k), times n^3: exact integers
        num = np.stack([np.prod([lat[:, a] if c[a] else n - lat[:, a] for a in range(3)], axis=0)
                        for c in HEX_CORNERS], axis=1)
        groups.append(lattice_group(pts, f, conn, conn, num, num / float(n ** 3), sub))
        out_type = 12
    else:
        sys.exit("fidelity.py: %s: expected quadratic tetra (24) or hexahedra (12), found type %d" % (src, vtk_type))
    xyz = np.concatenate([g[0] for g in groups])
    val = np.concatenate([g[1] for g in groups])
    width = max(g[2].shape[1] for g in groups)
    keys = np.concatenate([np.pad(g[2], ((0, 0), (0, width - g[2].shape[1])), constant_values=-1) for g in groups])
    offsets = np.cumsum([0] + [len(g[0]) for g in groups])
    local = np.concatenate([g[3] + o for g, o in zip(groups, offsets)])
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    write_vtk(out, xyz[first], inverse.reshape(-1)[local], out_type, val[first])


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "source":
        make_source(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) == 5 and sys.argv[1] == "uniform":
        uniform(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    else:
        sys.exit(__doc__)
