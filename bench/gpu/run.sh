#!/usr/bin/env bash
# The GPU benchmark in one command (issue 19): per mesh and layout, the Vulkan renderer's setup
# (device, upload, pipeline, first frame), median frame time wall and GPU, tet steps per second, device
# bytes per tet and PSNR against the CPU reference, for E+A, each effect alone, then all together.
#   bench/gpu/run.sh [--small] [--bin DIR] [--out DIR]
#   bench/gpu/run.sh --targets [--small] [--bin DIR] [--out DIR]: instead, the open GPU targets of
#   issues 21 and 22 (bench/gpu/targets.sh)
#   bench/gpu/run.sh --convert [--small] [--bin DIR] [--out DIR]: instead, issue 22's conversion target,
#   `convert --levels 4` against `convert` and the file sizes, on this machine's cores, no GPU used
#   (bench/gpu/convert_ratio.sh)
#   bench/gpu/run.sh --scaling [--small] [--bin DIR] [--out DIR]: instead, issue 37's scaling table on this
#   machine's cores, no GPU used (bench/scaling.sh: grids 120 and 200 at 1, 2, 4, ... threads)
#   bench/gpu/run.sh --partset [--small] [--bin DIR] [--out DIR]: instead, issue 39's 1G-tet part set made,
#   cut into 16 parts and rendered on one GPU, in stages of under 10 minutes (bench/gpu/partset.sh)
# --bin: where `tetpack` and `bench_gpu` are (default: build-release, configured and built here when it
# does not exist; the bundle passes its own bin/). --out: results (default bench/gpu/out): results.jsonl
# (one JSON line per mesh, layout and effect set), results.md (a Markdown table), the .tpk files.
# --small: the test form (ctest bench.gpu_small): the sample cylinder, 32x32, 2 frames, Tet16, E+A and
# all effects.
# Meshes (full form): sfepy/cube_big_tetra.mesh, grids of 1M, 6M and 48M tets (bench/make_grid_vtk.py
# 55, 100 and 200: python3 with numpy; skipped with a note without), and nasa_refine's ONERA M6 wing
# (a CFD mesh). TPK_GPU_MESHES (paths, space separated) replaces the list; TPK_GPU_GRIDS the grid sizes;
# TPK_GPU_SIZE (1024), TPK_GPU_FRAMES (10), TPK_GPU_EFFECTS (ea,shading,shadows,ao4,all,iso_raster: the
# isosurface drawn as triangles, by task and mesh shaders where the device has them, at TPK_GPU_ISO_SIZE,
# default 3840x2160),
# TPK_GPU_PSNR=0 skips the CPU reference. VK_DRIVER_FILES names the vendor's ICD JSON when the loader
# does not find it; TPK_VK_DEVICE=N picks a device.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
SMALL=0 TARGETS=0 CONVERT=0 SCALING=0 PARTSET=0 BIN="" OUT="$HERE/out"
while [ $# -gt 0 ]; do
    case "$1" in
        --small) SMALL=1 ;;
        --targets) TARGETS=1 ;;
        --convert) CONVERT=1 ;;
        --scaling) SCALING=1 ;;
        --partset) PARTSET=1 ;;
        --bin) BIN=$2; shift ;;
        --out) OUT=$2; shift ;;
        *) echo "usage: bench/gpu/run.sh [--targets | --convert | --scaling | --partset] [--small] [--bin DIR] [--out DIR]" >&2; exit 2 ;;
    esac
    shift
done
DATA=${TPK_DATA_DIR:-$ROOT/../shared/data}
if [ -z "$BIN" ]; then
    BIN=$ROOT/build-release
    [ -f "$BIN/CMakeCache.txt" ] || cmake -S "$ROOT" -B "$BIN" -DCMAKE_BUILD_TYPE=Release -DTETPACK_WITH_TESTS=OFF >/dev/null
    cmake --build "$BIN" -j"$(nproc)" --target tetpack_cli bench_gpu >/dev/null
fi
TPK=$BIN/tetpack
if [ $TARGETS = 1 ] || [ $CONVERT = 1 ] || [ $SCALING = 1 ] || [ $PARTSET = 1 ]; then # all make a grid: the first python3 with numpy
    PY=${PYTHON:-}
    for c in python3 /usr/bin/python3; do
        [ -n "$PY" ] || ! "$c" -c "import numpy" 2>/dev/null || PY=$c
    done
    [ -n "$PY" ] || { echo "run.sh: make_grid_vtk.py needs python3 with numpy (or set PYTHON)" >&2; exit 2; }
    export PYTHON=$PY
fi
[ $TARGETS = 0 ] || exec bash "$HERE/targets.sh" "$TPK" "$OUT" "$SMALL"
[ $CONVERT = 0 ] || exec bash "$HERE/convert_ratio.sh" "$TPK" "$OUT" "$SMALL"
[ $SCALING = 0 ] || exec bash "$HERE/../scaling.sh" "$TPK" "$OUT" "$SMALL"
[ $PARTSET = 0 ] || exec bash "$HERE/partset.sh" "$TPK" "$OUT" "$SMALL"
GPU=$BIN/bench_gpu
[ -x "$GPU" ] || GPU=$BIN/bench/bench_gpu
[ -x "$TPK" ] && [ -x "$GPU" ] || { echo "run.sh: no tetpack and bench_gpu in $BIN" >&2; exit 2; }
mkdir -p "$OUT"
RESULTS=$OUT/results.jsonl
: > "$RESULTS"

if [ $SMALL = 1 ]; then
    SIZE=${TPK_GPU_SIZE:-32} FRAMES=${TPK_GPU_FRAMES:-2} LAYOUTS="tet16"
    MESHES=${TPK_GPU_MESHES:-$ROOT/samples/cylinder.vtk} GRIDS=""
    EFFECTS=${TPK_GPU_EFFECTS:-ea,all,iso_raster}
    export TPK_GPU_ISO_SIZE=${TPK_GPU_ISO_SIZE:-48x32}
else
    SIZE=${TPK_GPU_SIZE:-1024} FRAMES=${TPK_GPU_FRAMES:-10} LAYOUTS="tet16 tet20 tet32"
    MESHES=${TPK_GPU_MESHES:-"$DATA/sfepy/cube_big_tetra.mesh $DATA/nasa_refine/om6_om6-curv-no-geom.meshb"}
    GRIDS=${TPK_GPU_GRIDS:-"55 100 200"}
fi
EFFECTS=${EFFECTS:-${TPK_GPU_EFFECTS:-ea,shading,shadows,ao4,all,iso_raster}}

# the grids: made once, kept in $OUT (a 48M-tet grid takes minutes and a few GiB)
for n in $GRIDS; do
    vtk=$OUT/grid$n.vtk
    if [ ! -s "$vtk" ]; then
        if python3 -c "import numpy" 2>/dev/null; then
            python3 "$ROOT/bench/make_grid_vtk.py" "$n" "$vtk.part" >&2 && mv "$vtk.part" "$vtk"
        else
            echo "# grid $n skipped: make_grid_vtk.py needs python3 with numpy (or put grid$n.vtk in $OUT)" >&2
            continue
        fi
    fi
    MESHES="$MESHES $vtk"
done

layout_args=""
for l in $LAYOUTS; do layout_args="$layout_args --layout $l"; done
for mesh in $MESHES; do
    name=$(basename "$mesh")
    name=${name%.*}
    tpk=$OUT/$name.tpk
    [ -s "$tpk" ] && [ "$tpk" -nt "$mesh" ] || "$TPK" convert "$mesh" "$tpk" $layout_args --quiet
    echo "# $name: ${SIZE}x${SIZE}, $FRAMES frames, effects $EFFECTS" >&2
    # under the sanitizers (tests/CMakeLists.txt) libasan and the driver are preloaded for this run only
    LD_PRELOAD="${TPK_VK_PRELOAD:-${LD_PRELOAD:-}}" "$GPU" "$tpk" "$name" "$SIZE" "$FRAMES" "$EFFECTS" | tee -a "$RESULTS"
done
python3 "$HERE/table.py" "$RESULTS" > "$OUT/results.md"
cat "$OUT/results.md"
