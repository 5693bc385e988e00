#!/usr/bin/env bash
# The open GPU targets of issues 21 and 22 in one short run (bench/gpu/run.sh --targets, which calls
# this; the bundle's run-gpu-bench.sh --targets), on one grid of about 10M tets (bench/make_grid_vtk.py
# 121: python3 with numpy) converted with --levels 4:
#   1. `tetpack iso --backend vulkan`: extraction, tets per second of the device's time (target 5G);
#   2. `render --iso-raster` at 3840x2160: the isosurface by task and mesh shaders where the device has
#      them (target 2 ms of GPU time a frame);
#   3. iso-only rays (a clear TF) at 1024x1024, range culling forced on and off: GPU ms a frame;
#   4. `render --max-ms 8` at 1024x1024: the level and pixel step the budget picks and the frame's
#      GPU ms (target 8 ms).
# Each is run RUNS times (3); the medians go to targets.md, every run's JSON to targets.jsonl.
# Called by run.sh --targets [--small] [--bin DIR] [--out DIR] as targets.sh TETPACK OUT_DIR SMALL (1: the
# test form, ctest bench.gpu_targets_small: grid 6, small pictures, 1 run).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
TPK=$1 OUT=$2 SMALL=$3
[ -x "$TPK" ] || { echo "targets.sh: no tetpack at $TPK" >&2; exit 2; }
mkdir -p "$OUT"
if [ "$SMALL" = 1 ]; then
    GRID=6 RUNS=1 ISO_SIZE=96x54 SIZE=64x64
else
    GRID=${TPK_GPU_TARGET_GRID:-121} RUNS=${TPK_GPU_TARGET_RUNS:-3} ISO_SIZE=3840x2160 SIZE=1024x1024
fi
PY=${PYTHON:-}
for c in python3 /usr/bin/python3; do # the first with numpy, for make_grid_vtk.py
    [ -n "$PY" ] || ! "$c" -c "import numpy" 2>/dev/null || PY=$c
done
[ -n "$PY" ] || { echo "targets.sh: make_grid_vtk.py needs python3 with numpy (or set PYTHON)" >&2; exit 2; }
vk() { LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" "$@"; } # the sanitizers' preloads, as run.sh
vtk=$OUT/grid$GRID.vtk tpk=$OUT/grid${GRID}_levels.tpk
[ -s "$vtk" ] || "$PY" "$ROOT/bench/make_grid_vtk.py" "$GRID" "$vtk"
[ -s "$tpk" ] && [ "$tpk" -nt "$vtk" ] || "$TPK" convert "$vtk" "$tpk" --levels 4 --quiet
printf '0 0.2 0.4 0.9 0\n1 0.9 0.2 0.1 0\n' > "$OUT/clear.tf" # opacity 0: iso-only rays
JSONL=$OUT/targets.jsonl
: > "$JSONL"
run() { # NAME, then the command: its JSON line, tagged
    local name=$1
    shift
    "$@" | "$PY" -c 'import json,sys; d=json.loads(sys.stdin.readline()); d["target"]=sys.argv[1]; print(json.dumps(d))' \
        "$name" >> "$JSONL"
}
for r in $(seq "$RUNS"); do
    echo "# run $r of $RUNS: grid $GRID" >&2
    run extract vk iso "$tpk" "$OUT/iso.ply" --value 0.3 --backend vulkan --json
    run iso_raster vk render "$tpk" -o "$OUT/raster.png" --backend vulkan --iso-raster --iso 0.3 --size "$ISO_SIZE" --json
    run rays_culled env TETPACK_ISO_CULLING=1 LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" render "$tpk" \
        -o "$OUT/rays.png" --backend vulkan --tf "$OUT/clear.tf" --iso 0.3 --size "$SIZE" --json
    run rays_marched env TETPACK_ISO_CULLING=0 LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" render "$tpk" \
        -o "$OUT/rays.png" --backend vulkan --tf "$OUT/clear.tf" --iso 0.3 --size "$SIZE" --json
    run budget vk render "$tpk" -o "$OUT/budget.png" --backend vulkan --max-ms 8 --size "$SIZE" --json
done
"$PY" - "$JSONL" > "$OUT/targets.md" <<'EOF'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
def of(name):
    return [r for r in rows if r["target"] == name]
def med(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else float("nan")
def ms(r):
    return 1e3 * r["gpu_seconds"] if r.get("gpu_seconds") is not None else float("nan")
out = ["| target | measured (median of %d) | goal |" % len(of("extract")), "|---|---|---|"]
e = of("extract")
if e:
    rate = med([r["tets"] / r["device_seconds"] for r in e if r.get("device_seconds")])
    out.append("| extraction on %s, %d tets | %.3g G tets/s (device time) | >= 5G |" % (e[0]["device"], e[0]["tets"], rate / 1e9))
i = of("iso_raster")
if i:
    out.append("| iso drawn %sx%s, %s | %.3f ms GPU, %d triangles | <= 2 ms |" % (
        i[0]["width"], i[0]["height"], i[0]["iso_raster"]["path"], med([ms(r) for r in i]),
        i[0]["iso_raster"]["triangles"]))
for name, what in (("rays_culled", "culled"), ("rays_marched", "marched")):
    g = of(name)
    if g:
        out.append("| iso-only rays %sx%s, %s | %.3f ms GPU (iso_culling %s) | |" % (
            g[0]["width"], g[0]["height"], what, med([ms(r) for r in g]), g[0]["iso_culling"]))
b = of("budget")
if b:
    out.append("| --max-ms 8, %sx%s | level %s, pixel step %s: %.3f ms GPU | <= 8 ms |" % (
        b[0]["width"], b[0]["height"], ",".join(str(r["level"]) for r in b),
        ",".join(str(r["pixel_step"]) for r in b), med([r["frame_ms"] for r in b])))
print("\n".join(out))
EOF
cat "$OUT/targets.md"
