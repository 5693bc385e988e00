#!/usr/bin/env bash
# Issue 39's size target: a part set of at least 1G tets rendered on one GPU (E+A, Tet16, 1024x1024),
# its parts resident as one mesh (libtetpack/set_mesh.c), against device memory per tet (target <= 22
# B/tet) and the frame's GPU time (target <= 30 ms). Called by run.sh --partset [--small] as
# partset.sh TETPACK OUT_DIR SMALL (1: the test form, ctest bench.gpu_partset_small: grid 6, 3 parts,
# 32x32, 1 run).
# Sized for the GPU host (16 cores, 128 GB of memory, 64 GB of disk, at most 10 minutes a command): run
# it in stages, each one command, each skipped when its output is there (TPK_GPU_PARTSET_STAGE=grid,
# convert, render, or all, the default):
#   grid     make_grid_vtk.py N --stream: grid 551 (6 x 551^3 = 1,003,612,806 tets), 26 GB, about 27 B a
#            tet, a plane of cubes at a time (memory: 0.7 GB of scalars and one plane)
#   convert  tetpack convert --parts P (16): measured 84 MB of peak RSS per 1M tets on grid 55, so about
#            84 GB here; grid 200 (48M tets) converts in 9-11 s on the host's 16 cores, so about 4 min
#            at 1G; the parts take about 26 B a tet (26 GB); the VTK is removed once the set is written,
#            so the disk holds at most both (52 GB)
#   render   RUNS (2) renders of the set with Vulkan: each merges the parts (one thread per core) and
#            uploads them, then draws one frame; the JSON lines in partset.jsonl, the table in
#            partset.md; then the CPU reference's picture at 256x256 (the link-following marcher over the
#            parts) against Vulkan's, PSNR (TPK_GPU_PSNR=0 skips it)
# A Tet16 set past 8 bindings of the device's texel limit is refused with a message: with NVIDIA's 2^27
# texels a binding, 1.07G tets at most. TPK_GPU_PARTSET_GRID (551), TPK_GPU_PARTSET_PARTS (16),
# TPK_GPU_PARTSET_RUNS (2) and TPK_GPU_SIZE (1024) change the sizes.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
TPK=$1 OUT=$2 SMALL=$3
[ -x "$TPK" ] || { echo "partset.sh: no tetpack at $TPK" >&2; exit 2; }
[ -n "${PYTHON:-}" ] || { echo "partset.sh: no PYTHON: run it through run.sh --partset, which finds python3 with numpy" >&2; exit 2; }
PY=$PYTHON
if [ "$SMALL" = 1 ]; then
    GRID=6 PARTS=3 RUNS=1 SIZE=32 CPU_SIZE=32
else
    GRID=${TPK_GPU_PARTSET_GRID:-551} PARTS=${TPK_GPU_PARTSET_PARTS:-16} RUNS=${TPK_GPU_PARTSET_RUNS:-2}
    SIZE=${TPK_GPU_SIZE:-1024} CPU_SIZE=256
fi
STAGE=${TPK_GPU_PARTSET_STAGE:-all}
mkdir -p "$OUT"
vtk=$OUT/grid${GRID}_stream.vtk set=$OUT/grid${GRID}_p$PARTS.tpkset
vk() { LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$TPK" "$@"; } # the sanitizers' preloads, as run.sh
now() { date +%s.%N; }

if [ "$STAGE" = all ] || [ "$STAGE" = grid ]; then
    if [ ! -s "$set" ] && [ ! -s "$vtk" ]; then
        echo "# grid $GRID: $((6 * GRID * GRID * GRID)) tets" >&2
        t0=$(now)
        "$PY" "$ROOT/bench/make_grid_vtk.py" "$GRID" "$vtk.part" --stream && mv "$vtk.part" "$vtk"
        echo "# grid written in $("$PY" -c "print('%.1f' % ($(now) - $t0))") s: $(du -h "$vtk" | cut -f1)" >&2
    fi
fi
if [ "$STAGE" = all ] || [ "$STAGE" = convert ]; then
    if [ ! -s "$set" ]; then
        t0=$(now)
        timed=()
        [ ! -x /usr/bin/time ] || timed=(/usr/bin/time -f "# convert --parts $PARTS: %e s, peak RSS %M KB")
        "${timed[@]}" "$TPK" convert "$vtk" "$set" --parts "$PARTS" --quiet
        echo "# converted in $("$PY" -c "print('%.1f' % ($(now) - $t0))") s" >&2
        [ "$SMALL" = 1 ] || rm -f "$vtk" # the disk holds the set alone from here on
    fi
fi
[ "$STAGE" = all ] || [ "$STAGE" = render ] || exit 0
[ -s "$set" ] || { echo "partset.sh: no $set: run the grid and convert stages first" >&2; exit 2; }
JSONL=$OUT/partset.jsonl
: > "$JSONL"
part_bytes=$(cat "$set" "${set%.tpkset}"-*.tpk | wc -c)
for r in $(seq "$RUNS"); do
    t0=$(now)
    vk render "$set" -o "$OUT/partset.png" --backend vulkan --size "${SIZE}x$SIZE" --json > "$OUT/partset.json"
    wall=$("$PY" -c "print($(now) - $t0)")
    "$PY" -c 'import json,sys; d=json.load(open(sys.argv[1])); d["command_seconds"]=float(sys.argv[2]); d["part_bytes"]=int(sys.argv[3]); print(json.dumps(d))' \
        "$OUT/partset.json" "$wall" "$part_bytes" >> "$JSONL"
done
psnr=skipped
if [ "${TPK_GPU_PSNR:-1}" != 0 ]; then
    vk render "$set" -o "$OUT/partset_vk_small.png" --backend vulkan --size "${CPU_SIZE}x$CPU_SIZE" > /dev/null
    "$TPK" render "$set" -o "$OUT/partset_cpu_small.png" --backend cpu --size "${CPU_SIZE}x$CPU_SIZE" > /dev/null
    psnr=$("$PY" "$ROOT/tests/cli/psnr.py" "$OUT/partset_cpu_small.png" "$OUT/partset_vk_small.png" 2>/dev/null ||
           echo "no psnr.py here")
fi
"$PY" - "$JSONL" "$GRID" "$PARTS" "$CPU_SIZE" "$psnr" > "$OUT/partset.md" <<'EOF'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
grid, parts, cpu_size, psnr = int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5]
tets = 6 * grid ** 3
r = rows[0]
def med(key):
    values = [x[key] for x in rows if x.get(key) is not None]
    return statistics.median(values) if values else float("nan")
print("| part set: grid %d, %d parts, %s tets, %s | median of %d | goal |" % (grid, parts, format(tets, ","), r["device"], len(rows)))
print("|---|---|---|")
print("| E+A %dx%d, Tet16: frame GPU time | %.3f ms | <= 30 ms |" % (r["width"], r["height"], 1e3 * med("gpu_seconds")))
print("| device memory | %s bytes, %.2f B/tet | <= 22 B/tet |" % (format(r["device_bytes"], ","), r["device_bytes"] / tets))
print("| the parts' file bytes (manifest included) | %s bytes, %.2f B/tet; device / files %.2f | about 1 |" % (
    format(r["part_bytes"], ","), r["part_bytes"] / tets, r["device_bytes"] / r["part_bytes"]))
print("| render command: merge, upload and frame (wall) | %.1f s (upload %.1f s, pipeline %.1f s) | |" % (
    med("command_seconds"), statistics.median(x["setup"]["upload"] for x in rows),
    statistics.median(x["setup"]["pipeline"] for x in rows)))
print("| CPU reference against Vulkan, %sx%s | %s | >= 60 dB |" % (cpu_size, cpu_size, psnr))
EOF
cat "$OUT/partset.md"
