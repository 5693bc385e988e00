# tetpack iso: isosurfaces as PLY, OBJ and GLB on the sample and real meshes, against an independent
# marching-tets reference (tests/cli/iso_check.py: numpy on the tets and field that `export --vtu` writes):
# triangle and vertex counts per value, area within 1e-6, watertight inside with open edges only on shell
# faces, normals toward increasing field; PLY and OBJ read back by meshio with the same counts; the GLB's
# structure by the glTF 2.0 spec; byte-identical outputs for --threads 1 and 2; a sphere of a radial
# field on a generated grid against 4 pi r^2; and each refusal with its message.
source "$(dirname "$0")/common.sh"
CHECK="$SRC/tests/cli/iso_check.py"

counts() { "$PY" -c "import json,sys; r=json.load(open(sys.argv[1])); print(r['triangles'], r['vertices'])" "$1"; }

# iso_all NAME FILE.tpk FIELD VTU_FIELD VALUES [options]: every format at 1 and 2 threads, checked (VTU_FIELD:
# the field's name in export's VTU, NAME_tK for step K of a field of several steps).
iso_all() {
    local name=$1 tpk=$2 field=$3 vtu_field=$4 values=$5
    shift 5
    "$TPK" export "$tpk" --vtu "$WORK/$name.vtu" > /dev/null
    for ext in ply obj glb; do
        for th in 1 2; do
            "$TPK" iso "$tpk" "$WORK/$name.$th.$ext" --field "$field" --value "$values" --threads $th --json "$@" \
                > "$WORK/$name.$th.$ext.json" || fail "iso $name.$ext --threads $th"
        done
        cmp "$WORK/$name.1.$ext" "$WORK/$name.2.$ext" || fail "$name.$ext differs between --threads 1 and 2"
    done
    read -r ntri nvert < <(counts "$WORK/$name.1.ply.json")
    [ "$ntri" -gt 0 ] || fail "$name: empty surface"
    "$PY" "$CHECK" reference "$WORK/$name.vtu" "$vtu_field" "$values" "$WORK/$name.1.ply" "$WORK/$name.1.ply.json" \
        || fail "$name: against the reference"
    "$PY" "$CHECK" meshio "$WORK/$name.1.ply" "$ntri" "$nvert" || fail "$name.ply through meshio"
    "$PY" "$CHECK" meshio "$WORK/$name.1.obj" "$ntri" "$nvert" || fail "$name.obj through meshio"
    "$PY" "$CHECK" glb "$WORK/$name.1.glb" "$ntri" "$nvert" || fail "$name.glb structure"
}

# The bundled sample: three values of its temperature.
convert_checked "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpk" --quiet
iso_all cyl "$WORK/cyl.tpk" temperature temperature 300,330,360

# Exodus: a field at step 3, another carried as the color field.
convert_checked "$DATA/seacas/exomerge_unit_test.e" "$WORK/exo.tpk" --quiet
iso_all exo "$WORK/exo.tpk" residual_z residual_z_t3 -20,0.5,40 --step 3 --color-field mass
grep -q "property float color" "$WORK/exo.1.ply" || fail "exo.ply lacks the color property"
"$PY" - "$WORK/exo.1.glb" <<'PYEOF' || fail "exo.glb lacks _COLOR_FIELD or extras"
import json, struct, sys
d = open(sys.argv[1], "rb").read(); n = struct.unpack_from("<I", d, 12)[0]; j = json.loads(d[20:20 + n])
m = j["meshes"][0]
assert "_COLOR_FIELD" in m["primitives"][0]["attributes"], m
assert m["extras"]["field"] == "residual_z" and m["extras"]["step"] == 3 and m["extras"]["color_field"] == "mass"
PYEOF

# Far from the origin (6.5e6, 4.9e6, 1.2e3): the GLB's node carries the origin as its translation.
convert_checked "$DATA/hard/huge_offset_hex.vtu" "$WORK/off.tpk" --quiet
iso_all off "$WORK/off.tpk" z_local z_local 0.1
"$PY" - "$WORK/off.1.glb" <<'PYEOF' || fail "off.glb: no translation"
import json, struct, sys
d = open(sys.argv[1], "rb").read(); n = struct.unpack_from("<I", d, 12)[0]; j = json.loads(d[20:20 + n])
assert j["nodes"][0]["translation"] == [6500000, 4900000, 1200], j["nodes"]
PYEOF

# A real tet mesh with a field made here (distance from a point inside): surfaces that close inside
# the volume and surfaces cut by the shell.
"$PY" - "$DATA/sfepy/cube_cylinder.mesh" "$WORK/cc.vtu" <<'PYEOF'
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
c = 0.5 * (m.points.min(axis=0) + m.points.max(axis=0))
r = np.linalg.norm(m.points - c, axis=1) / np.linalg.norm(m.points.max(axis=0) - m.points.min(axis=0))
meshio.write(sys.argv[2], meshio.Mesh(m.points, [("tetra", m.cells_dict["tetra"])], point_data={"r": r}))
PYEOF
convert_checked "$WORK/cc.vtu" "$WORK/cc.tpk" --quiet
iso_all cc "$WORK/cc.tpk" r r 0.1,0.3,0.45

# A sphere of a radial field on a generated 32^3 grid of Kuhn tets: closed, outward, area and enclosed
# volume within 1% of 4 pi r^2 and 4/3 pi r^3 (linear interpolation cuts inside the sphere: -0.28% area, -0.54% volume measured).
"$PY" - "$WORK/ball.vtu" <<'PYEOF'
import sys, meshio, numpy as np
n = 32
g = np.linspace(-1, 1, n + 1)
x, y, z = np.meshgrid(g, g, g, indexing="ij")
pts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
base = ((i * (n + 1) + j) * (n + 1) + k).ravel()
c = [base + ((b >> 2) & 1) * (n + 1) ** 2 + ((b >> 1) & 1) * (n + 1) + (b & 1) for b in range(8)]
paths = [(0, 4, 6, 7), (0, 4, 5, 7), (0, 2, 6, 7), (0, 2, 3, 7), (0, 1, 5, 7), (0, 1, 3, 7)]
tets = np.stack([np.stack([c[a] for a in p], axis=1) for p in paths], axis=1).reshape(-1, 4)
meshio.write(sys.argv[1], meshio.Mesh(pts, [("tetra", tets)], point_data={"radius": np.linalg.norm(pts, axis=1)}))
PYEOF
convert_checked "$WORK/ball.vtu" "$WORK/ball.tpk" --quiet
"$TPK" iso "$WORK/ball.tpk" "$WORK/ball.ply" --value 0.6 > /dev/null
"$PY" "$CHECK" sphere "$WORK/ball.ply" 0.6 0.01 || fail "sphere"

# Refusals, exit 2 with the reason; a value outside the range: a warning and a valid empty file.
expect_exit 2 "$TPK" iso "$WORK/cyl.tpk" "$WORK/x.stl" --value 300
expect_stderr "unknown extension; expected .ply, .obj or .glb"
for bad in abc 1,,2 nan 1,inf ""; do
    expect_exit 2 "$TPK" iso "$WORK/cyl.tpk" "$WORK/x.ply" --value "$bad"
    expect_stderr "--value expects 1 to 64 finite numbers"
done
expect_exit 2 "$TPK" iso "$WORK/cyl.tpk" "$WORK/x.ply" --value 300 --field nope
expect_stderr "no field named 'nope'"
expect_exit 2 "$TPK" iso "$WORK/cyl.tpk" "$WORK/x.ply" --value 300 --step 1
expect_stderr "has steps 0..0; step 1 asked"
expect_exit 2 "$TPK" iso "$WORK/cyl.tpk" "$WORK/x.ply" --value 300 --color-field nope
expect_stderr "no field named 'nope'"
expect_exit 2 "$TPK" iso "$WORK/cyl.tpk" "$WORK/cyl.tpk" --value 300
expect_exit 2 "$TPK" iso "$WORK/cyl.tpk" "$WORK/x.ply"
expect_stderr "expected IN.tpk OUT.ply|.obj|.glb --value"
convert_checked "$DATA/sfepy/cylinder.vtk" "$WORK/mat.tpk" --field mat_id --quiet
expect_exit 2 "$TPK" iso "$WORK/mat.tpk" "$WORK/x.ply" --value 6 --field mat_id
expect_stderr "is a tet field"
expect_stderr "--cell-to-point"
[ ! -e "$WORK/x.ply" ] || fail "a refused run left x.ply"
for ext in ply obj glb; do
    expect_exit 0 "$TPK" iso "$WORK/cyl.tpk" "$WORK/empty.$ext" --value 1000
    expect_stderr "value 1000 is outside the range"
done
"$PY" "$CHECK" meshio "$WORK/empty.ply" 0 0 || fail "empty.ply"
"$PY" "$CHECK" glb "$WORK/empty.glb" 0 0 || fail "empty.glb"
"$TPK" --help | grep -q "^  iso " || fail "tetpack --help lacks iso"
"$TPK" iso --help | grep -q "normals point toward increasing field" || fail "iso --help"
echo "iso: ok"
