#!/usr/bin/env bash
# tetpack-mpi scaling on this machine: a real mesh cut into .pvtu pieces (tests/mpi/make_pvtu.py), then
# mpirun -np 1, 2, 4 (4 is oversubscribed on a 2-core machine), one thread per rank, TPK_BENCH_RUNS runs
# each (default 3): the median of the slowest rank's phase times, each rank's peak RSS, the bytes it
# exchanged; and the single-process `tetpack convert --threads 1` of the whole mesh for reference.
#   ./bench/mpi_scaling.sh [build-dir] [mesh]     (PVTU_OPTIONS: make_pvtu.py's, default --no-point-data)
# e.g. hexahedra: python3 bench/make_hex_vtu.py 60 /tmp/hex60.vtu && PVTU_OPTIONS=--global-ids \
#      ./bench/mpi_scaling.sh build /tmp/hex60.vtu
# Default mesh: gmsh's tutorial t5 at -clscale 0.215 (MANIFEST.md's recipe: about 1M tets). Wall
# times on a shared, loaded machine count waiting for a core; the CPU seconds per phase do not (the
# model uses them). Prints one JSON line per rank count; bench/mpi_model.py fits the model to them.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
RUNS=${TPK_BENCH_RUNS:-3}
WORK=${TPK_BENCH_DIR:-/tmp/tpk_bench_mpi}
DATA=${TPK_DATA_DIR:-$(cd .. && pwd)/shared/data}
mkdir -p "$WORK"
MESH=${2:-}
if [ -z "$MESH" ]; then
    MESH="$WORK/t5.msh"
    [ -s "$MESH" ] || gmsh -3 "$DATA/gmsh/t5.geo" -clscale 0.215 -nt 1 -format msh41 -bin -o "$MESH" > /dev/null
fi
PIECES=8
TAG=$(basename "$MESH" | tr . _)
[ -s "$WORK/$TAG.pvtu" ] || /usr/bin/python3 tests/mpi/make_pvtu.py "$MESH" "$WORK/$TAG.pvtu" "$PIECES" ${PVTU_OPTIONS:---no-point-data}
echo "{\"input\": \"$MESH\", \"input_bytes\": $(cat "$WORK/${TAG}"_*.vtu | wc -c)}"

/usr/bin/time -f "%M %e %U %S" -o "$WORK/single.txt" "$BUILD/tetpack" convert "$MESH" "$WORK/single.tpk" --threads 1 \
    --json > "$WORK/single.json"
/usr/bin/python3 - "$WORK/single.json" "$WORK/single.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
rss_kib, wall, user, system = open(sys.argv[2]).read().split()[-4:]
print(json.dumps({"single": True, "tets": r["tets"], "seconds": r["seconds"]["total"],
                  "cpu_seconds": float(user) + float(system), "peak_rss_bytes": int(rss_kib) * 1024}))
PY
for ranks in 1 2 4; do
    for run in $(seq "$RUNS"); do
        mpirun --allow-run-as-root --oversubscribe -np "$ranks" "$BUILD/tetpack-mpi" convert "$WORK/$TAG.pvtu" \
            "$WORK/out.tpkset" --threads 1 --json > "$WORK/run_${ranks}_$run.json"
    done
    /usr/bin/python3 - "$ranks" "$WORK"/run_"${ranks}"_*.json <<'PY'
import json, statistics, sys
ranks, runs = int(sys.argv[1]), [json.load(open(p))["ranks"] for p in sys.argv[2:]]
phases = ["read", "ids", "tets", "cut", "write", "total"]
slowest = {p: statistics.median(max(r["seconds"][p] for r in run) for run in runs) for p in phases}
cpu = {p: statistics.median(max(r["cpu_seconds"][p] for r in run) for run in runs) for p in phases[:-1]}
last = runs[-1]
print(json.dumps({"ranks": ranks, "tets": sum(r["tets"] for r in last), "seconds": slowest, "cpu_seconds": cpu,
                  "tets_per_rank": [r["tets"] for r in last], "points_read": [r["points_read"] for r in last],
                  "peak_rss_bytes": [r["peak_rss_bytes"] for r in last],
                  "exchanged_bytes": [r["exchanged_bytes"] for r in last], "links": [r["links"] for r in last],
                  "file_bytes": [r["file_bytes"] for r in last]}))
PY
done
