# The first picture: --legend composites a colour bar whose pixels are the TF's colours (checked in the
# PNG against a TF file's points, linear between them), and changes nothing else of the picture but its
# corner; --iso auto is the field's median (--json iso_auto, -v) and draws what --iso with that value
# draws; the default opacity scale is bounds diagonal / 30 (the same image as --unit-distance D/30).
source "$(dirname "$0")/common.sh"

convert_checked "$SRC/samples/cylinder.vtk" "$WORK/cyl.tpk" > /dev/null
# a TF of two points: s = 0 red, s = 1 blue, both half opaque
printf '0 1 0 0 0.5\n1 0 0 1 0.5\n' > "$WORK/tf.txt"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/plain.png" --size 320x240 --tf "$WORK/tf.txt" > /dev/null
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/legend.png" --size 320x240 --tf "$WORK/tf.txt" --legend > /dev/null
"$PY" - "$SRC/tests/cli" "$WORK/plain.png" "$WORK/legend.png" <<'PYEOF' || fail "legend pixels"
import sys
sys.path.insert(0, sys.argv[1])
import numpy as np
from png_read import pixels
plain, legend = pixels(sys.argv[2]).astype(int), pixels(sys.argv[3]).astype(int)
h, w = plain.shape[:2]
# the bar's place (tools/render/legend.h, tpk_legend_place)
bw = max(h // 24, 10)
x1 = w - 1 - w // 40 - 4
x0 = x1 - bw + 1
y0, y1 = h // 6 + 14, h - 1 - h // 10
for y in range(y0, y1 + 1):
    s = (y1 - y) / (y1 - y0)
    want = np.array([255 * (1 - s), 0, 255 * s])
    for x in (x0, (x0 + x1) // 2, x1):
        got = legend[y, x, :3]
        assert np.abs(got - want).max() <= 1, (x, y, got, want)
        assert legend[y, x, 3] == 255
changed = np.argwhere((plain != legend).any(axis=2))
assert changed[:, 1].min() > w // 2, "the legend changed pixels left of the image's middle"
assert len(changed) > (y1 - y0) * bw, "the legend is smaller than its bar"
print("legend ok: bar %d..%d x %d..%d, %d pixels changed" % (x0, x1, y0, y1, len(changed)))
PYEOF
expect_exit 2 "$TPK" render "$WORK/cyl.tpk" -o "$WORK/tiny.png" --size 60x40 --legend
expect_stderr "too small for a legend"

# --iso auto: the median, said by --json and -v, and the same picture as --iso with that value
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/auto.png" --size 96x72 --iso auto --json -v > "$WORK/auto.json" 2> "$WORK/auto.err"
value=$("$PY" -c 'import json,sys; print(repr(json.load(open(sys.argv[1]))["iso_auto"]))' "$WORK/auto.json")
grep -q "iso auto: .*the median of 'temperature' at step 0" "$WORK/auto.err" || fail "-v: $(cat "$WORK/auto.err")"
"$TPK" export "$WORK/cyl.tpk" --vtu "$WORK/cyl.vtu" > /dev/null
"$PY" - "$WORK/cyl.vtu" "$value" <<'PYEOF' || fail "iso_auto is not the median"
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
median = float(np.median(m.point_data["temperature"].astype(np.float32)))
assert abs(median - float(sys.argv[2])) <= 1e-6 * abs(median), (median, sys.argv[2])
PYEOF
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/iso.png" --size 96x72 --iso "$value" > /dev/null
cmp -s "$WORK/auto.png" "$WORK/iso.png" || fail "--iso auto differs from --iso $value"

# the default opacity: per bounds diagonal / 30
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/default.png" --size 96x72 --save-scene "$WORK/default.json" > /dev/null
unit=$("$PY" -c 'import json,sys; print(repr(json.load(open(sys.argv[1]))["unit_distance"]))' "$WORK/default.json")
diag=$("$TPK" info "$WORK/cyl.tpk" --json | "$PY" -c '
import json, sys, math
b = json.load(sys.stdin)["bounds"]
print(repr(math.dist(b["min"], b["max"])))')
"$PY" -c "import sys; assert abs($unit - $diag / 30) <= 1e-9 * $diag, ($unit, $diag)" || fail "default unit distance $unit, diagonal $diag"
"$TPK" render "$WORK/cyl.tpk" -o "$WORK/explicit.png" --size 96x72 --unit-distance "$unit" > /dev/null
cmp -s "$WORK/default.png" "$WORK/explicit.png" || fail "the default differs from --unit-distance diagonal/30"
echo ok
