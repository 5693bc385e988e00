# convert -> info --json -> render -> export VTU/PLY on the bundled sample and real meshes;
# the VTU is cross-checked with meshio (an independent reader).
source "$(dirname "$0")/common.sh"

convert_checked "$SRC/samples/cylinder.vtk" "$WORK/c.tpk" --layout tet16 --layout tet20 --layout tet32 --quiet
"$TPK" info "$WORK/c.tpk" --json > "$WORK/info.json"
"$PY" - "$WORK/info.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
for k in ["format_version", "vertices", "tets", "shell_faces", "layouts", "fields", "bounds", "origin", "chunks"]:
    assert k in d, k
assert d["format_version"] == "1.1"
assert d["tets"] == 1348 and d["vertices"] == 354, (d["tets"], d["vertices"])
assert sorted(d["layouts"]) == ["tet16", "tet20", "tet32"], d["layouts"]
assert [f["name"] for f in d["fields"]] == ["temperature"], d["fields"]
assert d["fields"][0]["association"] == "point" and d["fields"][0]["steps"] == 1
for c in d["chunks"]:
    assert set(["tag", "codec", "stored_bytes", "raw_bytes"]) <= set(c)
assert d["checksums_ok"] is True
PY

# The render is looked at, not only its exit code: decoded here (zlib and the PNG filters, no imaging
# library), it has the asked size, the background at the corners, the volume covering the middle; the
# three layouts and 1 or 2 threads give the same pixels (the marcher visits the same tets), and a camera
# looking away from the volume sees only background.
"$TPK" render "$WORK/c.tpk" -o "$WORK/c.png" --size 96x64 --layout tet16 > /dev/null
"$TPK" render "$WORK/c.tpk" -o "$WORK/c32.png" --size 96x64 --layout tet32 --threads 1 > /dev/null
"$TPK" render "$WORK/c.tpk" -o "$WORK/c20.png" --size 96x64 --layout tet20 --threads 2 > /dev/null
"$TPK" render "$WORK/c.tpk" -o "$WORK/away.png" --size 96x64 --camera 0,0,50,0,0,100,0,1,0,30 > /dev/null
"$PY" - "$(dirname "$0")" "$WORK/c.png" "$WORK/c32.png" "$WORK/c20.png" "$WORK/away.png" <<'PY'
import sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from png_read import pixels
img = pixels(sys.argv[2])[:, :, :3]
h, w = img.shape[:2]
assert (w, h) == (96, 64), (w, h)
bg = img[0, 0]
assert (img[0, -1] == bg).all() and (img[-1, 0] == bg).all() and (img[-1, -1] == bg).all(), "corners differ: not background"
assert (img[h // 2, w // 2] != bg).any(), "the middle of the image shows no volume"
covered = np.any(img != bg, axis=2).mean()
assert 0.1 < covered < 0.9, covered
assert len(np.unique(img.reshape(-1, 3), axis=0)) > 20, "too few colors for a shaded volume"
for other in sys.argv[3:5]:
    assert (pixels(other)[:, :, :3] == img).all(), other + " differs from the tet16 render"
assert (pixels(sys.argv[5])[:, :, :3] == bg).all(), "the camera looking away sees something"
PY

"$TPK" export "$WORK/c.tpk" --vtu "$WORK/c.vtu" --shell "$WORK/c.ply"
"$PY" - "$WORK/c.vtu" "$SRC/samples/cylinder.vtk" <<'PY'
import sys
import meshio, numpy as np
out = meshio.read(sys.argv[1])
src = meshio.read(sys.argv[2])
tets = out.cells_dict["tetra"]
assert len(tets) == 1348
# Same points up to the stored permutation (float32 positions relative to a float64 origin).
perm = out.point_data["source_point"]
assert np.allclose(out.points, src.points[perm], rtol=0, atol=1e-8), np.abs(out.points - src.points[perm]).max()
# (meshio reads legacy VTK scalars as n x 1 arrays)
assert np.allclose(out.point_data["temperature"], np.ravel(src.point_data["temperature"])[perm], atol=1e-4)
# Same tets (as vertex sets in source numbering), each positively oriented.
src_sets = sorted(tuple(sorted(t)) for t in src.cells_dict["tetra"])
out_sets = sorted(tuple(sorted(perm[t])) for t in tets)
assert src_sets == out_sets
p = out.points
d = np.einsum("ij,ij->i", np.cross(p[tets[:, 1]] - p[tets[:, 0]], p[tets[:, 2]] - p[tets[:, 0]]), p[tets[:, 3]] - p[tets[:, 0]])
assert (d > 0).all(), (d <= 0).sum()
# source_cell maps every tet back to a source cell with the same vertices.
sc = out.cell_data["source_cell"][0]
assert sorted(sc.tolist()) == list(range(1348))
assert all(tuple(sorted(src.cells_dict["tetra"][c])) == tuple(sorted(perm[t])) for c, t in zip(sc, tets))
PY
# The shell PLY, parsed here with numpy (meshio 5.0 misreads per-face scalar properties of binary PLY):
# one face per shell face, every face outward (the owning tet's 4th vertex lies behind it).
"$PY" - "$WORK/c.ply" "$WORK/info.json" "$WORK/c.vtu" <<'PY'
import sys, json
import meshio, numpy as np
data = open(sys.argv[1], "rb").read()
end = data.index(b"end_header\n") + len(b"end_header\n")
header = data[:end].decode().split("\n")
nv = int([l for l in header if l.startswith("element vertex")][0].split()[2])
nf = int([l for l in header if l.startswith("element face")][0].split()[2])
assert "property list uchar int vertex_indices" in header and "property int tet" in header
verts = np.frombuffer(data, dtype="<f8", count=3 * nv, offset=end).reshape(nv, 3)
faces = np.frombuffer(data, dtype=np.dtype([("n", "u1"), ("v", "<i4", 3), ("t", "<i4")]), count=nf, offset=end + 24 * nv)
assert len(data) == end + 24 * nv + 17 * nf
assert (faces["n"] == 3).all()
assert nf == json.load(open(sys.argv[2]))["shell_faces"], nf
vol = meshio.read(sys.argv[3])
tets = vol.cells_dict["tetra"]
for (a, b, c), t in zip(faces["v"], faces["t"]):
    pa, pb, pc = verts[a], verts[b], verts[c]
    normal = np.cross(pb - pa, pc - pa)
    centroid = vol.points[tets[t]].mean(axis=0)
    assert np.dot(normal, centroid - pa) < 0, "face not outward"
PY

# Real meshes: legacy binary VTK (gmsh, big-endian doubles) and TetGen.
convert_checked "$DATA/gmsh/t5_small_tet_bin.vtk" "$WORK/t5.tpk" --zstd 3 --quiet
"$TPK" info "$WORK/t5.tpk" > /dev/null
convert_checked "$DATA/tetgen/hinge_small.node" "$WORK/hinge.tpk" --layout tet20 --quiet
"$TPK" info "$WORK/hinge.tpk" --json | "$PY" -c "import json,sys; d=json.load(sys.stdin); assert d['tets']==14487, d['tets']"
# A hexahedral mesh with only cell data, rendered by its material averaged to points.
convert_checked "$DATA/sfepy/acoustic_wg.vtk" "$WORK/wg.tpk" --cell-to-point --quiet
"$TPK" info "$WORK/wg.tpk" --json | "$PY" -c "
import json, sys
d = json.load(sys.stdin)
f = {x['name']: x for x in d['fields']}
assert f['mat_id']['association'] == 'point' and (f['mat_id']['min'], f['mat_id']['max']) == (1, 2), f
assert d['tets'] == 6 * 1392, d['tets']"
"$TPK" render "$WORK/wg.tpk" -o "$WORK/wg.png" --field mat_id --size 64x48 > /dev/null
echo "1 passed, 0 failed"
