#!/usr/bin/env bash
# The open GPU targets of issues 21 and 22 in one short run (bench/gpu/run.sh --targets, which calls
# this; the bundle's run-gpu-bench.sh --targets), on one grid of about 10M tets (bench/make_grid_vtk.py
# 121: python3 with numpy) converted with --levels 4:
#   1. `tetpack iso --backend vulkan`: extraction, tets per second of the passes' device time (timestamps,
#      the copies to the host left out; target 5G), and of the wall time of the submissions with them;
#   2. `render --iso-raster` at 3840x2160: the isosurface as --iso-raster-path auto draws it (both paths
#      timed on the first frame, the faster kept: the row names it and both times), by the compute
#      extraction and an indirect draw (TETPACK_ISO_MESH_SHADER=0 --iso-raster-path graphics), and by the
#      compute rasterizer (--iso-raster-path compute: a visibility buffer by 64-bit atomics, then
#      shaded): the draw's GPU time (target 2 ms a frame);
#   3. iso-only rays (a clear TF) at 1024x1024, range culling forced on and off, at the dense value 0.3
#      and the sparse 0.99: GPU ms a frame;
#   4. `render --max-ms 8` at 1024x1024: the level and pixel step the budget picks and the frame's
#      GPU ms (target 8 ms);
#   5. issue 39's effects the seed paper's way on a grid of about 1M tets (make_grid_vtk.py 55,
#      TPK_GPU_EFFECTS_GRID): an isosurface (0.3, dense) with shading, shadows and AO 4 cast once per pixel at
#      its first hit, the volume the occluder (`--occlusion surface`; target 20 ms, the paper's 20.6 ms for
#      1M tets), and the same with `--occlusion ray` (up to 32 volume shade points a pixel) beside it;
#   6. `--occlusion vertex`'s first frame on that grid: the device time of the vertex cache's casts
#      (vertex_cache_seconds; target 100 ms) and of the whole frame.
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
    GRID=6 RUNS=1 ISO_SIZE=96x54 SIZE=64x64 EGRID=5 ESIZE=32x32 EISO=0.6 # grid 5's field: 0.31 .. 1
else
    GRID=${TPK_GPU_TARGET_GRID:-121} RUNS=${TPK_GPU_TARGET_RUNS:-3} ISO_SIZE=3840x2160 SIZE=1024x1024
    EGRID=${TPK_GPU_EFFECTS_GRID:-55} ESIZE=$SIZE EISO=0.3
fi
[ -n "${PYTHON:-}" ] || { echo "targets.sh: no PYTHON: run it through run.sh --targets, which finds python3 with numpy" >&2; exit 2; }
PY=$PYTHON
vk() { LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" "$@"; } # the sanitizers' preloads, as run.sh
vtk=$OUT/grid$GRID.vtk tpk=$OUT/grid${GRID}_levels.tpk
[ -s "$vtk" ] || "$PY" "$ROOT/bench/make_grid_vtk.py" "$GRID" "$vtk"
[ -s "$tpk" ] && [ "$tpk" -nt "$vtk" ] || "$TPK" convert "$vtk" "$tpk" --levels 4 --quiet
evtk=$OUT/grid$EGRID.vtk etpk=$OUT/grid$EGRID.tpk # items 5 and 6
[ -s "$evtk" ] || "$PY" "$ROOT/bench/make_grid_vtk.py" "$EGRID" "$evtk"
[ -s "$etpk" ] && [ "$etpk" -nt "$evtk" ] || "$TPK" convert "$evtk" "$etpk" --quiet
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
    run iso_raster_compute env TETPACK_ISO_MESH_SHADER=0 LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" \
        render "$tpk" -o "$OUT/raster.png" --backend vulkan --iso-raster --iso-raster-path graphics --iso 0.3 \
        --size "$ISO_SIZE" --json
    run iso_raster_vis vk render "$tpk" -o "$OUT/raster.png" --backend vulkan --iso-raster --iso-raster-path compute \
        --iso 0.3 --size "$ISO_SIZE" --json
    for value in 0.3 0.99; do
        run rays_culled_$value env TETPACK_ISO_CULLING=1 LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" \
            render "$tpk" -o "$OUT/rays.png" --backend vulkan --tf "$OUT/clear.tf" --iso $value --size "$SIZE" --json
        run rays_marched_$value env TETPACK_ISO_CULLING=0 LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" \
            render "$tpk" -o "$OUT/rays.png" --backend vulkan --tf "$OUT/clear.tf" --iso $value --size "$SIZE" --json
    done
    run budget vk render "$tpk" -o "$OUT/budget.png" --backend vulkan --max-ms 8 --size "$SIZE" --json
    for occlusion in surface ray; do
        run effects_$occlusion vk render "$etpk" -o "$OUT/effects.png" --backend vulkan --iso $EISO --shading \
            --shadows --ao 4 --occlusion $occlusion --size "$ESIZE" --json
    done
    run vertex_first vk render "$etpk" -o "$OUT/vertex.png" --backend vulkan --shading --shadows --ao 4 \
        --occlusion vertex --size "$ESIZE" --json
done
"$PY" - "$JSONL" "$EGRID" > "$OUT/targets.md" <<'EOF'
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
    timed = [r["tets"] / r["gpu_seconds"] for r in e if r.get("gpu_seconds")]
    wall = [r["tets"] / r["device_seconds"] for r in e if r.get("device_seconds")]
    out.append("| extraction on %s, %d tets | %.3g G tets/s (passes' device time); %.3g G tets/s (submissions' wall "
               "time, copies to the host included) | >= 5G |" % (e[0]["device"], e[0]["tets"], med(timed) / 1e9,
                                                                  med(wall) / 1e9))
for name in ("iso_raster", "iso_raster_compute", "iso_raster_vis"):
    i = of(name)
    if i:
        draw = [1e3 * r["iso_raster"]["draw_gpu_seconds"] for r in i if r["iso_raster"].get("draw_gpu_seconds")]
        both = [r["iso_raster"]["measured_seconds"] for r in i if r["iso_raster"].get("measured_seconds")]
        measured = "; measured: graphics %.3f ms, compute %.3f ms" % (
            med([1e3 * b["graphics"] for b in both]), med([1e3 * b["compute"] for b in both])) if both else ""
        out.append("| iso drawn %sx%s, %s (%s) | draw %.3f ms GPU; frame %.3f ms GPU; %d triangles%s | <= 2 ms |" % (
            i[0]["width"], i[0]["height"], i[0]["iso_raster"]["path"], name, med(draw), med([ms(r) for r in i]),
            i[0]["iso_raster"]["triangles"], measured))
for value in ("0.3", "0.99"):
    for name, what in (("rays_culled_" + value, "culled"), ("rays_marched_" + value, "marched")):
        g = of(name)
        if g:
            out.append("| iso-only rays %sx%s, iso %s, %s | %.3f ms GPU (iso_culling %s) | |" % (
                g[0]["width"], g[0]["height"], value, what, med([ms(r) for r in g]), g[0]["iso_culling"]))
b = of("budget")
if b:
    out.append("| --max-ms 8, %sx%s | level %s, pixel step %s: %.3f ms GPU | <= 8 ms |" % (
        b[0]["width"], b[0]["height"], ",".join(str(r["level"]) for r in b),
        ",".join(str(r["pixel_step"]) for r in b), med([r["frame_ms"] for r in b])))
n = int(sys.argv[2]) # make_grid_vtk.py's grid: 6 n^3 tets, (n + 1)^3 vertices
for name, what, goal in (("effects_surface", "--occlusion surface: one shade point a pixel", "<= 20 ms"),
                         ("effects_ray", "--occlusion ray: up to 32 volume shade points a pixel", "")):
    f = of(name)
    if f:
        out.append("| iso + shading + shadows + AO 4, %s, %d tets, %sx%s | %.3f ms GPU; %d secondary rays | %s |" % (
            what, 6 * n ** 3, f[0]["width"], f[0]["height"], med([ms(r) for r in f]), f[0]["secondary_rays"], goal))
v = of("vertex_first")
if v:
    casts = [1e3 * r.get("vertex_cache_seconds", float("nan")) for r in v]
    out.append("| --occlusion vertex, first frame, %d tets (%d vertices), shadows + AO 4 | casts %.3f ms GPU (frame "
               "%.3f ms GPU, %d secondary rays) | <= 100 ms |" % (6 * n ** 3, (n + 1) ** 3, med(casts),
                                                                 med([ms(r) for r in v]), v[0]["secondary_rays"]))
print("\n".join(out))
EOF
cat "$OUT/targets.md"
