#!/usr/bin/env bash
# Levels of detail (spec §16) on real meshes: an OpenFOAM case (snappyHexMesh's flange, through
# foamToVTK), a gmsh boundary-layer mesh (tests/cli/sphere_bl.geo: tets, prisms and hexahedra, folds cut)
# and an Exodus file with transient fields (SEACAS's exomerge test). `convert --levels` writes levels that
# `check` finds valid (600..615 on the file and each level), `info` lists, `extract --level` writes as
# files of their own, and `render --level` / `--max-ms` draw with the full mesh's view, reporting the level,
# its error and the prediction; bad options are refused by name.
source "$(dirname "$0")/common.sh"

gmsh -3 -nt 1 "$SRC/tests/cli/sphere_bl.geo" -format vtk -o "$WORK/bl.vtk" > "$WORK/gmsh.log" 2>&1 ||
    { tail "$WORK/gmsh.log"; fail "gmsh failed"; }
declare -A extra=([bl]=--cut-folds)
declare -A input=([flange]="$SRC/tests/data/openfoam/flange.vtk" [bl]="$WORK/bl.vtk"
                  [exomerge]="$DATA/seacas/exomerge_unit_test.e")
for name in flange bl exomerge; do
    # shellcheck disable=SC2086
    "$TPK" convert "${input[$name]}" "$WORK/$name.tpk" --levels 3 ${extra[$name]:-} --json > "$WORK/$name.json" \
        2> "$WORK/err" || { cat "$WORK/err"; fail "$name: convert --levels"; }
    "$PY" - "$WORK/$name.json" "$name" <<'PYEOF' || fail "$name: the levels report: $(cat "$WORK/$name.json")"
import json, sys
r = json.load(open(sys.argv[1]))
levels = r["levels"]
assert len(levels) >= 1, levels
tets = [r["tets"]] + [l["tets"] for l in levels]
assert all(a > b for a, b in zip(tets, tets[1:])), tets
for l in levels:
    # the CLI's default lets the shell move inward, by at most 0.002 of the bounding-box diagonal
    assert 0 <= l["shell_distance"] <= l["shell_tolerance"] and l["shell_tolerance"] > 0, l
    assert l["error_max"] >= l["error_rms"] >= 0 and l["bytes"] > 0, l
print("%s: %s tets; error max/RMS %s" % (sys.argv[2], " > ".join(map(str, tets)),
      ", ".join("%.3g/%.3g" % (l["error_max"], l["error_rms"]) for l in levels)))
PYEOF
    check_6xx "$WORK/$name.tpk" 615 # the file and every level: 600..613 and 615 (TPK-L01)
    "$TPK" info "$WORK/$name.tpk" > "$WORK/info.txt" || fail "$name: info"
    grep -q "^  level 1: vertices [0-9]*, tets [0-9]*" "$WORK/info.txt" || fail "$name: info lists no level"
    grep -q "format 1.3" "$WORK/info.txt" || fail "$name: a file with levels is not format 1.3"
    "$TPK" extract "$WORK/$name.tpk" "$WORK/$name-1.tpk" --level 1 > /dev/null || fail "$name: extract --level 1"
    check_6xx "$WORK/$name-1.tpk"
    grep -q "format 1.1" <<< "$("$TPK" info "$WORK/$name-1.tpk")" || fail "$name: the extracted level is not plain 1.1"
    # the level's META names the file's source (its TMAP and VMAP number those cells and points, §16.1),
    # pipeline and repairs (the Gmsh mesh's cut folds: nonzero), as a part's does
    "$TPK" info "$WORK/$name.tpk" --json > "$WORK/info.json" && "$TPK" info "$WORK/$name-1.tpk" --json > "$WORK/info1.json" ||
        fail "$name: info --json"
    "$PY" -c "import json,sys; a, b = (json.load(open(f))['metadata'] for f in sys.argv[1:]); \
sys.exit(0 if all(a[k] == b['source_meta'][k] for k in ('source', 'pipeline', 'repairs')) and a['source']['cells'] > 0 else 1)" \
        "$WORK/info.json" "$WORK/info1.json" || fail "$name: level 1's META source, pipeline or repairs are not the file's"
done

# the exodus file: a transient field; the error is measured at its step of widest range, and is nonzero
"$PY" -c "import json,sys; l = json.load(open(sys.argv[1]))['levels'][0]; sys.exit(0 if l['error_samples'] > 0 else 1)" \
    "$WORK/exomerge.json" || fail "exomerge: no error samples"

# render: a level with the full mesh's camera and range; --max-ms picks one and says why
f=$WORK/exomerge.tpk
"$TPK" render "$f" -o "$WORK/full.png" --size 64x64 --field disp_z --step 4 --json > "$WORK/full.json"
"$TPK" render "$f" -o "$WORK/l1.png" --size 64x64 --field disp_z --step 4 --level 1 --json > "$WORK/l1.json"
"$PY" - "$WORK/l1.json" <<'PYEOF' || fail "render --level 1 --json: $(cat "$WORK/l1.json")"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["level"] == 1 and d["level_tets"] > 0 and d["level_error"]["max"] >= d["level_error"]["rms"], d
PYEOF
db=$("$PY" "$SRC/tests/cli/psnr.py" "$WORK/full.png" "$WORK/l1.png" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p')
"$PY" -c "import sys; sys.exit(0 if float(sys.argv[1]) >= 20 else 1)" "$db" || fail "level 1 draws another view: $db dB"
for case in "0.001 8" "100000 8" "0.001 2" "0.001 1"; do
    set -- $case
    ms=$1 max_step=$2
    "$TPK" render "$f" -o "$WORK/b.png" --size 64x48 --max-ms "$ms" --max-pixel-step "$max_step" --json \
        > "$WORK/b.json" || fail "--max-ms $ms --max-pixel-step $max_step"
    "$PY" - "$WORK/b.json" "$ms" "$WORK/exomerge.json" "$max_step" "$WORK/b.png" <<'PYEOF' ||
import json, struct, sys
d, ms = json.load(open(sys.argv[1])), float(sys.argv[2])
coarsest = len(json.load(open(sys.argv[3]))["levels"])
assert d["max_ms"] == ms and d["predicted_ms"] > 0 and d["frame_ms"] > 0, d
# a budget no frame fits: the coarsest level, then the largest pixel step allowed, rays at every
# max_step-th pixel (64/d x 48/d, rounded); one every frame fits: the full mesh at every pixel
step = 1 if ms > 1000 else int(sys.argv[4])
assert d["level"] == (0 if ms > 1000 else coarsest) and d["pixel_step"] == step, d
assert d["rays"] == max(1, round(64 / step)) * max(1, round(48 / step)), d
# the picture has the asked size whatever the step (PNG's IHDR)
png = open(sys.argv[5], "rb").read(24)
assert struct.unpack(">II", png[16:24]) == (64, 48), png
# the level's shell distance, as the converter measured it
level = json.load(open(sys.argv[3]))["levels"][d["level"] - 1] if d["level"] else {"shell_distance": 0}
assert abs(d["level_error"]["shell_distance"] - level["shell_distance"]) <= 1e-8 * (1 + level["shell_distance"]), d
PYEOF
        fail "--max-ms $ms --max-pixel-step $max_step: $(cat "$WORK/b.json")"
done
# at pixel step 2, the coarsest level's picture interpolated: near the picture with a ray at every pixel
coarsest=$("$PY" -c "import json,sys; print(len(json.load(open(sys.argv[1]))['levels']))" "$WORK/exomerge.json")
"$TPK" render "$f" -o "$WORK/c1.png" --size 128x96 --field disp_z --step 4 --level "$coarsest" > /dev/null
"$TPK" render "$f" -o "$WORK/c2.png" --size 128x96 --field disp_z --step 4 --max-ms 0.001 --max-pixel-step 2 \
    > /dev/null || fail "--max-pixel-step 2"
step_db=$("$PY" "$SRC/tests/cli/psnr.py" "$WORK/c1.png" "$WORK/c2.png" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p')
"$PY" -c "import sys; sys.exit(0 if float(sys.argv[1]) >= 40 else 1)" "$step_db" ||
    fail "pixel step 2 against every pixel: $step_db dB"
echo "render: level 1 at $db dB against the full mesh; --max-ms picks the coarsest and the full mesh, and past"
echo "the coarsest, the largest pixel step --max-pixel-step allows ($step_db dB at step 2 against every pixel)"

# refused by name
expect_exit 2 "$TPK" convert "${input[flange]}" "$WORK/x.tpk" --levels 9
expect_stderr "--levels expects a number of levels from 1 to 8, found '9'"
expect_exit 2 "$TPK" convert "${input[flange]}" "$WORK/x.tpkset" --levels 2 --parts 2
expect_stderr "--levels and --parts"
expect_exit 2 "$TPK" render "$f" -o "$WORK/x.png" --level 5
expect_stderr "no level 5: the file has 3 levels of detail"
expect_exit 2 "$TPK" convert "${input[flange]}" "$WORK/x.tpk" --levels 2 --level-shell-error 0.5
expect_stderr "--level-shell-error expects a fraction of the bounding-box diagonal from 0 to 0.1, found '0.5'"
expect_exit 2 "$TPK" render "$f" -o "$WORK/x.png" --max-ms 10 --max-pixel-step 0
expect_stderr "--max-pixel-step expects a pixel step from 1 to 16, found '0'"
"$TPK" convert "${input[flange]}" "$WORK/flange.tpkset" --parts 2 --quiet || fail "a part set"
expect_exit 2 "$TPK" render "$WORK/flange.tpkset" -o "$WORK/x.png" --max-ms 10
expect_stderr "a part set has no levels of detail: --max-ms draws a single file's"
expect_exit 2 "$TPK" render "$WORK/flange.tpkset" -o "$WORK/x.png" --level 1
expect_stderr "a part set has no levels of detail: --level draws a single file's"
expect_exit 2 "$TPK" extract "$f" "$WORK/x.tpk" --level 5
expect_stderr "no level 5"
[ ! -e "$WORK/x.tpk" ] || fail "extract left a file for a level that is not there"
echo "levels: ok"
