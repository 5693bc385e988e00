# tetpack view under Xvfb: the window's last frame (read back from the window) equals the headless
# render of the same scene (same size, camera, TF, backend) for each layout and with effects; --orbit
# turns the camera as a render with the turned camera shows it, and the scene it saves replays to the
# same picture; mouse drags and keys sent to the running window, and --keys, change the camera, field,
# step, layout, TF and effects as the scene they save says; no display, a bad file and bad options end
# with exit 2 and a message. All of that through OpenGL (--present gl: frames read back); then Vulkan
# presentation (the swapchain): the window's pixels as the X server has them equal the view's screenshot
# and render's picture, the title has the GPU time, a resize and a new renderer (L) keep presenting, and
# auto falls back to OpenGL with a note where the device cannot present.
set -euo pipefail
# One X server for the whole script (tests/with_xvfb.sh: a display of its own; 24-bit so that frames
# read back exactly).
if [ -z "${TPK_VIEW_XVFB:-}" ]; then
    command -v Xvfb > /dev/null || { echo "FAIL: Xvfb not installed (xvfb, xauth)" >&2; exit 1; }
    TPK_VIEW_XVFB=1 exec sh "$(dirname "$0")/../with_xvfb.sh" -screen 320x240x24 -audit bash "$0" "$@"
fi
source "$(dirname "$0")/common.sh"
psnr_at_least() { # A.png B.png what
    "$PY" "$SRC/tests/cli/psnr.py" "$1" "$2" --min 40 > "$WORK/psnr" || fail "$3: $(cat "$WORK/psnr")"
    echo "$3: $(cat "$WORK/psnr")"
}
unset TETPACK_RENDER_BACKEND
export TETPACK_VIEW_PRESENT=gl # the sections before "Vulkan presentation"
# view, like render, defaults to the CPU reference where the only Vulkan device is a software rasterizer
# (lavapipe, here); this test is about the Vulkan renderer's frames in the window
export TETPACK_RENDER_BACKEND=vulkan
SIZE=72x56
convert_checked "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpk" --layout tet16 --layout tet20 --layout tet32 > /dev/null
grep -q -- "--orbit DEG" <<< "$(tpk view --help)" || fail "view --help lacks --orbit"

# each layout: a few frames, the last one against the headless render of the scene view saved
for layout in tet16 tet20 tet32; do
    tpk view "$WORK/cyl.tpk" --size $SIZE --layout $layout --frames 3 --screenshot "$WORK/view-$layout.png" \
        --save-scene "$WORK/view-$layout.json" 2> "$WORK/err" || { cat "$WORK/err"; fail "view --layout $layout"; }
    tpk render "$WORK/cyl.tpk" --size $SIZE --layout $layout --backend vulkan -o "$WORK/render-$layout.png" > /dev/null
    psnr_at_least "$WORK/view-$layout.png" "$WORK/render-$layout.png" "view and render, $layout"
    grep -q "\"layout\":.*\"$layout\"" "$WORK/view-$layout.json" ||
        fail "scene of $layout: $(cat "$WORK/view-$layout.json")"
done
# effects through the shared options: iso, shading, clip box, another TF
FX=(--iso 335 --shading --clip-box 0,-1,-1,0.06,1,1 --tf inferno)
tpk view "$WORK/cyl.tpk" --size $SIZE --frames 2 "${FX[@]}" --screenshot "$WORK/view-fx.png" 2> "$WORK/err" ||
    { cat "$WORK/err"; fail "view with effects"; }
tpk render "$WORK/cyl.tpk" --size $SIZE "${FX[@]}" --backend vulkan -o "$WORK/render-fx.png" > /dev/null
psnr_at_least "$WORK/view-fx.png" "$WORK/render-fx.png" "view and render, effects"
# a part set (spec §15): its parts as one mesh, the picture render draws of the set
"$TPK" convert "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpkset" --parts 3 > /dev/null
tpk view "$WORK/cyl.tpkset" --size $SIZE --frames 2 --shading --screenshot "$WORK/view-set.png" 2> "$WORK/err" ||
    { cat "$WORK/err"; fail "view of a part set"; }
tpk render "$WORK/cyl.tpkset" --size $SIZE --shading --backend vulkan -o "$WORK/render-set.png" > /dev/null
psnr_at_least "$WORK/view-set.png" "$WORK/render-set.png" "view and render, a part set"

# --orbit: 4 frames at 25 degrees, the last one turned by 75 degrees around up (+z) from the first
tpk view "$WORK/cyl.tpk" --size $SIZE --frames 4 --orbit 25 --screenshot "$WORK/orbit.png" \
    --save-scene "$WORK/orbit.json" 2> "$WORK/err" || { cat "$WORK/err"; fail "view --orbit"; }
CAMERA=$("$PY" - "$WORK/view-tet16.json" <<'PYEOF'
import json, math, sys
c = json.load(open(sys.argv[1]))["camera"]
eye, at = c["eye"], c["at"]
a = math.radians(75)
x, y = eye[0] - at[0], eye[1] - at[1]
eye = [at[0] + x * math.cos(a) - y * math.sin(a), at[1] + x * math.sin(a) + y * math.cos(a), eye[2]]
print(",".join("%.17g" % v for v in eye + at + c["up"] + [c["fovy"]]))
PYEOF
)
tpk render "$WORK/cyl.tpk" --size $SIZE --camera "$CAMERA" --backend vulkan -o "$WORK/orbit-render.png" > /dev/null
psnr_at_least "$WORK/orbit.png" "$WORK/orbit-render.png" "view --orbit and render with the turned camera"
tpk render "$WORK/cyl.tpk" --scene "$WORK/orbit.json" --backend vulkan -o "$WORK/orbit-scene.png" > /dev/null
psnr_at_least "$WORK/orbit.png" "$WORK/orbit-scene.png" "view --orbit and its scene replayed"
! "$PY" "$SRC/tests/cli/psnr.py" "$WORK/orbit.png" "$WORK/view-tet16.png" --min 40 > /dev/null ||
    fail "--orbit did not turn the camera"
# the scene replayed by view gives view's own picture
tpk view "$WORK/cyl.tpk" --scene "$WORK/orbit.json" --frames 1 --screenshot "$WORK/orbit-view.png" 2> /dev/null
psnr_at_least "$WORK/orbit-view.png" "$WORK/orbit-scene.png" "view --scene"

# a user: mouse drags (orbit, pan, zoom), the wheel, then W, P and Q sent through XTEST while the view
# runs; the screenshot after them equals render of the scene W wrote, whose camera moved
tpk view "$WORK/cyl.tpk" --size $SIZE --keys P --screenshot "$WORK/user.png" --save-scene "$WORK/user.json" \
    2> "$WORK/user.err" &
VIEW_PID=$!
"$PY" "$SRC/tests/cli/view_input.py" "$WORK/user.png" "$WORK/user.json" || { kill $VIEW_PID; fail "driving the view"; }
wait $VIEW_PID || { cat "$WORK/user.err"; fail "view driven by input"; }
tpk render "$WORK/cyl.tpk" --scene "$WORK/user.json" --backend vulkan -o "$WORK/user-render.png" > /dev/null
psnr_at_least "$WORK/user.png" "$WORK/user-render.png" "view after mouse and keys, and render of its scene"
"$PY" - "$WORK/user.json" "$WORK/view-tet16.json" <<'PYEOF' || fail "the drags did not move the camera"
import json, sys
a, b = (json.load(open(p))["camera"] for p in sys.argv[1:3])
moved = lambda k: max(abs(x - y) for x, y in zip(a[k], b[k]))
print("camera moved: eye %.3g, look-at %.3g" % (moved("eye"), moved("at")))
sys.exit(0 if moved("eye") > 1e-3 and moved("at") > 1e-4 else 1)
PYEOF

# the keys (--keys types them before the first frame): on a file with 12 point fields of 11 steps, four
# steps forward and one back, the fourth field, the next layout, TF preset, iso, shading and clip box;
# the scene view saves says so, and render draws it the same
convert_checked "$DATA/seacas/8-block.g" "$WORK/blocks.tpk" --layout tet16 --layout tet32 > /dev/null
tpk view "$WORK/blocks.tpk" --size $SIZE --frames 1 --keys ']]]][FFFLTISC' --screenshot "$WORK/keys.png" \
    --save-scene "$WORK/keys.json" 2> "$WORK/err" || { cat "$WORK/err"; fail "view --keys"; }
"$PY" - "$WORK/keys.json" <<'PYEOF' || fail "the keys' scene: $(cat "$WORK/keys.json")"
import json, sys
s = json.load(open(sys.argv[1]))
assert (s["field"], s["step"], s["layout"], s["tf"]["preset"]) == ("accel_x", 3, "tet32", "cool-warm"), s
assert abs(s["iso"][0] - sum(s["range"]) / 2) < 1e-9 and s["effects"]["shading"], s
assert s["clip_box"] == [0, 0, 0, 0.5, 1, 1], s
PYEOF
tpk render "$WORK/blocks.tpk" --scene "$WORK/keys.json" --backend vulkan -o "$WORK/keys-render.png" > /dev/null
psnr_at_least "$WORK/keys.png" "$WORK/keys-render.png" "view --keys and render of its scene"

# a part set's next field (F): its colour range spans every part's, as render's of the set does
"$TPK" convert "$DATA/seacas/8-block.g" "$WORK/blocks.tpkset" --parts 3 > /dev/null
tpk view "$WORK/blocks.tpkset" --size $SIZE --frames 1 --keys FF --save-scene "$WORK/set-keys.json" \
    --screenshot "$WORK/set-keys.png" 2> "$WORK/err" || { cat "$WORK/err"; fail "view --keys on a part set"; }
field=$("$PY" -c 'import json,sys; print(json.load(open(sys.argv[1]))["field"])' "$WORK/set-keys.json")
tpk render "$WORK/blocks.tpkset" --field "$field" --size $SIZE --backend vulkan -o "$WORK/set-field.png" \
    --save-scene "$WORK/set-field.json" > /dev/null
"$PY" - "$WORK/set-keys.json" "$WORK/set-field.json" <<'PYEOF' || fail "a part set's next field: its range"
import json, sys
a, b = (json.load(open(p))["range"] for p in sys.argv[1:3])
assert max(abs(x - y) for x, y in zip(a, b)) <= 1e-6 * max(1.0, abs(b[1] - b[0])), (a, b)
PYEOF

# the probe keys: O twice (a sphere, then a plane facing the camera), K (cut, not keep), 6 and 9 (moved
# right and away), then O again (a box), ++ and 8: the scene view saves has the box, moved and grown,
# and render draws it the same
tpk view "$WORK/cyl.tpk" --size $SIZE --frames 1 --keys 'OOK69O++8' --screenshot "$WORK/probe.png" \
    --save-scene "$WORK/probe.json" 2> "$WORK/err" || { cat "$WORK/err"; fail "view --keys with probes"; }
"$PY" - "$WORK/probe.json" <<'PYEOF' || fail "the probe keys' scene: $(cat "$WORK/probe.json")"
import json, sys
p = json.load(open(sys.argv[1]))["probes"]
assert len(p) == 1 and p[0]["shape"] == "box" and p[0]["mode"] == "cut", p
size = [b - a for a, b in zip(p[0]["min"], p[0]["max"])]
assert size[0] > 0.05 * 1.5 and size[1] > 0.02 * 1.5, size  # the upper octant of the cylinder's box, grown 1.5625x
PYEOF
tpk render "$WORK/cyl.tpk" --scene "$WORK/probe.json" --backend vulkan -o "$WORK/probe-render.png" > /dev/null
psnr_at_least "$WORK/probe.png" "$WORK/probe-render.png" "view's probe keys and render of its scene"
! "$PY" "$SRC/tests/cli/psnr.py" "$WORK/probe.png" "$WORK/view-tet16.png" --min 40 > /dev/null ||
    fail "the probe keys did not change the picture"
expect_exit 2 tpk view "$WORK/cyl.tpk" --keys 'O7'
expect_stderr "--keys expects keys of T F \[ \] L I S C P W Q O K 4 6 8 2 9 3 + -, found 'O7'"

# --max-ms (levels of detail): with a budget nothing fits, the first frame is the coarsest level (the cost
# model has seen nothing yet) and, the view resting, the second the full mesh; each equals render's
convert_checked "$SRC/samples/cylinder.vtk" "$WORK/cyl_l.tpk" --levels 2 > /dev/null
coarsest=$(tpk info "$WORK/cyl_l.tpk" --json | "$PY" -c 'import json,sys; print(len(json.load(sys.stdin)["levels"]))')
[ "$coarsest" -ge 1 ] || fail "the sample has no level of detail"
for frames in 1 2; do
    tpk view "$WORK/cyl_l.tpk" --size $SIZE --frames $frames --max-ms 0.0001 --screenshot "$WORK/lod$frames.png" \
        2> "$WORK/err" || { cat "$WORK/err"; fail "view --max-ms"; }
    want=$([ $frames = 1 ] && echo "$coarsest" || echo 0)
    grep -q "the last at level $want" "$WORK/err" || fail "view --max-ms, $frames frames: $(cat "$WORK/err")"
    tpk render "$WORK/cyl_l.tpk" --size $SIZE --backend vulkan --level $want -o "$WORK/lod-render$want.png" > /dev/null
    psnr_at_least "$WORK/lod$frames.png" "$WORK/lod-render$want.png" "view --max-ms, frame $frames (level $want)"
done
# while the view moves (--orbit), the coarsest level, and past it, with a budget nothing fits, rays at
# every 8th pixel; with one every frame fits, the full mesh at every pixel
for case in "0.0001 $coarsest 8 8" "0.0001 $coarsest 3 3" "100000 0 8 1"; do
    set -- $case
    tpk view "$WORK/cyl_l.tpk" --size $SIZE --frames 3 --orbit 10 --max-ms "$1" --max-pixel-step "$3" 2> "$WORK/err" ||
        { cat "$WORK/err"; fail "view --max-ms $1 --max-pixel-step $3 --orbit"; }
    grep -q "the last at level $2, pixel step $4" "$WORK/err" ||
        fail "view --max-ms $1 --max-pixel-step $3 --orbit: $(cat "$WORK/err")"
done

# no Vulkan device: the CPU reference, with a note
VK_ICD_FILENAMES="$WORK/no_such_icd.json" TETPACK_RENDER_BACKEND= tpk view "$WORK/cyl.tpk" --size $SIZE --frames 1 \
    --screenshot "$WORK/view-cpu.png" 2> "$WORK/err" || { cat "$WORK/err"; fail "view without Vulkan"; }
expect_stderr "no Vulkan device"
tpk render "$WORK/cyl.tpk" --size $SIZE --backend cpu -o "$WORK/render-cpu.png" > /dev/null
psnr_at_least "$WORK/view-cpu.png" "$WORK/render-cpu.png" "view on the CPU reference"

# the OpenGL window as the X server has it: its pixels equal the screenshot (read back by glReadPixels)
tpk view "$WORK/cyl.tpk" --size $SIZE --layout tet16 --keys P --screenshot "$WORK/gl-shot.png" 2> "$WORK/gl.err" &
VIEW_PID=$!
"$PY" "$SRC/tests/cli/view_present.py" "$WORK/gl-shot.png" "$WORK" "OpenGL \\| .* ms, GPU [0-9.]+ ms, $SIZE" 96x64 ||
    { kill $VIEW_PID; cat "$WORK/gl.err"; fail "the OpenGL window"; }
wait $VIEW_PID || { cat "$WORK/gl.err"; fail "view --present gl driven"; }

# Vulkan presentation: each frame's bands copied on the device into an image blitted into the swapchain
unset TETPACK_VIEW_PRESENT
for layout in tet16 tet32; do
    tpk view "$WORK/cyl.tpk" --size $SIZE --layout $layout --present vulkan --frames 3 \
        --screenshot "$WORK/vk-$layout.png" 2> "$WORK/err" || { cat "$WORK/err"; fail "view --present vulkan"; }
    expect_stderr "presented"
    psnr_at_least "$WORK/vk-$layout.png" "$WORK/render-$layout.png" "view presented by Vulkan and render, $layout"
done
tpk view "$WORK/cyl.tpk" --size $SIZE --present vulkan --frames 2 "${FX[@]}" --screenshot "$WORK/vk-fx.png" \
    2> "$WORK/err" || { cat "$WORK/err"; fail "view --present vulkan with effects"; }
psnr_at_least "$WORK/vk-fx.png" "$WORK/render-fx.png" "view presented by Vulkan and render, effects"
# the discrete GPU's memory path (counters copied out), bands of a few rows each
TPK_VK_MEMORY=staged TPK_VK_BAND_PIXELS=1000 tpk view "$WORK/cyl.tpk" --size $SIZE --layout tet16 \
    --present vulkan --frames 2 --screenshot "$WORK/vk-staged.png" 2> "$WORK/err" ||
    { cat "$WORK/err"; fail "view --present vulkan, staged"; }
psnr_at_least "$WORK/vk-staged.png" "$WORK/render-tet16.png" "view presented by Vulkan, staged bands, and render"
# L makes the renderer again, and with it the window's surface and swapchain
tpk view "$WORK/cyl.tpk" --size $SIZE --layout tet16 --keys L --present vulkan --frames 2 \
    --screenshot "$WORK/vk-L.png" 2> "$WORK/err" || { cat "$WORK/err"; fail "view --present vulkan --keys L"; }
psnr_at_least "$WORK/vk-L.png" "$WORK/render-tet20.png" "view presented by Vulkan after L, and render of tet20"
# auto (the default) presents with Vulkan where it can
tpk view "$WORK/cyl.tpk" --size $SIZE --frames 1 2> "$WORK/err" || { cat "$WORK/err"; fail "view, auto"; }
expect_stderr "presented"
# the window as the X server has it: the view's screenshot, the title with the GPU time; then a resize
tpk view "$WORK/cyl.tpk" --size $SIZE --layout tet16 --present vulkan --keys P --screenshot "$WORK/vk-shot.png" \
    2> "$WORK/vk.err" &
VIEW_PID=$!
"$PY" "$SRC/tests/cli/view_present.py" "$WORK/vk-shot.png" "$WORK" "presented .* ms, GPU [0-9.]+ ms, $SIZE" 96x64 ||
    { kill $VIEW_PID; cat "$WORK/vk.err"; fail "the Vulkan-presented window"; }
wait $VIEW_PID || { cat "$WORK/vk.err"; fail "view --present vulkan driven"; }
tpk render "$WORK/cyl.tpk" --size 96x64 --layout tet16 --backend vulkan -o "$WORK/render-96x64.png" > /dev/null
psnr_at_least "$WORK/vk-shot.png" "$WORK/render-96x64.png" "view presented by Vulkan after a resize, and render"
psnr_at_least "$WORK/grab-96x64.png" "$WORK/render-96x64.png" "the resized window's pixels and render"
psnr_at_least "$WORK/grab-${SIZE}.png" "$WORK/render-tet16.png" "the window's pixels and render"
# a device that cannot present: auto shows the frames through OpenGL, with a note; vulkan is an error
AUDIT_FROM=$(($(wc -l < "$TPK_XVFB_LOG") + 1))
TPK_VK_NO_PRESENT=1 tpk view "$WORK/cyl.tpk" --size $SIZE --layout tet16 --frames 1 --screenshot "$WORK/vk-fb.png" \
    2> "$WORK/err" || { cat "$WORK/err"; fail "view, auto, without presentation"; }
# ... on the X connection it opened for Vulkan: had it closed it and opened another, the server (its only
# client gone) would reset and could refuse the new one, as it did in a CI run (the audit log: clients
# connected and disconnected, with the view's pid; the count open must reach 0 once, at the end). A
# client the server rejected (no cookie: another run's process still holding this display number, seen
# once while other test runs shared the machine) is logged as rejected, then disconnected: not counted.
tail -n +"$AUDIT_FROM" "$TPK_XVFB_LOG" > "$WORK/audit"
awk 'function id() { c = $0; sub(/.* client /, "", c); sub(/ .*/, "", c); return c }
     / connected from /{open[id()] = 1; n++}
     / rejected from /{open[id()] = 0}
     / disconnected$/{if (open[id()]) { open[c] = 0; if (--n == 0) z++ }}
     END{exit !(NR > 0 && z == 1 && n == 0)}' \
    "$WORK/audit" || { cat "$WORK/audit"; fail "view's fallback to OpenGL closed its X connection before opening one"; }
echo "view's fallback to OpenGL: $(grep -c " connected from " "$WORK/audit") X connections, never none open"
expect_stderr "no Vulkan presentation (vulkan: no Vulkan 1.2 device with a compute queue that can present"
expect_stderr "OpenGL, render time"
psnr_at_least "$WORK/vk-fb.png" "$WORK/render-tet16.png" "view falling back to OpenGL, and render"
# (here and below through env, so the sanitizers' preload is passed by hand as tpk() passes it: without it
# lavapipe is loaded and unloaded with each instance, and LeakSanitizer reports its JIT's leaks from an
# unnamed module: cli.view failed so under ASan at stops 25 and 27)
expect_exit 2 env TPK_VK_NO_PRESENT=1 LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" view "$WORK/cyl.tpk" \
    --size $SIZE --frames 1 --present vulkan
expect_stderr "--present vulkan: vulkan: no Vulkan 1.2 device"
expect_exit 2 tpk view "$WORK/cyl.tpk" --frames 1 --present vulkan --backend cpu
expect_stderr "--present vulkan: the CPU reference shows frames through OpenGL"
expect_exit 2 tpk view "$WORK/cyl.tpk" --frames 1 --present metal
expect_stderr "--present expects auto, vulkan or gl, found 'metal'"
expect_exit 2 env TETPACK_VIEW_PRESENT=x LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" view "$WORK/cyl.tpk" \
    --frames 1
expect_stderr "TETPACK_VIEW_PRESENT expects"

# errors: exit 2 with a message
expect_exit 2 env -u DISPLAY LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" view "$WORK/cyl.tpk" --frames 1
expect_stderr "tetpack render writes images without one"
echo "not a tetpack file" > "$WORK/bad.tpk"
expect_exit 2 tpk view "$WORK/bad.tpk" --frames 1
expect_stderr "bad.tpk"
expect_exit 2 tpk view "$WORK/cyl.tpk" --frames 0
expect_stderr "--frames expects"
expect_exit 2 tpk view "$WORK/cyl.tpk" --field pressure --frames 1
expect_stderr "no field named 'pressure'"
expect_exit 2 tpk view "$WORK/cyl.tpk" -o "$WORK/x.png"
expect_stderr "option of tetpack render"
expect_exit 2 tpk view "$WORK/cyl.tpk" --frames 1 --screenshot "$WORK/cyl.tpk"
expect_exit 2 tpk view "$WORK/cyl.tpk" --frames 1 --keys X
expect_stderr "--keys expects"
# --iso-raster: the isosurface triangles drawn by Vulkan (each value extracted once, drawn for every
# camera), shown through OpenGL; the window's frame against render --iso-raster of the same view
tpk view "$WORK/cyl.tpk" --size $SIZE --frames 3 --iso 0.5 --shading --iso-raster --screenshot "$WORK/raster-view.png" \
    --save-scene "$WORK/raster.json" 2> "$WORK/err" || { cat "$WORK/err"; fail "view --iso-raster"; }
grep -q "isosurface triangles" "$WORK/err" || fail "view --iso-raster does not say it draws triangles: $(cat "$WORK/err")"
tpk render "$WORK/cyl.tpk" -o "$WORK/raster-render.png" --scene "$WORK/raster.json" --iso-raster > /dev/null ||
    fail "render --iso-raster of view's scene"
psnr_at_least "$WORK/raster-view.png" "$WORK/raster-render.png" "view --iso-raster and render --iso-raster"
expect_exit 2 tpk view "$WORK/cyl.tpk" --frames 1 --iso 0.5 --iso-raster --present vulkan
expect_stderr "--iso-raster shows its frames through OpenGL"
echo "view: ok"
