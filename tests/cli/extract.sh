# tetpack extract: the output keeps one layout, one field and its steps, and the tets that meet the clip
# box; it passes tetpack check, its shell is closed, TMAP/VMAP map into the source (extract_check.py), and
# rendered with the scene extract saves it gives the full file's picture with the same clip box
# (PSNR >= 40 dB, psnr.py). On the bundled sample and on two real meshes of the data corpus.
source "$(dirname "$0")/common.sh"
HERE="$(dirname "$0")"

# check_clean FILE: tetpack check finds nothing at all (exit 0, "no problems found").
check_clean() {
    "$TPK" check "$1" --no-progress > "$WORK/check.txt" 2>&1 || { cat "$WORK/check.txt" >&2; fail "tetpack check $1 found problems"; }
    grep -q "no problems found" "$WORK/check.txt" || fail "tetpack check $1: $(cat "$WORK/check.txt")"
}
# same_picture FULL.tpk SMALL.tpk SCENE SMALL_SCENE [render options...]: PSNR >= 40 dB.
same_picture() {
    local full=$1 small=$2 scene=$3 small_scene=$4
    shift 4
    "$TPK" render "$full" -o "$WORK/full.png" --scene "$scene" "$@" > /dev/null
    "$TPK" render "$small" -o "$WORK/small.png" --scene "$small_scene" > /dev/null
    "$PY" "$HERE/psnr.py" --min 40 "$WORK/full.png" "$WORK/small.png" > "$WORK/psnr.txt" ||
        fail "$small renders another picture than $full: $(cat "$WORK/psnr.txt")"
    echo "  $small vs $full: $(cat "$WORK/psnr.txt")"
}

# The bundled sample, three layouts in, one out; the box cuts the cylinder across its axis.
convert_checked "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpk" --layout tet16 --layout tet20 --layout tet32 > /dev/null
check_clean "$WORK/cyl.tpk"
BOX=0.03,-1,-1,0.07,1,1
printf '{"clip_box": [0.03, -1, -1, 0.07, 1, 1], "size": [64, 64], "layout": "tet32", "effects": {"shading": true}}' \
    > "$WORK/cyl.json"
"$TPK" extract "$WORK/cyl.tpk" "$WORK/cyl_small.tpk" --scene "$WORK/cyl.json" --save-scene "$WORK/cyl_small.json" \
    --json > "$WORK/report.json"
check_6xx "$WORK/cyl_small.tpk"
check_clean "$WORK/cyl_small.tpk"
"$PY" "$HERE/extract_check.py" "$WORK/cyl.tpk" "$WORK/cyl_small.tpk" "$BOX"
"$PY" - "$WORK/report.json" <<'PYEOF' || fail "extract --json report: $(cat "$WORK/report.json")"
import json, os, sys
r = json.load(open(sys.argv[1]))
assert r["bytes_after"] == os.path.getsize(r["output"]) < r["bytes_before"] == os.path.getsize(r["input"])
assert r["tets_after"] < r["tets_before"] and r["layout"] == 32 and r["field"] == "temperature" and r["steps"] == 1
after = [c["tag"] for c in r["chunks_after"]]
assert after == ["POS3", "TT32", "SHEL", "FDSC", "FDAT", "TMAP", "VMAP", "META"], after
assert sum(c["stored"] for c in r["chunks_after"]) < r["bytes_after"]
assert [c["tag"] for c in r["chunks_before"]].count("TT16") == 1
PYEOF
same_picture "$WORK/cyl.tpk" "$WORK/cyl_small.tpk" "$WORK/cyl.json" "$WORK/cyl_small.json"

# Without a box: one layout, every tet; the layout's records are the source's, byte for byte.
"$TPK" extract "$WORK/cyl.tpk" "$WORK/cyl_tet20.tpk" --layout tet20 > "$WORK/out.txt"
grep -q "1348 of 1348 tets" "$WORK/out.txt" || fail "extract without a box: $(cat "$WORK/out.txt")"
check_clean "$WORK/cyl_tet20.tpk"
"$PY" - "$HERE" "$WORK/cyl.tpk" "$WORK/cyl_tet20.tpk" <<'PYEOF' || fail "extract without a box: records differ from the source's"
import sys
sys.path.insert(0, sys.argv[1])
import extract_check
a, b = extract_check.load(sys.argv[2])[1], extract_check.load(sys.argv[3])[1]
assert a[("TT20", 0, 0)] == b[("TT20", 0, 0)] and a[("POS3", 0, 0)] == b[("POS3", 0, 0)]
assert ("TT16", 0, 0) not in b and ("TT32", 0, 0) not in b
# The same shell faces; rotation and order are the writer's choice (spec 6.6), and extract starts from
# the vertex order the walk of a Tet20 file recovers, not the converter's.
def faces(raw):
    r = extract_check.ints(raw)
    out = set()
    for f in range(len(r) // 4):
        a, b, c, t = r[4 * f:4 * f + 4]
        k = min(range(3), key=lambda i: (a, b, c)[i])
        out.add(((a, b, c) * 2)[k:k + 3] + (t,))
    return out
assert faces(a[("SHEL", 0, 0)]) == faces(b[("SHEL", 0, 0)])
PYEOF

# A real hex mesh split into tets, eight point fields of five steps: keep one field, steps 2..4, zstd.
convert_checked "$DATA/seacas/exomerge_unit_test.e" "$WORK/exo.tpk" --layout tet16 --layout tet32 > /dev/null
cat > "$WORK/exo.json" <<'JSON'
{"field": "residual_z", "steps": [2, 4], "clip_box": [0.2, 0.1, -1, 0.75, 0.8, 0.6], "layout": "tet32",
 "size": [64, 64], "tf": {"preset": "cool-warm"}}
JSON
"$TPK" extract "$WORK/exo.tpk" "$WORK/exo_small.tpk" --scene "$WORK/exo.json" --save-scene "$WORK/exo_small.json" \
    --zstd 3 > "$WORK/out.txt"
grep -q "field residual_z" "$WORK/out.txt" || fail "exo extract: $(cat "$WORK/out.txt")"
check_6xx "$WORK/exo_small.tpk"
"$TPK" info "$WORK/exo_small.tpk" > "$WORK/info.txt"
grep -q "residual_z *point 3 step(s)" "$WORK/info.txt" || fail "exo extract kept: $(cat "$WORK/info.txt")"
grep -q "disp_x" "$WORK/info.txt" && fail "exo extract kept a field the scene does not show"
grep -q "zstd" "$WORK/info.txt" || fail "--zstd 3 wrote no zstd chunk"
"$PY" "$HERE/extract_check.py" "$WORK/exo.tpk" "$WORK/exo_small.tpk" 0.2,0.1,-1,0.75,0.8,0.6
# The source's own findings (duplicate points between blocks: 102, 303, 406; the blocks, face-connected apart,
# as 304) and no other.
"$TPK" check "$WORK/exo_small.tpk" --no-progress > "$WORK/check.txt" || true
grep -E '^  [0-9]{3} ' "$WORK/check.txt" | grep -vE '^  (102|303|304|406) ' && fail "exo extract: a new finding"
for s in 2 4; do
    sed "s/\"steps\":[^]]*]/\"step\": $((s - 2))/" "$WORK/exo_small.json" > "$WORK/exo_small_step.json"
    same_picture "$WORK/exo.tpk" "$WORK/exo_small.tpk" "$WORK/exo.json" "$WORK/exo_small_step.json" --step $s
done

# A per-tet field (a cell field of the same file): its values follow the kept tets (each tet of a source
# cell holds the cell's value, so TMAP says which value each kept tet must have), steps 1..3 of 5.
convert_checked "$DATA/seacas/exomerge_unit_test.e" "$WORK/exo_tet.tpk" --field disp_z --field vm_stress \
    --layout tet20 > /dev/null
"$TPK" extract "$WORK/exo_tet.tpk" "$WORK/exo_tet_small.tpk" --field vm_stress --steps 1:3 \
    --clip-box 0,0,0,0.5,0.5,0.5 > /dev/null
check_6xx "$WORK/exo_tet_small.tpk"
"$PY" - "$HERE" "$WORK/exo_tet.tpk" "$WORK/exo_tet_small.tpk" <<'PYEOF' || fail "the per-tet field's values do not follow the tets"
import struct, sys
sys.path.insert(0, sys.argv[1])
import extract_check
(hs, cs), (he, ce) = extract_check.load(sys.argv[2]), extract_check.load(sys.argv[3])
names = [cs[("FDSC", 0, 0)][128 * i:128 * i + 64].rstrip(b"\0").decode() for i in range(len(cs[("FDSC", 0, 0)]) // 128)]
f = names.index("vm_stress")
assert len(ce[("FDSC", 0, 0)]) == 128 and ce[("FDSC", 0, 0)][:9] == b"vm_stress" and ("FDAT", 0, 3) not in ce
tmap_s, tmap_e = extract_check.ints(cs[("TMAP", 0, 0)]), extract_check.ints(ce[("TMAP", 0, 0)])
for step in range(3):
    src = struct.unpack("<%df" % hs["tet_count"], cs[("FDAT", f, step + 1)])
    out = struct.unpack("<%df" % he["tet_count"], ce[("FDAT", 0, step)])
    by_cell = {tmap_s[t]: v for t, v in enumerate(src)}
    assert all(by_cell[tmap_e[t]] == v for t, v in enumerate(out)), step
PYEOF

# A real tet mesh (no field: constant density), Tet20, a box across the elbow given as an option over a
# scene that has none.
convert_checked "$DATA/sfepy/elbow.mesh" "$WORK/elbow.tpk" --layout tet20 > /dev/null
printf '{"size": [64, 64], "effects": {"shading": true}}' > "$WORK/elbow_view.json"
"$TPK" extract "$WORK/elbow.tpk" "$WORK/elbow_small.tpk" --scene "$WORK/elbow_view.json" \
    --clip-box 0.05,-1,-1,0.3,0.1,0.02 --save-scene "$WORK/elbow_small.json" > /dev/null
check_clean "$WORK/elbow_small.tpk"
"$PY" "$HERE/extract_check.py" "$WORK/elbow.tpk" "$WORK/elbow_small.tpk"
printf '{"clip_box": [0.05, -1, -1, 0.3, 0.1, 0.02], "size": [64, 64], "effects": {"shading": true}}' > "$WORK/elbow.json"
same_picture "$WORK/elbow.tpk" "$WORK/elbow_small.tpk" "$WORK/elbow.json" "$WORK/elbow_small.json"

# Cut folds (a gmsh boundary-layer mesh converted with --cut-folds): connect on the kept tets would pair
# the two faces of a fold again; the exact fold test cuts them again, so the whole mesh extracted keeps
# every shell face, and a half passes the 6xx checks.
gmsh -3 -nt 1 "$SRC/tests/cli/sphere_bl.geo" -format vtk -o "$WORK/bl.vtk" > "$WORK/gmsh.log" 2>&1 ||
    { tail "$WORK/gmsh.log"; fail "gmsh failed"; }
convert_checked "$WORK/bl.vtk" "$WORK/bl.tpk" --cut-folds > /dev/null 2>&1
"$TPK" extract "$WORK/bl.tpk" "$WORK/bl_all.tpk" --json > "$WORK/bl.json"
check_6xx "$WORK/bl_all.tpk"
"$PY" -c "
import json; r = json.load(open('$WORK/bl.json'))
assert r['tets_after'] == r['tets_before'] and r['shell_faces_after'] == r['shell_faces_before'] > 0, r" ||
    fail "extract of a file with cut folds changed its shell: $(cat "$WORK/bl.json")"
"$TPK" extract "$WORK/bl.tpk" "$WORK/bl_half.tpk" --clip-box -10,-10,-10,0,10,10 > /dev/null
check_6xx "$WORK/bl_half.tpk"
"$PY" "$HERE/extract_check.py" "$WORK/bl.tpk" "$WORK/bl_half.tpk"

# Refusals: exit 2 with the reason; nothing written.
expect_exit 2 "$TPK" extract "$WORK/cyl.tpk" "$WORK/none.tpk" --clip-box 5,5,5,6,6,6
expect_stderr "no tet meets the clip box"
expect_exit 2 "$TPK" extract "$WORK/cyl.tpk" "$WORK/none.tpk" --field pressure
expect_stderr "no field named 'pressure'"
expect_exit 2 "$TPK" extract "$WORK/cyl.tpk" "$WORK/none.tpk" --steps 0:3
expect_stderr "field 'temperature' has steps 0..0; steps 0..3 asked"
expect_exit 2 "$TPK" extract "$WORK/elbow.tpk" "$WORK/none.tpk" --steps 1:2
expect_stderr "steps 1..2 asked, but the file has no point field"
expect_exit 2 "$TPK" extract "$WORK/cyl_tet20.tpk" "$WORK/none.tpk" --layout tet16
expect_stderr "no Tet16 layout in the file"
expect_exit 2 "$TPK" extract "$WORK/cyl.tpk" "$WORK/cyl.tpk"
[ ! -e "$WORK/none.tpk" ] || fail "a refused extract left a file"
echo "extract: ok"
