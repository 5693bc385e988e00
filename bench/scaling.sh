#!/usr/bin/env bash
# Issue 37's scaling benchmark: `tetpack convert --json` of grids at 1, 2, 4, 8, ... threads up to the
# machine's cores (and the core count itself), rounds alternating the thread counts so that all see the
# same load. Per grid a table per stage: median seconds per thread count, the speed-up against one
# thread, and the serial share s of Amdahl's law T(p) = T(1) (s + (1 - s) / p), fitted by least squares
# over the thread counts; then peak RSS per output tet (the process's own, from wait4) per thread count.
#   bench/scaling.sh TETPACK OUT_DIR SMALL
# Called by bench/run.sh --scaling [--small] and bench/gpu/run.sh --scaling [--small] (the bundle's
# run-gpu-bench.sh --scaling). SMALL 1: the test form (ctest bench.scaling_small): grid 8, threads 1 and 2,
# one round, and the two outputs must be byte-identical. Full form: grids TPK_SCALING_GRIDS ("120 200";
# bench/make_grid_vtk.py, python3 with numpy: PYTHON), TPK_SCALING_RUNS rounds (3), TPK_SCALING_THREADS
# to replace the thread counts. The .tpk goes to TPK_SCALING_TPK_DIR (default /dev/shm where writable, so
# the figures are those of compute, not of a disk; else OUT_DIR). Every run's JSON line goes to
# OUT_DIR/scaling.jsonl, the tables to OUT_DIR/scaling.md.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
TPK=$1 OUT=$2 SMALL=$3
[ -x "$TPK" ] || { echo "scaling.sh: no tetpack at $TPK" >&2; exit 2; }
[ -n "${PYTHON:-}" ] || { echo "scaling.sh: no PYTHON (python3 with numpy): run it through bench/run.sh --scaling" >&2; exit 2; }
mkdir -p "$OUT"
cores=$(nproc)
if [ "$SMALL" = 1 ]; then
    GRIDS=8 RUNS=1 THREADS="1 2"
else
    GRIDS=${TPK_SCALING_GRIDS:-"120 200"} RUNS=${TPK_SCALING_RUNS:-3}
    THREADS=${TPK_SCALING_THREADS:-$(t=1; while [ $t -lt "$cores" ]; do printf '%d ' $t; t=$((t * 2)); done; echo "$cores")}
fi
TPK_DIR=${TPK_SCALING_TPK_DIR:-}
if [ -z "$TPK_DIR" ]; then
    TPK_DIR=$OUT
    [ -d /dev/shm ] && [ -w /dev/shm ] && TPK_DIR=/dev/shm
fi
JSONL=$OUT/scaling.jsonl
: > "$JSONL"
for g in $GRIDS; do
    vtk=$OUT/grid$g.vtk
    [ -s "$vtk" ] || "$PYTHON" "$HERE/make_grid_vtk.py" "$g" "$vtk" >&2
done
# one run: its JSON line with the grid, the threads, the process's peak RSS and the load at its start
"$PYTHON" - "$TPK" "$OUT" "$TPK_DIR" "$JSONL" "$RUNS" "$GRIDS" "$THREADS" "$SMALL" <<'EOF'
import json, os, subprocess, sys
tpk, out, tpk_dir, jsonl, runs, grids, threads, small = sys.argv[1:]
pid = os.getpid()
with open(jsonl, "a") as log:
    for g in grids.split():
        for r in range(int(runs)):
            print("# grid %s, round %d of %s: threads %s" % (g, r + 1, runs, threads), file=sys.stderr)
            for t in threads.split():
                dst = os.path.join(tpk_dir, "scaling_%d_%s_%s.tpk" % (pid, g, t))
                load = os.getloadavg()[0]
                p = subprocess.Popen([tpk, "convert", os.path.join(out, "grid%s.vtk" % g), dst, "--json",
                                      "--threads", t], stdout=subprocess.PIPE)
                text = p.stdout.read()
                _, status, usage = os.wait4(p.pid, 0)
                if status != 0:
                    sys.exit("scaling.sh: tetpack convert failed (grid %s, %s threads)" % (g, t))
                d = json.loads(text)
                d.update(grid=int(g), threads=int(t), cores=os.cpu_count(), load=load,
                         peak_rss_bytes=usage.ru_maxrss * 1024)
                log.write(json.dumps(d) + "\n")
            if small == "1":
                a, b = (os.path.join(tpk_dir, "scaling_%d_%s_%s.tpk" % (pid, g, t)) for t in threads.split()[:2])
                if open(a, "rb").read() != open(b, "rb").read():
                    sys.exit("scaling.sh: the outputs of %s and %s threads differ" % tuple(threads.split()[:2]))
            for t in threads.split():
                os.remove(os.path.join(tpk_dir, "scaling_%d_%s_%s.tpk" % (pid, g, t)))
EOF
"$PYTHON" "$HERE/scaling_table.py" "$JSONL" > "$OUT/scaling.md"
cat "$OUT/scaling.md"
