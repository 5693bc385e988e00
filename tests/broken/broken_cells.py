"""Corpus cases for the cell checks (2xx), each with exact counts, and a near miss for each geometric check.
The importers refuse some broken node lists before `check` runs (exit 2): ids out of range, unknown
cell types and wrong node counts; they drop lower-dimensional cells (with a warning). Those cases are
here with the exit status that documents it; tests/test_check_cells.c covers 201, 212 and 213 on
meshes built in memory."""
import math

from make_broken import vtk_legacy

CUBE = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
KUHN = [(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)]
HEX = list(range(8))
ALL_2XX = ["index_out_of_range", "repeated_vertex", "zero_volume_cell", "inverted_cell", "nonplanar_face",
           "nonconvex_cell", "self_intersecting_cell", "split_inverts", "sliver_tet", "poor_radius_ratio",
           "duplicate_cell", "unsupported_cell", "lower_dimensional_cell"]


def tets(ids):
    return [(10, list(t)) for t in ids]


def others(*names):
    return [n for n in ALL_2XX if n not in names]


def coplanar_points():
    """Four points exactly on the plane 3x + 5y + 7z = 0 (integers near 2^30 times 2^-20, so every
    coordinate is a double and the plane is exact) whose double determinant does not come out 0."""
    seed = 1
    while True:
        pts = []
        while len(pts) < 4:
            seed = (seed * 6364136223846793005 + 1442695040888963407) % 2 ** 64
            x = (seed >> 34) + 2 ** 29
            seed = (seed * 6364136223846793005 + 1442695040888963407) % 2 ** 64
            y = (seed >> 34) - 2 ** 29
            if (3 * x + 5 * y) % 7 == 0:
                pts.append(tuple(math.ldexp(v, -20) for v in (x, y, -(3 * x + 5 * y) // 7)))
        a, b, c, d = pts
        u, v, w = [[q[k] - a[k] for k in range(3)] for q in (b, c, d)]
        det = (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
               u[2] * (v[0] * w[1] - v[1] * w[0]))
        if det != 0:
            return pts


def twisted_hex():
    """sfepy's cross3d upper arm: the top face turned ~56 deg against the bottom one."""
    return [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1), (0.6, 0, 2), (1, 0.6, 2), (0.4, 1, 2), (0, 0.4, 2)]


def turned_wedge(degrees):
    """A unit triangular prism whose top triangle is turned by `degrees` about the axis."""
    t = math.radians(degrees)
    ring = [2 * math.pi * k / 3 for k in range(3)]
    return ([(math.cos(a), math.sin(a), 0) for a in ring] +
            [(math.cos(a + t), math.sin(a + t), 1) for a in ring])


def cases():
    out = []
    add = out.append
    add({"name": "cells_clean_cube", "text": vtk_legacy(CUBE, tets(KUHN)), "expect": {}, "absent": ALL_2XX})

    # Refused by the VTK importer (exit 2), so the check never sees them.
    add({"name": "cells_index_out_of_range_refused", "text": vtk_legacy(CUBE, tets(KUHN[:5] + [(0, 5, 1, 8)])),
         "expect": {}, "exit": 2})
    add({"name": "cells_unknown_type_refused", "text": vtk_legacy(CUBE, tets(KUHN) + [(99, [0, 1, 2, 6])]),
         "expect": {}, "exit": 2})
    add({"name": "cells_wrong_node_count_refused", "text": vtk_legacy(CUBE, tets(KUHN) + [(12, HEX[:7])]),
         "expect": {}, "exit": 2})
    # Dropped by the importer with a warning: nothing left for 213 to count.
    add({"name": "cells_lower_dimensional_dropped",
         "text": vtk_legacy(CUBE, tets(KUHN) + [(5, [0, 1, 2]), (3, [0, 6])]),
         "expect": {}, "absent": ALL_2XX})

    # 202: a tet naming vertex 1 twice, a hexahedron naming 6 twice.
    add({"name": "cells_repeated_vertex",
         "text": vtk_legacy(CUBE, tets(KUHN) + [(10, [0, 1, 1, 6]), (12, [0, 1, 2, 3, 4, 5, 6, 6])]),
         "expect": {"repeated_vertex": 2}, "absent": others("repeated_vertex")})

    # 203: the bottom face as a tet, and four points exactly coplanar whose double determinant is not 0.
    pts = CUBE + coplanar_points()
    add({"name": "cells_zero_volume", "text": vtk_legacy(pts, tets(KUHN + [(0, 1, 2, 3), (8, 9, 10, 11)])),
         "expect": {"zero_volume_cell": 2}, "absent": ["inverted_cell", "sliver_tet"]})
    # Near miss: at 1e7, d one ulp above the plane of a, b, c: a valid (very thin) tet, a sliver.
    o = 1e7
    up = o + math.ulp(o)
    thin = [(o, o, o), (o + 1, o, o), (o, o + 1, o), (o + 0.25, o + 0.25, up)]
    add({"name": "cells_one_ulp_above_near_miss", "text": vtk_legacy(thin, tets([(0, 1, 2, 3)])),
         "expect": {"sliver_tet": 1, "poor_radius_ratio": 1}, "absent": ["zero_volume_cell", "inverted_cell"],
         "exit": 0})

    # 204: two Kuhn tets turned over, a hexahedron and a wedge in mirrored order.
    flipped = list(KUHN)
    flipped[1] = (0, 3, 2, 6)
    flipped[4] = (4, 0, 5, 6)
    pts = CUBE + [(x + 2, y, z) for x, y, z in CUBE]
    add({"name": "cells_inverted",
         "text": vtk_legacy(pts, tets(flipped) + [(12, [12, 13, 14, 15, 8, 9, 10, 11]), (13, [12, 13, 15, 8, 9, 11])]),
         "expect": {"inverted_cell": 4}, "absent": others("inverted_cell")})

    # 205: corner 6 of a cube raised by 0.5: only the top face warps (36.9 deg); the sides stay planar.
    raised = list(CUBE)
    raised[6] = (1, 1, 1.5)
    add({"name": "cells_nonplanar_face", "text": vtk_legacy(raised, [(12, HEX)]),
         "expect": {"nonplanar_face": 1}, "absent": others("nonplanar_face"), "exit": 0})
    # Near miss: a frustum at 1e7 with exactly planar trapezoid faces, even with --warp-deg 0.
    frustum = [(0, 0, 0), (4, 0, 0), (4, 4, 0), (0, 4, 0), (1, 1, 2), (3, 1, 2), (3, 3, 2), (1, 3, 2)]
    frustum = [(x + o, y + o + 0.125, z + o + 0.25) for x, y, z in frustum]
    add({"name": "cells_planar_frustum_near_miss", "text": vtk_legacy(frustum, [(12, HEX)]),
         "args": ["--warp-deg", "0"], "expect": {}, "absent": ALL_2XX})

    # 206: corner 6 pushed inside (a dent): not convex, no faces crossing.
    dent = list(CUBE)
    dent[6] = (0.4, 0.4, 0.4)
    add({"name": "cells_nonconvex", "text": vtk_legacy(dent, [(12, HEX)]),
         "expect": {"nonconvex_cell": 1}, "absent": ["self_intersecting_cell", "zero_volume_cell", "inverted_cell"],
         "exit": 0})
    # Near miss: a parallelepiped sheared by 70 deg and stretched 20:1 is convex.
    u, v, w = (20, 0, 0), (2.75, 1, 0), (-2.5, 0.5, 0.25)
    skew = [tuple(100 + x * u[k] + y * v[k] + z * w[k] for k in range(3)) for x, y, z in CUBE]
    add({"name": "cells_skewed_hex_near_miss", "text": vtk_legacy(skew, [(12, HEX)]),
         "args": ["--warp-deg", "0"], "expect": {}, "absent": ALL_2XX})

    # 207: top face as a bow-tie (nodes 6 and 7 swapped).
    add({"name": "cells_self_intersecting", "text": vtk_legacy(CUBE, [(12, [0, 1, 2, 3, 4, 5, 7, 6])]),
         "expect": {"self_intersecting_cell": 1, "split_inverts": 1}, "absent": ["inverted_cell"]})
    # A wedge whose top triangle is turned by 150 deg: the quads cross each other (and the split folds).
    add({"name": "cells_self_intersecting_wedge", "text": vtk_legacy(turned_wedge(150), [(13, list(range(6)))]),
         "expect": {"self_intersecting_cell": 1, "split_inverts": 1, "nonconvex_cell": 1, "nonplanar_face": 3},
         "absent": ["inverted_cell", "zero_volume_cell"]})
    # Near miss: turned by 50 deg the quads warp by far more than 20 deg, but nothing crosses or folds.
    add({"name": "cells_turned_wedge_near_miss", "text": vtk_legacy(turned_wedge(50), [(13, list(range(6)))]),
         "expect": {"nonplanar_face": 3}, "absent": others("nonplanar_face"), "exit": 0})

    # 208: the twisted hex of sfepy's cross: warped, not convex, its split has a negative tet; no faces cross.
    add({"name": "cells_split_inverts", "text": vtk_legacy(twisted_hex(), [(12, HEX)]),
         "expect": {"split_inverts": 1, "nonplanar_face": 4, "nonconvex_cell": 1},
         "absent": ["self_intersecting_cell", "zero_volume_cell", "inverted_cell"], "exit": 0})
    # Near miss: a wedge turned by 5 deg: its quads warp by ~10 deg (under the default 20), a valid split.
    add({"name": "cells_slightly_turned_wedge_near_miss",
         "text": vtk_legacy(turned_wedge(5), [(13, list(range(6)))]), "expect": {}, "absent": ALL_2XX})

    # 209 and 210: a square's corners with one lifted by 1e-6 (min dihedral ~1e-4 deg), beside the cube.
    pts = CUBE + [(3, 0, 0), (4, 0, 0), (4, 1, 1e-6), (3, 1, 0)]
    add({"name": "cells_sliver", "text": vtk_legacy(pts, tets(KUHN + [(8, 9, 11, 10)])),
         "expect": {"sliver_tet": 1, "poor_radius_ratio": 1}, "absent": others("sliver_tet", "poor_radius_ratio"),
         "exit": 0})
    add({"name": "cells_sliver_near_miss", "text": vtk_legacy(pts, tets(KUHN + [(8, 9, 11, 10)])),
         "args": ["--sliver-deg", "1e-5"], "expect": {"poor_radius_ratio": 1}, "absent": ["sliver_tet"], "exit": 0})
    # 210 alone: a needle 30 times longer than wide has a poor radius ratio but no small dihedral angle.
    pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0.3, 0.3, 30)]
    add({"name": "cells_needle_radius_ratio", "text": vtk_legacy(pts, tets([(0, 1, 2, 3)])),
         "expect": {"poor_radius_ratio": 1}, "absent": others("poor_radius_ratio"), "exit": 0})

    # 211: a Kuhn tet repeated in another order, and a voxel on the hexahedron's corners.
    pts = CUBE + [(x + 2, y, z) for x, y, z in CUBE]
    cells = tets(KUHN + [(6, 2, 1, 0)]) + [(12, [8, 9, 10, 11, 12, 13, 14, 15]),
                                          (11, [8, 9, 11, 10, 12, 13, 15, 14])]
    add({"name": "cells_duplicate", "text": vtk_legacy(pts, cells),
         "expect": {"duplicate_cell": 2}, "absent": others("duplicate_cell")})

    # 212: a pentagonal prism (VTK 15) is read, but convert cannot split it.
    ring = [(math.cos(2 * math.pi * k / 5), math.sin(2 * math.pi * k / 5)) for k in range(5)]
    prism = [(x, y, 0) for x, y in ring] + [(x, y, 1) for x, y in ring]
    add({"name": "cells_unsupported_prism", "text": vtk_legacy(prism, [(15, list(range(10)))]),
         "expect": {"unsupported_cell": 1}, "absent": others("unsupported_cell")})
    return out
