# tetpack render's effects on the bundled sample and a real Exodus mesh: each option changes the picture
# the way its definition (render.h, docs/ARCHITECTURE.md "Render effects") says, measured on the pixels;
# tet fields and step ranges; the same bytes on 1 and 2 threads with every effect on; bad options.
source "$(dirname "$0")/common.sh"

convert_checked "$SRC/samples/cylinder.vtk" "$WORK/c.tpk" --quiet
"$TPK" info "$WORK/c.tpk" --json > "$WORK/c.json"
printf '0 1 0 0 0\n1 0 0 1 0\n' > "$WORK/clear.tf"   # red to blue, transparent: only isosurfaces show
R() { "$TPK" render "$@" --size 80x60 > /dev/null; }
R "$WORK/c.tpk" -o "$WORK/plain.png"
R "$WORK/c.tpk" -o "$WORK/iso.png" --tf "$WORK/clear.tf" --iso 335
R "$WORK/c.tpk" -o "$WORK/iso_shaded.png" --tf "$WORK/clear.tf" --iso 335 --shading --light 0.3,0.2,0.1
R "$WORK/c.tpk" -o "$WORK/clip_none.png" --clip-box 1,1,1,2,2,2
R "$WORK/c.tpk" -o "$WORK/clip_half.png" --clip-box -1,-1,-1,0.05,1,1
R "$WORK/c.tpk" -o "$WORK/shaded.png" --shading --light -0.1,0,0
R "$WORK/c.tpk" -o "$WORK/shadows.png" --shading --shadows --light -0.1,0,0
R "$WORK/c.tpk" -o "$WORK/ao.png" --ao 4
R "$WORK/c.tpk" -o "$WORK/ao_short.png" --ao 4 --ao-radius 0.001
R "$WORK/c.tpk" -o "$WORK/midpoint.png" --integration midpoint
"$PY" - "$WORK" "$(dirname "$0")" <<'PY'
import json, sys
import numpy as np
sys.path.insert(0, sys.argv[2])
from png_read import pixels
w = sys.argv[1]
img = {n: pixels("%s/%s.png" % (w, n)) for n in
       ["plain", "iso", "iso_shaded", "clip_none", "clip_half", "shaded", "shadows", "ao", "ao_short", "midpoint"]}
bg = img["plain"][0, 0]
def shown(a):
    return np.any(a != bg, axis=2)
field = json.load(open(w + "/c.json"))["fields"][0]
lo, hi = field["min"], field["max"]
u = (335 - lo) / (hi - lo)
# iso, no shading: every pixel that shows anything is the TF colour at 335, opaque
iso = img["iso"][shown(img["iso"])]
assert len(iso) > 100, len(iso)
expect = np.array([255 * (1 - u), 0, 255 * u, 255])
assert np.abs(iso - expect).max() <= 1, (iso[:3], expect)
# shaded: the same hue, scaled by 0.3..1 (red / blue stays (1-u) / u)
sh = img["iso_shaded"][shown(img["iso_shaded"])].astype(float)
assert np.array_equal(shown(img["iso_shaded"]), shown(img["iso"]))
scale = sh[:, 2] / (255 * u)
assert scale.min() >= 0.3 - 0.01 and scale.max() <= 1.0 + 0.01 and scale.max() - scale.min() > 0.1, (scale.min(), scale.max())
assert np.abs(sh[:, 0] - scale * 255 * (1 - u)).max() <= 1.5
# clip: a box beside the mesh leaves the background; x <= 0.05 keeps about half
assert not shown(img["clip_none"]).any()
ratio = shown(img["clip_half"]).sum() / shown(img["plain"]).sum()
assert 0.3 < ratio < 0.7, ratio
# shadows and AO only darken, and do darken
for dark, light in [("shadows", "shaded"), ("ao", "plain")]:
    d = img[dark][..., :3].astype(int) - img[light][..., :3]
    assert d.max() <= 1 and (d < -2).sum() > 50, (dark, d.max(), (d < -2).sum())
# shorter AO rays see less volume: brighter than the default length, darker than none
short = img["ao_short"][..., :3].astype(int)
assert (short - img["ao"][..., :3]).min() >= -1 and (img["plain"][..., :3] - short).min() >= -1
assert (short > img["ao"][..., :3] + 2).sum() > 50
# one sample per piece: close to the exact integral, not the same
d = np.abs(img["midpoint"].astype(int) - img["plain"])
assert 0 < d.max() and d.mean() < 2, (d.max(), d.mean())
PY

# every effect on: 1 and 2 threads give the same file
ALL=(--iso 320,350 --iso-opacity 0.6 --clip-box -1,-1,-1,0.07,1,1 --shading --shadows --light 0.2,0.1,0.1 --ao 3)
R "$WORK/c.tpk" -o "$WORK/all1.png" "${ALL[@]}" --threads 1
R "$WORK/c.tpk" -o "$WORK/all2.png" "${ALL[@]}" --threads 2
cmp "$WORK/all1.png" "$WORK/all2.png" || fail "the thread count changes the picture with effects on"

# A tet field (Exodus element variable, 5 steps) against the same values averaged to points.
EXO="$DATA/seacas/exomerge_unit_test.e"
convert_checked "$EXO" "$WORK/e.tpk" --field pressure --field disp_z --quiet
convert_checked "$EXO" "$WORK/ep.tpk" --cell-to-point --field pressure --quiet
R "$WORK/e.tpk" -o "$WORK/tet.png" --field pressure --step 4 --range 0,1.4e9
R "$WORK/ep.tpk" -o "$WORK/point.png" --field pressure --step 4 --range 0,1.4e9
R "$WORK/e.tpk" -o "$WORK/tet_iso.png" --field pressure --step 4 --range 0,1.4e9 --tf "$WORK/clear.tf" --iso 1.345e9
"$TPK" render "$WORK/e.tpk" -o "$WORK/frame_%04d.png" --field pressure --steps 0:4 --range 0,1.4e9 --size 80x60 > "$WORK/steps.out"
[ "$(grep -c 'frame_000[0-4].png' "$WORK/steps.out")" = 5 ] || fail "--steps 0:4 did not report 5 frames"
cmp "$WORK/frame_0004.png" "$WORK/tet.png" || fail "frame 4 of --steps differs from --step 4"
# A point field over steps: one render keeps its marcher (and vertex cache) from step to step and hands
# it each step's field, so every frame must be that step's picture alone: iso-only at each step's median
# (the range trees made again for each field, culled, against one step marched) and with vertex AO.
ISOS=3.343e8,6.702e8,1.0077e9,1.3469e9
PS=(--field pressure --range 0,1.4e9 --size 80x60)
TETPACK_ISO_CULLING=1 "$TPK" render "$WORK/ep.tpk" -o "$WORK/pi_%d.png" "${PS[@]}" --tf "$WORK/clear.tf" --iso $ISOS \
    --steps 0:4 > /dev/null
"$TPK" render "$WORK/ep.tpk" -o "$WORK/pa_%d.png" "${PS[@]}" --ao 3 --occlusion vertex --steps 0:4 > /dev/null
for s in 1 2 4; do
    TETPACK_ISO_CULLING=0 R "$WORK/ep.tpk" -o "$WORK/one_i.png" "${PS[@]}" --tf "$WORK/clear.tf" --iso $ISOS --step $s
    cmp "$WORK/pi_$s.png" "$WORK/one_i.png" || fail "--steps: frame $s (iso, culled) differs from --step $s alone"
    R "$WORK/ep.tpk" -o "$WORK/one_a.png" "${PS[@]}" --ao 3 --occlusion vertex --step $s
    cmp "$WORK/pa_$s.png" "$WORK/one_a.png" || fail "--steps: frame $s (vertex AO) differs from --step $s alone"
done
# The automatic culling choice of each --steps frame is that of its step alone: each step's range trees
# serve one frame, not TPK_RENDER_KEPT_FRAMES (40x30 rays with these values: step 3 marches alone, and
# with the trees counted as paid by 8 frames it culled).
FEW=(--field pressure --range 0,1.4e9 --size 40x30 --tf "$WORK/clear.tf" --iso 2e8,6e8,1e9)
culled() {
    "$PY" -c 'import json, sys; print("".join("1" if json.loads(l)["iso_culling"] else "0" for l in sys.stdin))'
}
auto() { env -u TETPACK_ISO_CULLING "$TPK" render "$WORK/ep.tpk" "${FEW[@]}" --json "$@"; }
steps=$(auto -o "$WORK/pf_%d.png" --steps 0:4 | culled)
alone=$(for s in 0 1 2 3 4; do auto -o "$WORK/one_f.png" --step $s; done | culled)
[ "$steps" = "$alone" ] || fail "--steps: the frames' culling choices $steps are not those of each step alone, $alone"
case "$alone" in
*0*1* | *1*0*) ;;
*) fail "the culling choices of the steps alone, $alone, are not mixed: the check above checks nothing" ;;
esac
cmp -s "$WORK/pi_1.png" "$WORK/pi_4.png" && fail "--steps: the isosurfaces of steps 1 and 4 look the same"
cmp -s "$WORK/pa_1.png" "$WORK/pa_4.png" && fail "--steps: steps 1 and 4 look the same with vertex AO"
"$PY" - "$WORK" "$(dirname "$0")" <<'PY'
import sys
import numpy as np
sys.path.insert(0, sys.argv[2])
from png_read import pixels
w = sys.argv[1]
tet, point, iso = pixels(w + "/tet.png"), pixels(w + "/point.png"), pixels(w + "/tet_iso.png")
bg = tet[0, 0]
d = np.abs(tet.astype(int) - point)
assert d.max() > 10, "the tet field renders like its point average: %d" % d.max()
hit = iso[np.any(iso != bg, axis=2)]
assert len(hit) > 20, len(hit)
u = 1.345e9 / 1.4e9  # step 4 spans 1.25e9 .. 1.40e9 (median 1.347e9)
assert np.abs(hit - [255 * (1 - u), 0, 255 * u, 255]).max() <= 1, hit[:3]
f0, f4 = pixels(w + "/frame_0000.png"), pixels(w + "/frame_0004.png")
assert np.abs(f0.astype(int) - f4).max() > 10, "steps 0 and 4 look the same"
PY

# Bad options: exit 2 with a message, no image.
expect_exit 2 "$TPK" render "$WORK/e.tpk" -o "$WORK/x.png" --field pressure --steps 0:2
expect_stderr "one %d conversion"
expect_exit 2 "$TPK" render "$WORK/e.tpk" -o "$WORK/x_%d.png" --field pressure --steps 3:9
expect_stderr "field 'pressure' has 5 step(s) (0..4), step 9 asked"
expect_exit 2 "$TPK" render "$WORK/c.tpk" -o "$WORK/x.png" --iso 1,2,3,4,5
expect_stderr "--iso expects 1 to 4"
expect_exit 2 "$TPK" render "$WORK/c.tpk" -o "$WORK/x.png" --clip-box 1,1,1,0,0,0
expect_stderr "--clip-box expects 6 numbers"
expect_exit 2 "$TPK" render "$WORK/c.tpk" -o "$WORK/x.png" --ao 1025
expect_stderr "--ao expects a ray count 0..1024 (0: off), found '1025'"
expect_exit 2 "$TPK" render "$WORK/c.tpk" -o "$WORK/x.png" --integration trapezoid
expect_stderr "exact, sampled or midpoint"
expect_exit 2 "$TPK" render "$WORK/c.tpk" -o "$WORK/x.png" --light 1,2
ls "$WORK"/x*.png 2>/dev/null && fail "an image was left by a refused command"
# --ao 0 is AO off, as in a scene (effects.ao_rays 0): the option table gives both the range 0..1024
"$TPK" render "$WORK/c.tpk" -o "$WORK/ao0.png" --size 32x24 --ao 0 > /dev/null || fail "--ao 0 refused"
"$TPK" render "$WORK/c.tpk" -o "$WORK/noao.png" --size 32x24 > /dev/null || fail "render failed"
cmp -s "$WORK/ao0.png" "$WORK/noao.png" || fail "--ao 0 differs from no AO"
exit 0
