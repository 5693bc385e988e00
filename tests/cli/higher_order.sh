#!/usr/bin/env bash
# Second-order meshes made by gmsh, converted with each cell split whole (the default) and reduced to its
# corners (--higher-order corners):
# - t5 (shared/data/gmsh/t5.geo) at order 2, 13,391 ten-node tets: every one of its nodes is a vertex of
#   some tet (check finds no unused vertex, where the corners leave 17,519 unused), 8 tets per cell, and
#   the file checks clean;
# - hexahedra beside prisms with a curved side (tests/cli/hexprism.geo), complete (27-node hexahedra,
#   18-node prisms) and serendipity (20 and 15 nodes, Mesh.SecondOrderIncomplete): no hanging face (the
#   shell is exactly 4 times the corners' shell: each boundary quad or triangle in 4, nothing inside), the
#   serendipity mesh gets the same vertices as the complete one (a face centre made once per face), and
#   each checks clean but for gmsh's stray geometry points; check --against finds every point sampled in
#   the source cells inside the split file, and some outside the corners' file.
source "$(dirname "$0")/common.sh" "$@"
command -v gmsh > /dev/null || fail "gmsh not installed (./dev deps installs it)"

summary() { # tets vertices shell_faces source_points source_cells mirrored inverted
    "$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); print(d['tets'], d['vertices'], d['shell_faces'], d['source_points'], d['source_cells'], d['mirrored_cells'], d['inverted_fixed'])" "$1"
}
unused() { # FILE.tpk: tetpack check's count of unused vertices (104), and whether it found errors
    "$TPK" check --json "$1" > "$WORK/check.json" || true
    "$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); f=[x for x in d['findings'] if x.get('id')==104 or x.get('name')=='unused_vertex']; e=[x for x in d['findings'] if x.get('severity')=='error']; print(f[0].get('count', 1) if f else 0, len(e))" "$WORK/check.json"
}

gmsh -3 -nt 1 -order 2 "$DATA/gmsh/t5.geo" -o "$WORK/t5.msh" > "$WORK/gmsh.log" 2>&1 || { tail "$WORK/gmsh.log"; fail "gmsh failed"; }
"$TPK" convert "$WORK/t5.msh" "$WORK/t5.tpk" --json > "$WORK/t5.json"
"$TPK" convert "$WORK/t5.msh" "$WORK/t5c.tpk" --higher-order corners --json > "$WORK/t5c.json" 2> "$WORK/err"
expect_stderr "reduced higher-order cells to their corner nodes"
check_6xx "$WORK/t5.tpk"
read -r tets verts shell points cells mirrored inverted < <(summary "$WORK/t5.json")
[ "$tets" -eq $((8 * cells)) ] && [ "$verts" -eq "$points" ] && [ "$mirrored" -eq 0 ] && [ "$inverted" -eq 0 ] ||
    fail "t5 order 2: $(summary "$WORK/t5.json")"
read -r ctets cverts cshell _ < <(summary "$WORK/t5c.json")
[ "$ctets" -eq "$cells" ] && [ "$shell" -eq $((4 * cshell)) ] || fail "t5 corners: $(summary "$WORK/t5c.json")"
[ "$(unused "$WORK/t5.tpk")" = "0 0" ] || fail "t5 split: unused vertices or errors: $(unused "$WORK/t5.tpk")"
read -r cunused cerrors < <(unused "$WORK/t5c.tpk")
[ "$cunused" -gt 0 ] && [ "$cerrors" -eq 0 ] || fail "t5 corners: $cunused unused vertices, $cerrors errors"
"$TPK" info "$WORK/t5.tpk" | grep -q '"higher_order":"split"' || fail "t5.tpk: META lacks higher_order split"
"$TPK" info "$WORK/t5.tpk" | grep -q '^  higher-order cells: split whole' || fail "t5.tpk: info does not say how"

for kind in complete serendipity; do
    extra=()
    [ $kind = serendipity ] && extra=(-string "Mesh.SecondOrderIncomplete=1;")
    gmsh -3 -nt 1 -order 2 "${extra[@]}" "$SRC/tests/cli/hexprism.geo" -o "$WORK/$kind.msh" > "$WORK/gmsh.log" 2>&1 ||
        { tail "$WORK/gmsh.log"; fail "gmsh failed ($kind)"; }
    "$TPK" convert "$WORK/$kind.msh" "$WORK/$kind.tpk" --json > "$WORK/$kind.json" 2> /dev/null
    "$TPK" convert "$WORK/$kind.msh" "$WORK/${kind}c.tpk" --higher-order corners --json > "$WORK/${kind}c.json" 2> /dev/null
    check_6xx "$WORK/$kind.tpk"
    read -r tets verts shell points cells mirrored inverted < <(summary "$WORK/$kind.json")
    read -r ctets _ cshell _ < <(summary "$WORK/${kind}c.json")
    [ "$tets" -eq $((8 * ctets)) ] && [ "$shell" -eq $((4 * cshell)) ] && [ "$mirrored" -eq 0 ] && [ "$inverted" -eq 0 ] ||
        fail "$kind: $(summary "$WORK/$kind.json") against corners $(summary "$WORK/${kind}c.json")"
    read -r nunused nerrors < <(unused "$WORK/$kind.tpk")
    [ "$nerrors" -eq 0 ] && [ "$nunused" -le 2 ] || fail "$kind: $nunused unused vertices (gmsh's 2 stray points at most), $nerrors errors"
    added=$("$PY" -c "import json,sys; h=json.load(open(sys.argv[1]))['higher_order']; print(h['mode'], h['cells'], h['added_points'])" "$WORK/$kind.json")
    read -r mode hcells hadded <<< "$added"
    [ "$mode" = split ] && [ "$hcells" -eq "$cells" ] && [ "$verts" -eq $((points + hadded)) ] ||
        fail "$kind: higher_order $added, $verts vertices from $points points"
    { [ $kind = complete ] && [ "$hadded" -eq 0 ]; } || { [ $kind = serendipity ] && [ "$hadded" -gt 0 ]; } ||
        fail "$kind: $hadded points added (the complete cells have every lattice node, the serendipity ones lack some)"
    echo "$verts" > "$WORK/$kind.vertices"
done
# check --against: points sampled in the curved source cells all lie in the split file's tets; some lie
# outside the corners' flat-faced one (beyond the curved side's chords).
outside() { "$TPK" check "$1" --against "$2" --samples 8 | sed -n 's/.*), \([0-9]*\) in no tet.*/\1/p'; }
[ "$(outside "$WORK/complete.tpk" "$WORK/complete.msh")" = 0 ] || fail "complete: samples outside the split file"
[ "$(outside "$WORK/completec.tpk" "$WORK/complete.msh")" -gt 0 ] || fail "complete: no sample outside the corners' file"
# The same as JSON (no field to compare: the .msh has none).
"$TPK" check "$WORK/complete.tpk" --against "$WORK/complete.msh" --samples 8 --json > "$WORK/against.json" ||
    fail "check --against --json: exit $?"
"$TPK" check "$WORK/completec.tpk" --against "$WORK/complete.msh" --samples 8 --json > "$WORK/againstc.json" ||
    fail "check --against --json (corners): exit $?"
"$PY" - "$WORK/against.json" "$WORK/againstc.json" <<'PYEOF' || fail "check --against --json: unexpected report"
import json, sys
a, c = (json.load(open(f)) for f in sys.argv[1:3])
assert a["outside"] == 0 and a["samples"] == c["samples"] > 0 and a["samples_per_axis"] == 8, a
assert a["bound"] is None and not a["bound_exceeded"] and a["fields"] == [], a
assert c["outside"] > 0, c
PYEOF
[ "$(cat "$WORK/complete.vertices")" = "$(cat "$WORK/serendipity.vertices")" ] ||
    fail "serendipity mesh: $(cat "$WORK/serendipity.vertices") vertices, the complete one $(cat "$WORK/complete.vertices")"
echo "ok"
