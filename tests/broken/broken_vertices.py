"""Corpus cases for the vertex checks (1xx). A unit cube split into 6 tets is the base mesh."""
import math

from make_broken import vtk_legacy

CUBE = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
# Kuhn split of the cube along the diagonal 0-6: six positively oriented tets.
KUHN = [(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)]


def tets(ids):
    return [(10, list(t)) for t in ids]


def cases():
    out = []
    out.append({"name": "vertices_clean_cube", "text": vtk_legacy(CUBE, tets(KUHN)), "expect": {},
                "absent": ["duplicate_vertex", "near_duplicate_vertex", "unused_vertex"]})
    # NaN coordinate on a used vertex.
    pts = list(CUBE)
    pts[5] = (1, float("nan"), 1)
    out.append({"name": "vertices_nan", "text": vtk_legacy(pts, tets(KUHN)).replace("nan", "nan"),
                "expect": {"nonfinite_vertex": 1}})
    # Two unused vertices: one far away, one exact duplicate of vertex 6 (also a duplicate).
    pts = list(CUBE) + [(5, 5, 5), (1, 1, 1)]
    out.append({"name": "vertices_unused_and_duplicate", "text": vtk_legacy(pts, tets(KUHN)),
                "expect": {"unused_vertex": 2, "duplicate_vertex": 1}, "absent": ["near_duplicate_vertex"],
                "exit": 0})
    # A near duplicate 1e-12 away (relative to a diagonal of sqrt 3): found with the default tol 1e-9,
    # not with --tol 1e-13; a point 1e-6 away is a near miss for the default.
    pts = list(CUBE) + [(1 + 1e-12, 1, 1), (0, 0, 1e-6)]
    out.append({"name": "vertices_near_duplicate", "text": vtk_legacy(pts, tets(KUHN)),
                "expect": {"near_duplicate_vertex": 1, "unused_vertex": 2}, "absent": ["duplicate_vertex"],
                "exit": 0})
    out.append({"name": "vertices_near_duplicate_tight_tol", "text": vtk_legacy(pts, tets(KUHN)),
                "args": ["--tol", "1e-13"], "expect": {"unused_vertex": 2},
                "absent": ["duplicate_vertex", "near_duplicate_vertex"], "exit": 0})
    # Coordinates at a huge offset: points 1 ulp apart are distinct, not exact duplicates.
    base = 6.5e6
    step = math.ulp(base)
    pts = [(base + x, base + y, z) for x, y, z in CUBE] + [(base + 1 + step, base + 1, 1)]
    out.append({"name": "vertices_offset_ulp_apart", "text": vtk_legacy(pts, tets(KUHN)),
                "args": ["--tol", "0"], "expect": {"unused_vertex": 1},
                "absent": ["duplicate_vertex", "near_duplicate_vertex"], "exit": 0})
    # 2000 random points in the cube, each with a twin 0.4 * tol * diagonal away in a random direction
    # (tol 1e-3: about 1.5% of the pairs straddle a side of the ~1-point grid cells; without the
    # neighbour-cell search 32 twins are missed), and every twin must be found; twins 2.5 * tol away
    # must not be.
    import random
    rng = random.Random(12345)
    tol = 1e-3
    reach = tol * math.sqrt(3)
    near, far = list(CUBE), list(CUBE)
    for _ in range(2000):
        p = [rng.uniform(0.01, 0.99) for _ in range(3)]
        d = [rng.gauss(0, 1) for _ in range(3)]
        norm = math.sqrt(sum(x * x for x in d))
        near += [tuple(p), tuple(p[k] + 0.4 * reach * d[k] / norm for k in range(3))]
        far += [tuple(p), tuple(p[k] + 2.5 * reach * d[k] / norm for k in range(3))]
    out.append({"name": "vertices_near_twins", "text": vtk_legacy(near, tets(KUHN)), "args": ["--tol", "1e-3"],
                "expect": {"near_duplicate_vertex": 2000, "unused_vertex": 4000}, "exit": 0})
    out.append({"name": "vertices_far_twins", "text": vtk_legacy(far, tets(KUHN)), "args": ["--tol", "1e-3"],
                "expect": {"unused_vertex": 4000}, "absent": ["near_duplicate_vertex", "duplicate_vertex"],
                "exit": 0})
    return out
