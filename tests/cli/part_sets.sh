#!/usr/bin/env bash
# convert --parts N (spec §15): on real meshes, the part set holds the tets of the single-file conversion
# (compared by their vertex positions), the same outer shell, every cut face linked both ways (check 614),
# and renders the same picture; a missing or replaced part makes the set unusable (exit 2).
source "$(dirname "$0")/common.sh" "$@"

one_case() { # input parts
    local input=$1 parts=$2 name
    name=$(basename "$input" | tr . _)_$parts
    mkdir -p "$WORK/$name"
    convert_checked "$input" "$WORK/$name/whole.tpk" --layout tet16 --layout tet32 > /dev/null
    "$TPK" convert "$input" "$WORK/$name/set.tpkset" --parts "$parts" --layout tet16 --layout tet32 > /dev/null
    local files=("$WORK/$name"/set-*.tpk)
    [ "${#files[@]}" -eq "$parts" ] || fail "$name: expected $parts part files, found ${#files[@]}"
    for f in "${files[@]}"; do check_6xx "$f"; done
    expect_exit 0 "$TPK" check "$WORK/$name/set.tpkset" --json --no-progress
    "$PY" - "$WORK/out" <<'PYEOF' || fail "$name: check on the set found problems"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["format"] == "tpkset" and not r["problems"] and not r["findings"], r
PYEOF
    "$TPK" info "$WORK/$name/set.tpkset" --json > "$WORK/$name/info.json"
    "$TPK" info "$WORK/$name/whole.tpk" --json > "$WORK/$name/whole.json"
    "$PY" - "$WORK/$name/info.json" "$WORK/$name/whole.json" "$parts" <<'PYEOF' || fail "$name: info totals"
import json, sys
s, w, n = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), int(sys.argv[3])
assert s["part_set"] and s["part_count"] == n and len(s["parts"]) == n, s
assert s["tets"] == w["tets"], (s["tets"], w["tets"])
assert s["shell_faces"] == w["shell_faces"], ("outer shell", s["shell_faces"], w["shell_faces"])
assert sum(p["cut_faces"] for p in s["parts"]) == 2 * s["cut_faces"]
assert (s["cut_faces"] > 0) == (n > 1)
sizes = [p["tets"] for p in s["parts"]]
assert max(sizes) - min(sizes) <= 1, sizes  # balanced by tets
PYEOF
    keys "$WORK/$name/whole.keys" "$WORK/$name/whole.tpk"
    keys "$WORK/$name/set.keys" "${files[@]}"
    cmp -s "$WORK/$name/whole.keys" "$WORK/$name/set.keys" ||
        fail "$name: the parts do not hold the tets and outer shell of the single file ($(head -1 "$WORK/$name/set.keys") vs $(head -1 "$WORK/$name/whole.keys"))"
    "$TPK" render "$WORK/$name/whole.tpk" -o "$WORK/$name/whole.png" --size 160x120 > /dev/null
    "$TPK" render "$WORK/$name/set.tpkset" -o "$WORK/$name/set.png" --size 160x120 > /dev/null
    cmp -s "$WORK/$name/whole.png" "$WORK/$name/set.png" || fail "$name: the set renders a different picture"
}

one_case "$SRC/samples/cylinder.vtk" 4
one_case "$DATA/sfepy/acoustic_wg.vtk" 3
one_case "$DATA/hard/huge_offset_hex.vtu" 5
one_case "$DATA/sfepy/cube_medium_tetra.mesh" 1

# The manifest binds its parts: one missing, or another file in its place, makes the set unusable.
set_dir="$WORK/cylinder_vtk_4"
cp "$set_dir/set-1.tpk" "$WORK/keep.tpk"
rm "$set_dir/set-1.tpk"
expect_exit 2 "$TPK" check "$set_dir/set.tpkset"
expect_stderr "part 1"
expect_exit 2 "$TPK" render "$set_dir/set.tpkset" -o "$WORK/x.png"
cp "$set_dir/set-2.tpk" "$set_dir/set-1.tpk"
expect_exit 2 "$TPK" info "$set_dir/set.tpkset"
expect_stderr "does not match its record"
cp "$WORK/keep.tpk" "$set_dir/set-1.tpk"
expect_exit 0 "$TPK" info "$set_dir/set.tpkset"
# Isosurfaces and a clip box march across the cuts too: the same picture as the single file.
fx=(--size 96x72 --iso 330,360 --iso-opacity 0.7 --clip-box 0.02,-1,-1,0.08,1,1 --integration midpoint)
"$TPK" render "$set_dir/whole.tpk" -o "$WORK/fx_whole.png" "${fx[@]}" > /dev/null
"$TPK" render "$set_dir/set.tpkset" -o "$WORK/fx_set.png" "${fx[@]}" > /dev/null
cmp -s "$WORK/fx_whole.png" "$WORK/fx_set.png" || fail "iso and clip on the set differ from the single file"
# Lighting and tet fields take the parts as one mesh (libtetpack/set_mesh.c): the same picture as the
# single file, byte for byte, from parts with Tet32 (read directly) and with Tet16 alone (walked), with a
# tet field (a cell field of the source), on a mesh whose parts touch along edges and at vertices alone.
fx=(--size 96x72 --shading --shadows --ao 4 --integration midpoint)
"$TPK" render "$set_dir/whole.tpk" -o "$WORK/lit_whole.png" "${fx[@]}" > /dev/null
"$TPK" render "$set_dir/set.tpkset" -o "$WORK/lit_set.png" "${fx[@]}" --json > "$WORK/lit.json"
cmp -s "$WORK/lit_whole.png" "$WORK/lit_set.png" || fail "shading, shadows and AO on the set differ from the single file"
grep -q '"secondary_rays":[1-9]' "$WORK/lit.json" || fail "no shadow or AO rays: $(cat "$WORK/lit.json")"
lit_case() { # input parts field options...
    local input=$1 parts=$2 field=$3 name
    shift 3
    name=lit_$(basename "$input" | tr . _)
    convert_checked "$input" "$WORK/$name.tpk" --field "$field" > /dev/null
    "$TPK" convert "$input" "$WORK/$name.tpkset" --parts "$parts" --field "$field" > /dev/null
    "$TPK" render "$WORK/$name.tpk" -o "$WORK/$name.png" --size 96x72 --field "$field" "$@" > /dev/null
    "$TPK" render "$WORK/$name.tpkset" -o "$WORK/${name}_set.png" --size 96x72 --field "$field" "$@" > /dev/null
    cmp -s "$WORK/$name.png" "$WORK/${name}_set.png" || fail "$name: the set ($field $*) differs from the single file"
}
lit_case "$DATA/sfepy/acoustic_wg.vtk" 3 mat_id --shading
lit_case "$DATA/hard/nonmanifold_vertex_edge_tets.vtu" 5 component --shadows --ao 2
# More parts than tets is refused with a reason.
expect_exit 2 "$TPK" convert "$DATA/seacas/cube.g" "$WORK/many.tpkset" --parts 1000
expect_stderr "each part needs at least one"
echo "part sets: ok"
