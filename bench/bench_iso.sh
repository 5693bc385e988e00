#!/bin/bash
# tetpack iso on the 998,250-tet grid (make_grid_vtk.py 55, its 'wave' field): the median of 5 runs per
# thread count of load, extraction and write seconds, tets/s and triangles/s of the extraction; then
# bench_iso_extract's in-process figures (median of 9), whose CPU time gives tets per core-second on a
# shared machine.
# usage: bench/bench_iso.sh [BUILD_DIR] [WORK_DIR]     (defaults: build, /tmp/tpk_bench_iso)
set -euo pipefail
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$SRC/build}
TPK=$BUILD/tetpack
WORK=${2:-/tmp/tpk_bench_iso}
mkdir -p "$WORK"
[ -f "$WORK/g55.tpk" ] || { /usr/bin/python3 "$SRC/bench/make_grid_vtk.py" 55 "$WORK/g55.vtk" &&
    "$TPK" convert "$WORK/g55.vtk" "$WORK/g55.tpk" --layout tet32 --layout tet16 --quiet; }
for threads in 1 2; do
    for run in 1 2 3 4 5; do
        "$TPK" iso "$WORK/g55.tpk" "$WORK/iso.ply" --value 0.3 --threads $threads --json
    done | /usr/bin/python3 -c '
import json, statistics, sys
rs = [json.loads(l) for l in sys.stdin]
med = lambda k: statistics.median(r[k] for r in rs)
r = rs[0]
print("threads %d: %d tets, %d triangles, %d vertices; load %.3f s, extract %.3f s, write %.3f s; "
      "%.1fM tets/s, %.2fM triangles/s (medians of %d)" % (r["threads"], r["tets"], r["triangles"], r["vertices"],
      med("seconds_load"), med("seconds_extract"), med("seconds_write"), r["tets"] / med("seconds_extract") / 1e6,
      r["triangles"] / med("seconds_extract") / 1e6, len(rs)))'
done
for threads in 1 2; do
    "$BUILD/bench/bench_iso_extract" "$WORK/g55.tpk" 0.3 $threads 9 | /usr/bin/python3 -c '
import json, sys
r = json.load(sys.stdin)
print("in process, threads %d: extract %.4f s wall, %.4f s CPU: %.1fM tets per core-second (median of %d)" %
      (r["threads"], r["seconds"], r["cpu_seconds"], r["tets_per_core_second"] / 1e6, r["runs"]))'
done
