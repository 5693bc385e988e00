#!/usr/bin/env python3
"""Checks of `tetpack iso` outputs, independent of its code (numpy and meshio only).

  iso_check.py reference MESH.vtu FIELD VALUES OUT.ply REPORT.json
      An independent marching-tets reference on the tets and point field that `tetpack export --vtu`
      wrote for the same .tpk: per value, the triangle count, the vertex count (crossed edges), and the
      area (each crossed tet's polygon, planar since the field is linear in a tet) within 1e-6 relative.
      The PLY: every surface edge inside the volume in exactly two triangles (watertight), every open
      edge on a shell face of the tets; triangles counter-clockwise seen from the higher values; the
      report's counts equal to the PLY's.
  iso_check.py meshio OUT.ply|OUT.obj TRIANGLES VERTICES
      meshio reads the file back with these counts.
  iso_check.py glb OUT.glb TRIANGLES VERTICES
      GLB structure by the glTF 2.0 spec: header, chunk lengths and padding, JSON accessors, buffer views
      and the buffer consistent with the BIN chunk; POSITION min/max equal to the data; indices in range;
      unit normals.
  iso_check.py sphere OUT.ply RADIUS REL_TOL
      A closed surface (every edge in two triangles), area within REL_TOL of 4 pi r^2 and enclosed volume
      (positive: normals point outward, toward increasing radius) within REL_TOL of 4/3 pi r^3."""
import collections
import json
import struct
import sys

import numpy as np


def read_ply(path):
    data = open(path, "rb").read()
    head, body = data.split(b"end_header\n", 1)
    lines = head.decode().split("\n")
    nv = nf = 0
    props = []
    for line in lines:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            nv = int(w[2])
        elif w[:2] == ["element", "face"]:
            nf = int(w[2])
        elif w[:1] == ["property"] and w[1] != "list":
            props.append((w[2], {"double": "<f8", "float": "<f4", "int": "<i4"}[w[1]]))
    vert = np.frombuffer(body, np.dtype(props), nv)
    off = vert.nbytes
    face = np.frombuffer(body[off:], np.dtype([("n", "u1"), ("v", "<i4", 3)]), nf)
    assert (face["n"] == 3).all()
    assert off + face.nbytes == len(body), "trailing bytes"
    return vert, face["v"].astype(np.int64)


def edge_uses(tri):
    uses = collections.Counter()
    for t in tri:
        for k in range(3):
            a, b = t[k], t[(k + 1) % 3]
            uses[(min(a, b), max(a, b))] += 1
    return uses


def reference(vtu, field, values, ply, report):
    import meshio
    m = meshio.read(vtu)
    pts, tets = m.points, m.cells_dict["tetra"].astype(np.int64)
    s = np.asarray(m.point_data[field], dtype=np.float64).ravel()
    rep = json.load(open(report))
    vert, tri = read_ply(ply)
    assert rep["triangles"] == len(tri) and rep["vertices"] == len(vert), (rep["triangles"], len(tri))
    xyz = np.stack([vert["x"], vert["y"], vert["z"]], axis=1)
    # shell faces of the tets: faces in one tet
    faces = collections.Counter()
    for k in range(4):
        f = np.sort(np.delete(tets, k, axis=1), axis=1)
        faces.update(map(tuple, f))
    shell = {f for f, n in faces.items() if n == 1}
    first = 0
    for i, v in enumerate(values):
        sv = s[tets]
        above = (sv >= v).sum(axis=1)
        nan = np.isnan(sv).any(axis=1)
        ntri = np.where(nan, 0, np.where(above == 2, 2, np.where((above == 1) | (above == 3), 1, 0)))
        want_tris = int(ntri.sum())
        # crossed edges
        edges = set()
        area = 0.0
        for t in np.nonzero(ntri)[0]:
            c = tets[t]
            poly = []
            for a, b in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]:
                ia, ib = min(c[a], c[b]), max(c[a], c[b])
                if (s[ia] >= v) != (s[ib] >= v):
                    edges.add((ia, ib))
                    tt = (v - s[ia]) / (s[ib] - s[ia])
                    poly.append(pts[ia] + tt * (pts[ib] - pts[ia]))
            poly = np.array(poly)
            if len(poly) == 3:
                area += 0.5 * np.linalg.norm(np.cross(poly[1] - poly[0], poly[2] - poly[0]))
            else:  # 4 points of a planar convex quad in some order: area from the convex hull in its plane
                ctr = poly.mean(axis=0)
                n = np.cross(poly[1] - poly[0], poly[2] - poly[0])
                if np.linalg.norm(n) == 0:
                    n = np.cross(poly[1] - poly[0], poly[3] - poly[0])
                u = poly[0] - ctr
                w = np.cross(n, u)
                ang = np.arctan2((poly - ctr) @ w, (poly - ctr) @ u)
                q = poly[np.argsort(ang)]
                area += 0.5 * np.linalg.norm(np.cross(q[2] - q[0], q[3] - q[1]))
        got = rep["values"][i]
        assert got["triangles"] == want_tris, ("value", v, "triangles", got["triangles"], want_tris)
        assert got["vertices"] == len(edges), ("value", v, "vertices", got["vertices"], len(edges))
        sub = tri[first:first + want_tris]
        first += want_tris
        p = xyz[sub]
        cr = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        ours = 0.5 * np.linalg.norm(cr, axis=1).sum()
        assert abs(ours - area) <= 1e-6 * max(area, 1e-300), ("area", v, ours, area)
        # watertight inside, open edges on the shell
        ea, eb = vert["edge_a"], vert["edge_b"]
        opened = 0
        for (a, b), n in edge_uses(sub).items():
            assert n in (1, 2), ("edge used", n, "times")
            if n == 1:
                opened += 1
                ids = tuple(sorted({ea[a], eb[a], ea[b], eb[b]}))
                assert ids in shell, ("open edge not on a shell face", ids)
        # orientation: normal toward the higher end of each corner's edge (non-degenerate triangles)
        lens = np.linalg.norm(cr, axis=1)
        big = lens > 1e-9 * max(lens.max(initial=0), 1e-300)
        for k in range(3):
            vid = sub[:, k]
            a, b = ea[vid], eb[vid]
            up = np.where((s[b] > s[a])[:, None], pts[b] - pts[a], pts[a] - pts[b])
            dots = np.einsum("ij,ij->i", cr, up)
            assert (dots[big] > 0).all(), ("triangle facing the lower values", int((dots[big] <= 0).sum()))
        print("value %g: %d triangles, %d vertices, area %.12g (reference %.12g), %d open edges"
              % (v, want_tris, len(edges), ours, area, opened))
    assert first == len(tri)


def check_meshio(path, ntri, nvert):
    import meshio
    m = meshio.read(path)
    t = m.cells_dict.get("triangle", np.zeros((0, 3)))
    assert len(t) == ntri and len(m.points) == nvert, (path, len(t), len(m.points), ntri, nvert)
    print("meshio", path, len(t), "triangles", len(m.points), "points")


def check_glb(path, ntri, nvert):
    data = open(path, "rb").read()
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67 and version == 2 and length == len(data), (magic, version, length, len(data))
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert jtype == 0x4E4F534A and jlen % 4 == 0
    doc = json.loads(data[20:20 + jlen].decode("utf-8"))
    assert doc["asset"]["version"] == "2.0"
    pos = 20 + jlen
    if ntri == 0:
        assert pos == len(data) and "meshes" not in doc and "buffers" not in doc
        print("glb: empty surface, valid")
        return
    blen, btype = struct.unpack_from("<II", data, pos)
    assert btype == 0x004E4942 and blen % 4 == 0 and pos + 8 + blen == len(data)
    bin_ = data[pos + 8:]
    assert doc["buffers"] == [{"byteLength": blen}] or doc["buffers"][0]["byteLength"] <= blen
    comp = {5126: ("<f4", 4), 5125: ("<u4", 4)}
    ncomp = {"SCALAR": 1, "VEC3": 3}
    prim = doc["meshes"][0]["primitives"][0]
    assert prim.get("mode", 4) == 4

    def get(i):
        acc = doc["accessors"][i]
        view = doc["bufferViews"][acc["bufferView"]]
        dt, size = comp[acc["componentType"]]
        off = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        n = acc["count"] * ncomp[acc["type"]]
        assert acc["count"] >= 1 and off % size == 0
        assert acc.get("byteOffset", 0) + n * size <= view["byteLength"]
        assert view["byteOffset"] + view["byteLength"] <= doc["buffers"][0]["byteLength"]
        return acc, np.frombuffer(bin_, dt, n, off).reshape(acc["count"], -1)

    pacc, p = get(prim["attributes"]["POSITION"])
    assert pacc["count"] == nvert and pacc["type"] == "VEC3"
    assert np.array_equal(p.min(axis=0), np.float32(pacc["min"])) and np.array_equal(p.max(axis=0), np.float32(pacc["max"]))
    nacc, n = get(prim["attributes"]["NORMAL"])
    assert nacc["count"] == nvert and np.allclose(np.linalg.norm(n, axis=1), 1, atol=1e-5)
    vacc, _ = get(prim["attributes"]["_VALUE"])
    assert vacc["count"] == nvert
    iacc, idx = get(prim["indices"])
    assert iacc["componentType"] == 5125 and iacc["count"] == 3 * ntri and idx.max() < nvert
    assert doc["bufferViews"][doc["accessors"][prim["indices"]]["bufferView"]]["target"] == 34963
    print("glb: %d triangles, %d vertices, %d bytes, valid" % (ntri, nvert, len(data)))


def check_sphere(path, r, tol):
    vert, tri = read_ply(path)
    xyz = np.stack([vert["x"], vert["y"], vert["z"]], axis=1)
    assert all(n == 2 for n in edge_uses(tri).values()), "not closed"
    p = xyz[tri]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
    vol = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6
    a0, v0 = 4 * np.pi * r * r, 4 / 3 * np.pi * r ** 3
    print("sphere r=%g: area %.6f (4 pi r^2 %.6f, %.2e), volume %.6f (%.6f, %.2e)"
          % (r, area, a0, area / a0 - 1, vol, v0, vol / v0 - 1))
    assert abs(area / a0 - 1) < tol and abs(vol / v0 - 1) < tol


if __name__ == "__main__":
    mode = sys.argv[1]
    if mode == "reference":
        reference(sys.argv[2], sys.argv[3], [float(x) for x in sys.argv[4].split(",")], sys.argv[5], sys.argv[6])
    elif mode == "meshio":
        check_meshio(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
    elif mode == "glb":
        check_glb(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
    elif mode == "sphere":
        check_sphere(sys.argv[2], float(sys.argv[3]), float(sys.argv[4]))
    else:
        sys.exit(__doc__)
