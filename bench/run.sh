#!/usr/bin/env bash
# Benchmarks, run on demand: ./bench/run.sh [build-dir]   (default build-release, built here)
# Prints JSON lines and a summary; medians of several runs. Needs /usr/bin/time and Debian's python3.
# Sizes: TPK_BENCH_SIZES="55 119" (grid edge N: 6*N^3 tets; 55 -> ~1M, 119 -> ~10M).
#   ./bench/run.sh --scaling [--small] [--bin DIR] [--out DIR]: instead, issue 37's scaling table
#   (bench/scaling.sh): convert of grids 120 and 200 at 1, 2, 4, ... threads up to the cores, per stage the
#   speed-up and the serial share, and peak RSS per tet. --bin: where tetpack is (default build-release,
#   built here); --out: results (default $TPK_BENCH_DIR/scaling); --small: the ctest bench.scaling_small.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = --scaling ]; then
    shift
    small=0 bin="" out=${TPK_BENCH_DIR:-/tmp/tpk_bench}/scaling
    while [ $# -gt 0 ]; do
        case "$1" in
            --small) small=1 ;;
            --bin) bin=$2; shift ;;
            --out) out=$2; shift ;;
            *) echo "usage: bench/run.sh --scaling [--small] [--bin DIR] [--out DIR]" >&2; exit 2 ;;
        esac
        shift
    done
    if [ -z "$bin" ]; then
        bin=build-release
        cmake -S . -B "$bin" -DCMAKE_BUILD_TYPE=Release -DTETPACK_WITH_TESTS=OFF >/dev/null
        cmake --build "$bin" -j"$(nproc)" --target tetpack_cli >/dev/null
    fi
    PYTHON=${PYTHON:-}
    for c in python3 /usr/bin/python3; do
        [ -n "$PYTHON" ] || ! "$c" -c "import numpy" 2>/dev/null || PYTHON=$c
    done
    [ -n "$PYTHON" ] || { echo "run.sh: make_grid_vtk.py needs python3 with numpy (or set PYTHON)" >&2; exit 2; }
    export PYTHON
    exec bash bench/scaling.sh "$bin/tetpack" "$out" "$small"
fi
BUILD=${1:-build-release}
RUNS=${TPK_BENCH_RUNS:-3}
SIZES=${TPK_BENCH_SIZES:-"55 119"}
WORK=${TPK_BENCH_DIR:-/tmp/tpk_bench}
mkdir -p "$WORK"
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DTETPACK_WITH_TESTS=OFF >/dev/null
cmake --build "$BUILD" -j"$(nproc)" >/dev/null
TPK="$BUILD/tetpack"

median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

# convert_stats INPUT OUTPUT [options]: median over RUNS of total seconds, and peak RSS (MiB).
convert_stats() {
    local in=$1 out=$2
    shift 2
    local totals=() rss=() line
    for _ in $(seq "$RUNS"); do
        /usr/bin/time -f "%M" -o "$WORK/time.txt" "$TPK" convert "$in" "$out" --json "$@" > "$WORK/convert.json"
        totals+=("$(/usr/bin/python3 -c "import json;print(json.load(open('$WORK/convert.json'))['seconds']['total'])")")
        rss+=("$(tail -1 "$WORK/time.txt")")
    done
    local t m
    t=$(printf '%s\n' "${totals[@]}" | median)
    m=$(printf '%s\n' "${rss[@]}" | median)
    /usr/bin/python3 - "$WORK/convert.json" "$t" "$m" "$in" "$*" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
t, rss_kib = float(sys.argv[2]), int(sys.argv[3])
out = {"input": sys.argv[4], "options": sys.argv[5], "tets": d["tets"], "median_total_s": t,
       "tets_per_s": d["tets"] / t, "peak_rss_mib": rss_kib / 1024, "output_mib": d["output_bytes"] / 2**20,
       "peak_over_output": rss_kib * 1024 / d["output_bytes"], "last_run_stage_s": d["seconds"]}
print(json.dumps(out))
PY
}

echo "# conversion (binary VTK in, uncompressed out, tet16)"
for n in $SIZES; do
    [ -f "$WORK/grid$n.vtk" ] || ./bench/make_grid_vtk.py "$n" "$WORK/grid$n.vtk"
    convert_stats "$WORK/grid$n.vtk" "$WORK/grid$n.tpk" --layout tet16 --reorient
done

echo "# tetpack check, all groups (median of RUNS), on the grids as VTK (half their tets are given"
echo "# inverted: a stress case) and as the converted .tpk (clean, 6xx too); memory against the mesh as read"
for input in $(for n in $SIZES; do echo "$WORK/grid$n.vtk" "$WORK/grid$n.tpk"; done); do
    totals=() rss=()
    for _ in $(seq "$RUNS"); do
        /usr/bin/time -f "%e %M" -o "$WORK/time.txt" "$TPK" check "$input" --json --no-progress \
            > "$WORK/check.json" || true
        totals+=("$(tail -1 "$WORK/time.txt" | cut -d' ' -f1)")
        rss+=("$(tail -1 "$WORK/time.txt" | cut -d' ' -f2)")
    done
    /usr/bin/python3 - "$WORK/check.json" "$(printf '%s\n' "${totals[@]}" | median)" \
        "$(printf '%s\n' "${rss[@]}" | median)" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
t, rss = float(sys.argv[2]), int(sys.argv[3]) * 1024
# The mesh as read (tpk_mesh): f64 points, int64 offsets, int32 connectivity, uint8 types.
mesh_bytes = 24 * d["vertices"] + d["cells"] * (8 + 16 + 1)
print(json.dumps({"check": d["input"].rsplit("/", 1)[-1], "cells": d["cells"], "median_wall_s": t, "cells_per_s": d["cells"] / t,
                  "peak_rss_mib": rss / 2**20, "mesh_mib": mesh_bytes / 2**20, "peak_over_mesh": rss / mesh_bytes,
                  "groups_last_run": {g["name"]: round(g["seconds"], 3) for g in d["groups"]},
                  "findings": {f["name"]: f["count"] for f in d["findings"]}}))
PY
done

echo "# mixed cells: hexahedra as binary VTU (zlib, written by meshio), N^3 hexes (TPK_BENCH_HEX, default 216: ~10M)"
h=${TPK_BENCH_HEX:-216}
[ -f "$WORK/hex$h.vtu" ] || ./bench/make_hex_vtu.py "$h" "$WORK/hex$h.vtu"
convert_stats "$WORK/hex$h.vtu" "$WORK/hex$h.tpk" --layout tet16
echo "# the largest real file of each format in ../shared/data"
for f in sfepy/cube_big_tetra.mesh nasa_refine/cube-sphere_cube-sphere.meshb nasa_refine/cube_cylinder_ega.ugrid \
         seacas/exomerge_unit_test.e hard/nonmanifold_vertex_edge_tets.vtu tetgen/hinge_small.node \
         sfepy/piezo_mesh_micro.vtk gmsh/t5_small_tet_bin.vtk; do
    convert_stats "../shared/data/$f" "$WORK/format.tpk" --layout tet16
done

echo "# tets per input cell against the face-centre approach (24 tets per hexahedron)"
[ -f "$WORK/hex_1M.msh" ] || gmsh -3 ../shared/data/gmsh/hexrecomb.geo -nt 1 -format msh41 -bin -o "$WORK/hex_1M.msh" >/dev/null 2>&1 || true
/usr/bin/python3 bench/tets_per_cell.py "$TPK" ../shared/data/sfepy/acoustics_mesh3d.mesh ../shared/data/seacas/exomerge_unit_test.e \
    ../shared/data/gmsh/t3_hex_prism_ascii41.msh ../shared/data/sfepy/cross3d.mesh "$WORK/hex_1M.msh"

echo "# file size per layout and zstd level (first size)"
n=$(echo $SIZES | awk '{print $1}')
for layout in tet16 tet20 tet32; do
    for z in 0 1 3 9 19; do
        opt=()
        [ "$z" -gt 0 ] && opt=(--zstd "$z")
        "$TPK" convert "$WORK/grid$n.vtk" "$WORK/size.tpk" --layout $layout --reorient "${opt[@]}" --json > "$WORK/size.json"
        /usr/bin/python3 -c "import json;d=json.load(open('$WORK/size.json'));print(json.dumps({'layout':'$layout','zstd':$z,'bytes':d['output_bytes'],'bytes_per_tet':d['output_bytes']/d['tets'],'write_s':d['seconds']['write']}))"
    done
done

echo "# open time (uncompressed, largest size)"
n=$(echo $SIZES | awk '{print $NF}')
"$BUILD/bench/bench_open" "$WORK/grid$n.tpk" 21

n_small=$(echo $SIZES | awk '{print $1}')
n_large=$(echo $SIZES | awk '{print $NF}')
echo "# face matching alone (and orient, reorder, layouts, shell), grid $n_large"
"$BUILD/bench/bench_connect" "$n_large" "$RUNS"
echo "# accuracy of splitting hexahedra: |tet - trilinear| / field range at random points"
"$BUILD/bench/bench_accuracy" ../shared/data/sfepy/cube_medium_hexa.mesh ../shared/data/sfepy/acoustics_mesh3d.mesh
echo "# CPU marcher: tet steps per second per layout and thread count, grid $n_small, 512x512 rays"
"$BUILD/bench/bench_march" "$n_small" "$RUNS" 512 1 2
