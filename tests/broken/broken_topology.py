"""Corpus cases for the connectivity (3xx) and shell (4xx) checks. Each broken case has an exact count
that follows from its construction (see the comments); near misses must not fire."""
from make_broken import vtk_legacy

CUBE = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
KUHN = [(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)]
# A positive tet and the point below its face (0, 1, 2).
TET = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TOPO_ERRORS = ["nonmanifold_face", "inconsistent_orientation", "nonconforming_face", "folded_face",
               "nonmanifold_edge", "nonmanifold_vertex", "shell_orientation", "open_shell",
               "shell_self_intersection"]


def tets(ids):
    return [(10, list(t)) for t in ids]


def hexes(ids):
    return [(12, list(h)) for h in ids]


def grid_points(nx, ny, nz, origin=(0, 0, 0), step=1.0):
    """Points of an (nx+1) x (ny+1) x (nz+1) lattice, x fastest, and a function (i, j, k) -> id."""
    pts = [(origin[0] + i * step, origin[1] + j * step, origin[2] + k * step)
           for k in range(nz + 1) for j in range(ny + 1) for i in range(nx + 1)]

    def pid(i, j, k):
        return (k * (ny + 1) + j) * (nx + 1) + i
    return pts, pid


def hex_at(pid, i, j, k, offset=0):
    c = [pid(i, j, k), pid(i + 1, j, k), pid(i + 1, j + 1, k), pid(i, j + 1, k),
         pid(i, j, k + 1), pid(i + 1, j, k + 1), pid(i + 1, j + 1, k + 1), pid(i, j + 1, k + 1)]
    return [v + offset for v in c]


def without(names, *keep):
    return [n for n in names if n not in keep]


def clean_cases():
    out = []
    out.append({"name": "topo_clean_cube", "text": vtk_legacy(CUBE, tets(KUHN)), "expect": {},
                "absent": TOPO_ERRORS + ["components", "euler_characteristic"]})
    # Two wedges (a cube cut along the diagonal plane through 0-2 and 4-6) and six pyramids (a cube
    # from its centre): wrong face tables would show as inconsistent orientation or an open shell.
    wedges = [(13, [0, 1, 2, 4, 5, 6]), (13, [0, 2, 3, 4, 6, 7])]
    out.append({"name": "topo_clean_wedges", "text": vtk_legacy(CUBE, wedges), "expect": {},
                "absent": TOPO_ERRORS + ["components", "euler_characteristic"]})
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    pyramids = [(14, list(reversed(f)) + [8]) for f in faces]  # VTK: the base turns towards the apex
    out.append({"name": "topo_clean_pyramids", "text": vtk_legacy(CUBE + [(0.5, 0.5, 0.5)], pyramids),
                "expect": {}, "absent": TOPO_ERRORS + ["components", "euler_characteristic"]})
    # Two voxels side by side (x fastest, then y, then z).
    pts, pid = grid_points(2, 1, 1)
    voxels = [(11, [pid(i, 0, 0), pid(i + 1, 0, 0), pid(i, 1, 0), pid(i + 1, 1, 0),
                    pid(i, 0, 1), pid(i + 1, 0, 1), pid(i, 1, 1), pid(i + 1, 1, 1)]) for i in range(2)]
    out.append({"name": "topo_clean_voxels", "text": vtk_legacy(pts, voxels), "expect": {},
                "absent": TOPO_ERRORS + ["components", "euler_characteristic"]})
    # A valid non-convex shell: an L of three hexes (concave edge, nothing wrong).
    pts, pid = grid_points(2, 2, 1)
    ell = [hex_at(pid, 0, 0, 0), hex_at(pid, 1, 0, 0), hex_at(pid, 0, 1, 0)]
    out.append({"name": "topo_nonconvex_shell", "text": vtk_legacy(pts, hexes(ell)), "expect": {},
                "absent": TOPO_ERRORS + ["components", "euler_characteristic"]})
    # A square ring of 8 hexes around a hole: a closed torus, V - E + F = 0, reported as info only.
    pts, pid = grid_points(3, 3, 1)
    ring = [hex_at(pid, i, j, 0) for j in range(3) for i in range(3) if (i, j) != (1, 1)]
    out.append({"name": "topo_torus_info_only", "text": vtk_legacy(pts, hexes(ring)),
                "expect": {"euler_characteristic": 1}, "absent": TOPO_ERRORS + ["components"], "exit": 0})
    return out


def face_cases():
    out = []
    # The second tet of two sharing face (1, 2, 3) is given in mirrored order (same place): one
    # inconsistent face; on the shell the three edges of that face are traversed the same way by
    # the two tets' faces. Geometrically they are on opposite sides: no fold.
    pts = TET + [(1, 1, 1)]
    out.append({"name": "topo_inconsistent_orientation", "text": vtk_legacy(pts, tets([(0, 1, 2, 3), (1, 2, 4, 3)])),
                "expect": {"inconsistent_orientation": 1, "shell_orientation": 3},
                "absent": ["folded_face", "nonmanifold_face", "nonconforming_face", "open_shell"]})
    # Near miss: the same two tets, both in consistent (positive) order.
    out.append({"name": "topo_consistent_neighbours", "text": vtk_legacy(pts, tets([(0, 1, 2, 3), (1, 2, 3, 4)])),
                "expect": {}, "absent": TOPO_ERRORS})
    # A fold: the neighbour across (1, 2, 3) is consistent in order but its apex (0.1, 0.1, 0.1) lies
    # on the same side as tet 0's apex (0, 0, 0).
    pts = TET + [(0.1, 0.1, 0.1)]
    out.append({"name": "topo_folded_face", "text": vtk_legacy(pts, tets([(0, 1, 2, 3), (1, 2, 3, 4)])),
                "expect": {"folded_face": 1}, "absent": ["inconsistent_orientation", "nonmanifold_face"]})
    # Three tets on face (0, 1, 2): one non-manifold face; its three edges carry 3 shell faces each.
    pts = TET + [(0.2, 0.2, -1), (0.3, 0.1, -2)]
    out.append({"name": "topo_nonmanifold_face", "text": vtk_legacy(pts, tets([(0, 1, 2, 3), (0, 2, 1, 4), (0, 2, 1, 5)])),
                "expect": {"nonmanifold_face": 1, "nonmanifold_edge": 3}, "absent": ["open_shell"]})
    # A duplicated tet plus a third on one face: face (0, 1, 2) has 3 cells; the other three faces of
    # the duplicate pair are shared by two cells that traverse them the same way and lie on the same
    # side (3 inconsistent, 3 folded); what is left of the shell is the third tet's other faces, whose
    # edges along (0, 1, 2) have one shell face each: 3 open edges.
    pts = TET + [(0.2, 0.2, -1)]
    out.append({"name": "topo_duplicate_tet_open_shell",
                "text": vtk_legacy(pts, tets([(0, 1, 2, 3), (0, 1, 2, 3), (0, 2, 1, 4)])),
                "expect": {"nonmanifold_face": 1, "inconsistent_orientation": 3, "folded_face": 3, "open_shell": 3}})
    return out


def nonconforming_cases():
    out = []
    # Hanging nodes: a 2x2x2 hex at x in [0, 2] against four unit hexes at x in [-1, 0]: the big face
    # and the four small ones lie against each other (5 faces). The two closed surfaces (big hex, block
    # of four) meet at the big face's 4 corners: 4 non-manifold vertices. Joined: one component.
    fine, fid = grid_points(1, 2, 2, origin=(-1, 0, 0))
    coarse_ids = {}
    pts = list(fine)
    for k in (0, 2):
        for j in (0, 2):
            coarse_ids[(j, k)] = fid(1, j, k)  # the shared corners at x = 0
    for k in (0, 2):
        for j in (0, 2):
            pts.append((2.0, float(j), float(k)))
            coarse_ids[("far", j, k)] = len(pts) - 1
    big = [coarse_ids[(0, 0)], coarse_ids[("far", 0, 0)], coarse_ids[("far", 2, 0)], coarse_ids[(2, 0)],
           coarse_ids[(0, 2)], coarse_ids[("far", 0, 2)], coarse_ids[("far", 2, 2)], coarse_ids[(2, 2)]]
    small = [hex_at(fid, 0, j, k) for k in range(2) for j in range(2)]
    out.append({"name": "topo_hanging_nodes", "text": vtk_legacy(pts, hexes([big] + small)),
                # components: face-connected, as checkMesh's regions (the big hex and the small ones)
                "expect": {"nonconforming_face": 5, "nonmanifold_vertex": 4, "components": 2},
                "absent": without(TOPO_ERRORS, "nonconforming_face", "nonmanifold_vertex")})
    # A quad against two triangles: a hex at x in [0, 1] and the cube x in [1, 2] as six Kuhn tets,
    # sharing the 4 corner ids of the face x = 1. Quad + 2 triangles lie against each other (3 faces);
    # the face's 4 outline edges carry 4 shell faces each (the quad, the hex's side, a triangle, a tet's
    # side). The same with the other diagonal.
    pts, pid = grid_points(2, 1, 1)
    hexa = hex_at(pid, 0, 0, 0)
    c = hex_at(pid, 1, 0, 0)  # corners of the second cube in hex order
    for name, diagonal in (("topo_quad_two_triangles", (0, 6)), ("topo_quad_two_triangles_other_diagonal", (3, 5))):
        a, b = diagonal
        # Kuhn-like split around the main diagonal c[a] -> c[b] (corner order of a hex)
        if diagonal == (0, 6):
            kuhn = [(c[0], c[1], c[2], c[6]), (c[0], c[2], c[3], c[6]), (c[0], c[3], c[7], c[6]),
                    (c[0], c[7], c[4], c[6]), (c[0], c[4], c[5], c[6]), (c[0], c[5], c[1], c[6])]
        else:
            kuhn = [(c[3], c[0], c[1], c[5]), (c[3], c[1], c[2], c[5]), (c[3], c[2], c[6], c[5]),
                    (c[3], c[6], c[7], c[5]), (c[3], c[7], c[4], c[5]), (c[3], c[4], c[0], c[5])]
        cells = [(12, hexa)] + [(10, list(t)) for t in kuhn]
        out.append({"name": name, "text": vtk_legacy(pts, cells),
                    "expect": {"nonconforming_face": 3, "nonmanifold_edge": 4, "components": 2},
                    "absent": ["nonmanifold_vertex", "shell_self_intersection", "open_shell"]})
    # Near miss: two tets whose faces on z = 0 touch along the shared edge (0, 1) only, facing
    # opposite ways (one above, one below): not nonconforming; the edge has 4 shell faces.
    pts = [(0, 0, 0), (0, 1, 0), (-1, 0.5, 0), (-0.5, 0.5, 1), (1, 0.5, 0), (0.5, 0.5, -1)]
    out.append({"name": "topo_faces_touch_at_edge", "text": vtk_legacy(pts, tets([(0, 2, 1, 3), (0, 1, 4, 5)])),
                "expect": {"nonmanifold_edge": 1, "components": 2},
                "absent": ["nonconforming_face", "shell_self_intersection", "nonmanifold_vertex"]})
    return out


def shell_cases():
    out = []
    # Two cubes (6 tets each) touching at one corner: one non-manifold vertex, two components.
    pts = CUBE + [(x + 1, y + 1, z + 1) for x, y, z in CUBE[1:]]
    second = [tuple(6 if v == 0 else v + 7 for v in t) for t in KUHN]
    out.append({"name": "topo_touch_at_vertex", "text": vtk_legacy(pts, tets(KUHN + second)),
                "expect": {"nonmanifold_vertex": 1, "components": 2},
                "absent": ["nonmanifold_edge", "nonconforming_face", "shell_self_intersection", "open_shell"]})
    # A tet poking through the face (1, 2, 3) of another, sharing no vertex: its apex is inside, its
    # base outside, so its three side faces each cross that face: 3 intersecting pairs.
    pts = TET + [(0.3, 0.3, 0.3), (0.9, 0.2, 0.2), (0.2, 0.9, 0.2), (0.2, 0.2, 0.9)]
    poke = [(0, 1, 2, 3), (4, 5, 6, 7)]  # both positively oriented
    out.append({"name": "topo_self_intersection", "text": vtk_legacy(pts, tets(poke)),
                "expect": {"shell_self_intersection": 3, "components": 2},
                "absent": ["nonconforming_face", "nonmanifold_vertex", "nonmanifold_edge"]})
    out.append({"name": "topo_self_intersection_skipped", "text": vtk_legacy(pts, tets(poke)),
                "args": ["--no-self-intersections"], "expect": {"components": 2},
                "absent": ["shell_self_intersection", "nonconforming_face"], "exit": 0})
    # Near miss: the same small tet moved just outside (apex at x + y + z = 1.05 > 1).
    pts_out = TET + [(0.4, 0.35, 0.3), (1.2, 0.5, 0.4), (0.5, 1.2, 0.4), (0.5, 0.5, 1.2)]
    out.append({"name": "topo_separate_tets", "text": vtk_legacy(pts_out, tets(poke)),
                "expect": {"components": 2}, "absent": TOPO_ERRORS, "exit": 0})
    return out


def cases():
    return clean_cases() + face_cases() + nonconforming_cases() + shell_cases()
