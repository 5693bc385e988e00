# tetpack export --shell OUT.{ply,obj,off,stl}: the format from the extension (OBJ/OFF/STL by OpenMesh's
# writers). Every file is read back (OBJ/OFF/STL by meshio; PLY by numpy, as meshio cannot read a list
# property followed by another face property). The PLY is compared with the boundary of the tets that
# --vtu exports, computed here: the same faces, float64 positions of mesh points, every face outward (its
# tet's fourth vertex behind it); OBJ/OFF/STL with the PLY: the same faces and corners in the same order,
# at float32 (OpenMesh's writers round positions to float32 whatever the mesh holds). Every shell
# encloses a positive volume.
source "$(dirname "$0")/common.sh"

check_shells() { # check_shells NAME: NAME.tpk exported and checked in every format
    local name=$1
    "$TPK" export "$WORK/$name.tpk" --vtu "$WORK/$name.vtu"
    for ext in ply obj off stl; do
        "$TPK" export "$WORK/$name.tpk" --shell "$WORK/$name.$ext" 2> "$WORK/err" || { cat "$WORK/err"; fail "export $name.$ext"; }
    done
    "$PY" - "$WORK/$name" <<'EOF' || fail "shells of $1"
import sys, collections, meshio, numpy as np
base = sys.argv[1]
vol = meshio.read(base + ".vtu")
points, tets = vol.points, vol.cells_dict["tetra"]
faces_of = collections.defaultdict(list)  # sorted face -> (tet, opposite vertex)
for t, tet in enumerate(tets):
    for k in range(4):
        face = tuple(sorted(np.delete(tet, k)))
        faces_of[face].append(tet[k])
boundary = {f: opp[0] for f, opp in faces_of.items() if len(opp) == 1}

def read_ply(path):
    data = open(path, "rb").read()
    head, body = data.split(b"end_header\n", 1)
    nv = int(head.split(b"element vertex ")[1].split()[0]); nf = int(head.split(b"element face ")[1].split()[0])
    xyz = np.frombuffer(body, "<f8", 3 * nv).reshape(nv, 3)
    rec = np.frombuffer(body[24 * nv:], np.dtype([("n", "u1"), ("v", "<i4", 3), ("tet", "<i4")]), nf)
    assert (rec["n"] == 3).all()
    return xyz, rec["v"]

def volume(corners):  # enclosed volume, about the centre: 6.5e6 m coordinates would cancel every digit
    p = corners - corners.reshape(-1, 3).mean(axis=0)
    return np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6

# PLY against the tets: exactly the boundary faces, float64 positions of mesh points, each face outward.
xyz, tri = read_ply(base + ".ply")
id_of = {tuple(p): i for i, p in enumerate(points)}
assert len(tri) == len(boundary), ("ply", len(tri), len(boundary))
seen = set()
for f in tri:
    ids = [id_of[tuple(xyz[v])] for v in f]  # KeyError: a position that is not a mesh point
    face = tuple(sorted(ids))
    assert face in boundary and face not in seen, ("ply", face)
    seen.add(face)
    a, b, c = points[ids]
    assert np.dot(np.cross(b - a, c - a), points[boundary[face]] - a) < 0, ("ply: face not outward", face)
reference = xyz[tri]
assert volume(reference) > 0
print("ply", len(tri), "faces, volume", volume(reference))
# OBJ/OFF/STL through meshio: the same faces in the same order and corner order (so outward too), each
# corner at the float32 rounding of its PLY position.
for ext in ["obj", "off", "stl"]:
    m = meshio.read(base + "." + ext)
    corners = m.points[m.cells_dict["triangle"]]
    assert corners.shape == reference.shape, (ext, corners.shape, reference.shape)
    assert (corners.astype(np.float32) == reference.astype(np.float32)).all(), ext
    assert volume(corners) > 0, ext
    print(ext, len(corners), "faces, volume", volume(corners))
# Binary STL also stores a normal per face: outward, as the corner order says.
data = open(base + ".stl", "rb").read()
rec = np.frombuffer(data[84:], np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                    int.from_bytes(data[80:84], "little"))
v = rec["v"].astype(np.float64) - rec["v"].reshape(-1, 3).mean(axis=0)
normal = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
length = np.linalg.norm(normal, axis=1)
ok = length > 0  # far from the origin float32 can flatten a face; its normal then says nothing
assert (np.einsum("ij,ij->i", rec["n"][ok], normal[ok] / length[ok, None]) > 0.99).all(), "STL normals"
EOF
}

# Tets (sfepy's cylinder), hexahedra split into tets, and hexahedra 6.5e6 m from the origin (PLY keeps
# every digit of origin + float32 position; OBJ/OFF/STL get float32 world positions, with a warning).
convert_checked "$DATA/sfepy/cylinder.vtk" "$WORK/cyl.tpk" --quiet
check_shells cyl
convert_checked "$DATA/sfepy/cube_medium_hexa.mesh" "$WORK/hex.tpk" --quiet
check_shells hex
convert_checked "$DATA/hard/huge_offset_hex.vtu" "$WORK/far.tpk" --quiet
check_shells far
"$TPK" export "$WORK/far.tpk" --shell "$WORK/far2.off" 2> "$WORK/err"
expect_stderr "OpenMesh's off writer stores float32 positions: vertices move by up to"
"$TPK" export "$WORK/cyl.tpk" --shell "$WORK/cyl2.off" 2> "$WORK/err"
[ ! -s "$WORK/err" ] || { cat "$WORK/err"; fail "a warning for a mesh near the origin"; }

# Three cubes, one touching at a vertex, one along an edge: OpenMesh's halfedge mesh cannot share such a
# vertex or edge; every face is still written (on copies of its vertices), and the warning says so.
convert_checked "$DATA/hard/nonmanifold_vertex_edge_tets.vtu" "$WORK/nm.tpk" --quiet
"$TPK" export "$WORK/nm.tpk" --shell "$WORK/nm.obj" 2> "$WORK/err"
grep -q "the shell is not manifold: [0-9]* faces" "$WORK/err" || { cat "$WORK/err"; fail "no non-manifold warning"; }
faces=$("$TPK" info "$WORK/nm.tpk" --json | "$PY" -c "import json,sys; print(json.load(sys.stdin)['shell_faces'])")
"$PY" -c "import meshio; m=meshio.read('$WORK/nm.obj'); n=len(m.cells_dict['triangle']); assert n==$faces, n"

# Bad requests: refused by name, nothing left behind (no temporary files either).
expect_exit 2 "$TPK" export "$WORK/cyl.tpk" --shell "$WORK/cyl.xyz"
expect_stderr "unknown shell format '.xyz': the extension must be .ply, .obj, .off or .stl"
expect_exit 2 "$TPK" export "$WORK/cyl.tpk" --shell "$WORK/noext"
expect_exit 2 "$TPK" export "$WORK/cyl.tpk" --shell "$WORK/missing/dir/cyl.obj"
expect_stderr "missing/dir/cyl.obj"
[ -z "$(ls "$WORK" | grep -e tmp -e xyz -e noext)" ] || { ls "$WORK"; fail "stray files"; }
"$TPK" export "$WORK/cyl.tpk" --shell "$WORK/CYL.OBJ"
"$PY" -c "import meshio; assert len(meshio.read('$WORK/CYL.OBJ', file_format='obj').cells_dict['triangle'])==440"
"$TPK" export --help | grep -q "\.stl  binary" || fail "help lacks .stl"
echo "1 passed, 0 failed"
