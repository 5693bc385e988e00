#!/usr/bin/env bash
# The Vulkan renderer against the CPU reference on the same meshes and the same cores, in one run:
#   ./bench/bench_render_vk.sh [build-dir] (default build-release, built here)
# Per mesh and layout, one JSON line (bench_render_vk): median frame time and tet steps/s of both, the
# Vulkan setup apart. Lavapipe and the CPU reference both get TPK_BENCH_THREADS threads (default 2).
# Meshes: sfepy/cube_big_tetra.mesh (202,596 tets) and sfepy/piezo_mesh_micro.vtk (42,744 tets) from
# ../shared/data, and TPK_BENCH_EXTRA (more meshes, space separated). Then, per mesh and layout, one JSON
# line of device memory against the file: a file holding only that layout (uncompressed), and the
# renderer's device bytes for it (`render --json` device_bytes: arrays, BVH, image band, parameters).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build-release}
DATA=${TPK_DATA_DIR:-../shared/data}
THREADS=${TPK_BENCH_THREADS:-2}
SIZE=${TPK_BENCH_IMAGE:-512}
FRAMES=${TPK_BENCH_FRAMES:-5}
WORK=${TPK_BENCH_DIR:-/tmp/tpk_bench_vk}
mkdir -p "$WORK"
# A build directory that exists keeps its configuration; a new one is configured for Release.
[ -f "$BUILD/CMakeCache.txt" ] || cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DTETPACK_WITH_TESTS=OFF >/dev/null
cmake --build "$BUILD" -j"$THREADS" --target tetpack_cli bench_render_vk >/dev/null
for mesh in "$DATA/sfepy/cube_big_tetra.mesh" "$DATA/sfepy/piezo_mesh_micro.vtk" ${TPK_BENCH_EXTRA:-}; do
    name=$(basename "$mesh")
    "$BUILD/tetpack" convert "$mesh" "$WORK/$name.tpk" --layout tet16 --layout tet20 --layout tet32 >/dev/null
    echo "# $name, ${SIZE}x${SIZE}, $FRAMES frames, $THREADS threads" >&2
    LP_NUM_THREADS=$THREADS "$BUILD/bench/bench_render_vk" "$WORK/$name.tpk" "$SIZE" "$FRAMES" "$THREADS" |
        sed "s/^{/{\"mesh\":\"$name\",/"
done
for mesh in "$DATA/sfepy/cube_big_tetra.mesh" "$DATA/sfepy/piezo_mesh_micro.vtk" ${TPK_BENCH_EXTRA:-}; do
    name=$(basename "$mesh")
    for layout in tet16 tet20 tet32; do
        "$BUILD/tetpack" convert "$mesh" "$WORK/$name.$layout.tpk" --layout $layout >/dev/null
        file_bytes=$(stat -c %s "$WORK/$name.$layout.tpk")
        device_bytes=$("$BUILD/tetpack" render "$WORK/$name.$layout.tpk" -o "$WORK/mem.png" --size "${SIZE}x${SIZE}" \
            --backend vulkan --json | sed 's/.*"device_bytes":\([0-9]*\).*/\1/')
        echo "{\"mesh\":\"$name\",\"layout\":\"$layout\",\"file_bytes\":$file_bytes,\"device_bytes\":$device_bytes}"
    done
done
