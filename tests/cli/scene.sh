# render --scene / --save-scene: a scene replays a render byte for byte, a hand-written scene equals the
# same options on the command line, options given override the scene, and a bad scene is exit 2 with
# file, line, column and key.
source "$(dirname "$0")/common.sh"

convert_checked "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpk" --layout tet16 --layout tet20 --layout tet32 > /dev/null

# Options on the command line, the scene they make, and the scene replayed: the same PNG bytes.
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/cli.png" --size 80x60 --tf inferno --layout tet20 --range 300,370 \
    --unit-distance 0.002 --integration sampled --save-scene "$WORK/saved.json" > /dev/null
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/replay.png" --scene "$WORK/saved.json" > /dev/null
cmp "$WORK/cli.png" "$WORK/replay.png" || fail "render --scene of a saved scene differs from the render that saved it"
grep -q '"layout":[[:space:]]*"tet20"' "$WORK/saved.json" || fail "the saved scene lacks the layout"

# A hand-written scene and the same values as options.
cat > "$WORK/hand.json" <<'JSON'
{
  "tetpack_scene": 1,
  "camera": {"eye": [0.2, 0.1, 0.12], "at": [0.05, 0, 0], "up": [0, 0, 1], "fovy": 30},
  "tf": {"points": [[0, 0, 0, 1, 0.1], [0.5, 0, 1, 0, 0.4], [1, 1, 0, 0, 0.9]]},
  "field": "temperature",
  "step": 0,
  "range": [295, 375],
  "layout": "tet32",
  "size": [72, 54],
  "integration": "exact"
}
JSON
printf '0 0 0 1 0.1\n0.5 0 1 0 0.4\n1 1 0 0 0.9\n' > "$WORK/tf.txt"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/hand.png" --scene "$WORK/hand.json" > /dev/null
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/opts.png" --camera 0.2,0.1,0.12,0.05,0,0,0,0,1,30 --tf "$WORK/tf.txt" \
    --field temperature --step 0 --range 295,375 --layout tet32 --size 72x54 --integration exact > /dev/null
cmp "$WORK/hand.png" "$WORK/opts.png" || fail "render --scene differs from the same render from command-line options"

# The command line overrides the scene: another size and range give the image those options give.
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/over.png" --scene "$WORK/hand.json" --size 40x30 --range 300,320 > "$WORK/over.txt"
grep -q "40x30" "$WORK/over.txt" || fail "--size did not override the scene's size: $(cat "$WORK/over.txt")"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/over_opts.png" --camera 0.2,0.1,0.12,0.05,0,0,0,0,1,30 --tf "$WORK/tf.txt" \
    --range 300,320 --layout tet32 --size 40x30 > /dev/null
cmp "$WORK/over.png" "$WORK/over_opts.png" || fail "options over a scene differ from the same options alone"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/over2.png" --scene "$WORK/hand.json" > /dev/null
cmp -s "$WORK/over.png" "$WORK/over2.png" && fail "the overriding options changed nothing"

# Effects come from the scene: shading and a clip box each change the picture.
printf '{"size": [48, 48], "effects": {"shading": true}}' > "$WORK/shaded.json"
printf '{"size": [48, 48], "clip_box": [0, -1, -1, 0.05, 1, 1]}' > "$WORK/clipped.json"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/plain.png" --size 48x48 > /dev/null
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/shaded.png" --scene "$WORK/shaded.json" > /dev/null
cmp -s "$WORK/plain.png" "$WORK/shaded.png" && fail "the scene's shading changed nothing"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/clipped.png" --scene "$WORK/clipped.json" > /dev/null
cmp -s "$WORK/plain.png" "$WORK/clipped.png" && fail "the scene's clip box changed nothing"

# Every effect from a scene equals the same effects as options, and a saved scene of them replays them.
printf '{"size": [48, 40], "clip_box": [0, -1, -1, 0.08, 1, 1], "iso": [330], "iso_opacity": 0.6, "integration": "midpoint",
 "effects": {"shading": true, "shadows": true, "light": [0.3, 0.2, 0.2], "ao_rays": 2, "ao_radius": 0.01}}' > "$WORK/fx.json"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/fx_scene.png" --scene "$WORK/fx.json" > /dev/null
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/fx_opts.png" --size 48x40 --clip-box 0,-1,-1,0.08,1,1 --iso 330 --iso-opacity 0.6 \
    --integration midpoint --shading --shadows --light 0.3,0.2,0.2 --ao 2 --ao-radius 0.01 --save-scene "$WORK/fx_saved.json" > /dev/null
cmp "$WORK/fx_scene.png" "$WORK/fx_opts.png" || fail "a scene's effects differ from the same effects as options"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/fx_replay.png" --scene "$WORK/fx_saved.json" > /dev/null
cmp "$WORK/fx_opts.png" "$WORK/fx_replay.png" || fail "a saved scene with effects does not replay them"
cmp -s "$WORK/fx_opts.png" "$WORK/plain.png" && fail "the effects changed nothing"

# A TF file named by the scene is found next to the scene, wherever render runs.
mkdir -p "$WORK/sub"
cp "$WORK/tf.txt" "$WORK/sub/tf.txt"
sed 's|"tf": {"points": .*|"tf": {"file": "tf.txt"},|' "$WORK/hand.json" > "$WORK/sub/file.json"
(cd / && "$TPK" render "$WORK/cyl.tpk" -o "$WORK/file.png" --scene "$WORK/sub/file.json" > /dev/null)
cmp "$WORK/hand.png" "$WORK/file.png" || fail "a scene's TF file gives another image than the same points inline"

# Bad scenes: exit 2, file:line:col, key.
printf '{\n  "size": [64, 48],\n  "effects": {\n    "shadows": "yes"\n  }\n}\n' > "$WORK/bad.json"
expect_exit 2 "$TPK" render "$WORK/cyl.tpk" -o "$WORK/x.png" --scene "$WORK/bad.json"
expect_stderr "bad.json:4:5: key 'effects.shadows': expected true or false, found \"yes\""
printf '{\n  "size": [64, 48],\n  "clip-box": [0, 0, 0, 1, 1, 1]\n}\n' > "$WORK/typo.json"
expect_exit 2 "$TPK" render "$WORK/cyl.tpk" -o "$WORK/x.png" --scene "$WORK/typo.json"
expect_stderr "typo.json:3:3: key 'clip-box': unknown key (did you mean 'clip_box'?)"
printf '{"size": [64, 48],\n "range": [1, 2]\n "step": 0}\n' > "$WORK/syntax.json"
expect_exit 2 "$TPK" render "$WORK/cyl.tpk" -o "$WORK/x.png" --scene "$WORK/syntax.json"
expect_stderr "syntax.json:3:2: JSON syntax error in key 'range' at '\"step\": 0}'"
[ ! -e "$WORK/x.png" ] || fail "a refused scene still wrote an image"
printf '{"steps": [0, 3]}' > "$WORK/steps.json"
expect_exit 2 "$TPK" render "$WORK/cyl.tpk" -o "$WORK/x.png" --scene "$WORK/steps.json"
expect_stderr "the scene gives steps 0..3: -o needs one %d conversion for the step (e.g. frame_%04d.png), or choose one step with --step N, found '$WORK/x.png'"
expect_exit 2 "$TPK" render "$WORK/cyl.tpk" -o "$WORK/x.png" --scene "$WORK/missing.json"
expect_stderr "missing.json: cannot open the scene file"
echo "scene: ok"

