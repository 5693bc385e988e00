"""Corpus cases for polyhedra (VTK type 42, face streams in CELLS) in the connectivity and shell checks:
two unit cubes side by side given as polyhedra with outward faces."""
from make_broken import vtk_legacy

PTS = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1, 2)]  # id = x + 3 y + 6 z


def pid(x, y, z):
    return x + 3 * y + 6 * z


def cube_faces(i):
    """Outward quads of the cube [i, i+1] x [0, 1] x [0, 1] (VTK hexahedron face order)."""
    c = [pid(i, 0, 0), pid(i + 1, 0, 0), pid(i + 1, 1, 0), pid(i, 1, 0),
         pid(i, 0, 1), pid(i + 1, 0, 1), pid(i + 1, 1, 1), pid(i, 1, 1)]
    local = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    return [[c[k] for k in f] for f in local]


def stream(faces):
    out = [len(faces)]
    for f in faces:
        out += [len(f)] + list(f)
    return out


def cases():
    a, b = cube_faces(0), cube_faces(1)
    clean = [(42, stream(a)), (42, stream(b))]
    out = [{"name": "poly_clean_two_cubes", "text": vtk_legacy(PTS, clean), "expect": {},
            "absent": ["nonmanifold_face", "inconsistent_orientation", "folded_face", "nonconforming_face",
                       "nonmanifold_edge", "shell_orientation", "components"]}]
    # The second cube's face on x = 1 given inward: the shared face is traversed the same way by both.
    b_bad = [list(reversed(f)) if f == b[5] else f for f in b]
    out.append({"name": "poly_shared_face_inward", "text": vtk_legacy(PTS, [(42, stream(a)), (42, stream(b_bad))]),
                "expect": {"inconsistent_orientation": 1}})
    # A polyhedron next to a hexahedron on the same shared face: conforming, one component.
    hexa = [pid(1, 0, 0), pid(2, 0, 0), pid(2, 1, 0), pid(1, 1, 0),
            pid(1, 0, 1), pid(2, 0, 1), pid(2, 1, 1), pid(1, 1, 1)]
    out.append({"name": "poly_next_to_hexahedron", "text": vtk_legacy(PTS, [(42, stream(a)), (12, hexa)]),
                "expect": {}, "absent": ["nonconforming_face", "components", "inconsistent_orientation"]})
    # A polyhedron with the four faces of a tet on the corners of the first cube's bottom square: every
    # point in the plane z = 0, no volume; convert refuses it (issue 10), so check must not call it clean.
    q0, q1, q2, q3 = pid(0, 0, 0), pid(1, 0, 0), pid(1, 1, 0), pid(0, 1, 0)
    flat = [[q0, q1, q2], [q0, q2, q3], [q0, q3, q1], [q1, q3, q2]]
    out.append({"name": "poly_flat", "text": vtk_legacy(PTS, [(42, stream(flat))]),
                "expect": {"flat_polyhedron": 1}, "absent": ["no_volume_cells"]})
    # Points and no cell at all: nothing to convert.
    out.append({"name": "no_volume_cells", "text": vtk_legacy(PTS, []), "expect": {"no_volume_cells": 1},
                "absent": ["flat_polyhedron"]})
    return out
