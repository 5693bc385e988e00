#!/bin/bash
# Levels of detail (spec §16): frame time against image error across the levels of a mesh, and what the
# levels cost in conversion time and file size. For each mesh: convert with and without --levels 4
# (median of RUNS each), then per level a render (CPU, THREADS threads, SIZE², median of RUNS frame
# times) and its PSNR against the full mesh's picture (same camera and range), then render --max-ms at
# a few budgets, RUNS frames each (the level and pixel step the cost model picks, the frame time it got,
# the PSNR against the full mesh's picture at every pixel). One JSON line per
# measurement on stdout; a Markdown table on stderr.
# usage: bench/bench_levels.sh [BUILD_DIR] [WORK_DIR] [GRID] [SIZE] [RUNS] [THREADS]
#   defaults: build, /tmp/tpk_bench_levels, 121 (make_grid_vtk.py 121: 10.6M tets), 512, 3, 2
# Meshes: SEACAS's exomerge test (../shared/data/seacas, a real Exodus mesh with a transient field, at its
# last step) and the grid.
set -euo pipefail
SRC=$(cd "$(dirname "$0")/.." && pwd)
TPK=${1:-$SRC/build}/tetpack
WORK=${2:-/tmp/tpk_bench_levels}
GRID=${3:-121}
SIZE=${4:-512}
RUNS=${5:-3}
THREADS=${6:-2}
SHARED=${TETPACK_DATA_DIR:-$SRC/../shared/data}
PY=/usr/bin/python3
mkdir -p "$WORK"
[ -f "$WORK/grid$GRID.vtk" ] || "$PY" "$SRC/bench/make_grid_vtk.py" "$GRID" "$WORK/grid$GRID.vtk" > /dev/null
median() { "$PY" -c 'import statistics,sys; print(statistics.median(float(x) for x in sys.argv[1:]))' "$@"; }

measure() { # NAME INPUT FIELD STEP
    local name=$1 input=$2 field=$3 step=$4 plain=() lev=()
    for r in $(seq "$RUNS"); do
        plain+=("$("$TPK" convert "$input" "$WORK/$name.tpk" --json | "$PY" -c 'import json,sys; print(json.load(sys.stdin)["seconds"]["total"])')")
        lev+=("$("$TPK" convert "$input" "$WORK/${name}_l.tpk" --levels 4 --json | tee "$WORK/$name.conv.json" |
                "$PY" -c 'import json,sys; print(json.load(sys.stdin)["seconds"]["total"])')")
    done
    "$PY" - "$WORK/$name.conv.json" "$name" "$(median "${plain[@]}")" "$(median "${lev[@]}")" \
        "$(stat -c %s "$WORK/$name.tpk")" "$(stat -c %s "$WORK/${name}_l.tpk")" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
print(json.dumps({"mesh": sys.argv[2], "convert_s": float(sys.argv[3]), "convert_levels_s": float(sys.argv[4]),
                  "bytes": int(sys.argv[5]), "bytes_levels": int(sys.argv[6]), "tets": r["tets"],
                  "levels": [{k: l[k] for k in ("level", "tets", "error_max", "error_rms", "shell_distance")}
                             for l in r["levels"]]}))
EOF
    local count
    count=$("$PY" -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["levels"]))' "$WORK/$name.conv.json")
    for k in $(seq 0 "$count"); do
        local secs=()
        for r in $(seq "$RUNS"); do
            secs+=("$("$TPK" render "$WORK/${name}_l.tpk" -o "$WORK/$name-$k.png" --backend cpu --threads "$THREADS" \
                      --size "${SIZE}x$SIZE" --field "$field" --step "$step" --level "$k" --json |
                      "$PY" -c 'import json,sys; print(json.load(sys.stdin)["seconds"])')")
        done
        local db
        db=$("$PY" "$SRC/tests/cli/psnr.py" "$WORK/$name-0.png" "$WORK/$name-$k.png" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p')
        echo "{\"mesh\":\"$name\",\"level\":$k,\"frame_s\":$(median "${secs[@]}"),\"psnr_db\":\"$db\",\"size\":$SIZE,\"threads\":$THREADS}"
    done
    for ms in 50 100 250 1000; do # RUNS frames each: the summary takes their median
        for r in $(seq "$RUNS"); do
            "$TPK" render "$WORK/${name}_l.tpk" -o "$WORK/$name-b.png" --backend cpu --threads "$THREADS" \
                --size "${SIZE}x$SIZE" --field "$field" --step "$step" --max-ms "$ms" --json > "$WORK/$name-b.json"
            "$PY" -c 'import json,sys; d=json.load(open(sys.argv[2])); print(json.dumps({"mesh":sys.argv[1],"max_ms":d["max_ms"],"level":d["level"],"pixel_step":d["pixel_step"],"predicted_ms":d["predicted_ms"],"frame_ms":d["frame_ms"],"psnr_db":sys.argv[3]}))' \
                "$name" "$WORK/$name-b.json" \
                "$("$PY" "$SRC/tests/cli/psnr.py" "$WORK/$name-0.png" "$WORK/$name-b.png" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p')"
        done
    done
}

{
    measure exomerge "$SHARED/seacas/exomerge_unit_test.e" disp_z 4
    measure "grid$GRID" "$WORK/grid$GRID.vtk" wave 0
} | tee "$WORK/levels.jsonl"

"$PY" - "$WORK/levels.jsonl" >&2 <<'EOF'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
for c in (r for r in rows if "convert_s" in r):
    print("\n%s: %d tets; convert %.2f s, with --levels 4 %.2f s (%.2fx); %.1f MiB, with levels %.1f MiB (%.2fx)" % (
        c["mesh"], c["tets"], c["convert_s"], c["convert_levels_s"], c["convert_levels_s"] / c["convert_s"],
        c["bytes"] / 2**20, c["bytes_levels"] / 2**20, c["bytes_levels"] / c["bytes"]))
    print("\n| level | tets | field error max / RMS | frame s | PSNR vs full (dB) |\n|---:|---:|---|---:|---:|")
    lv = {l["level"]: l for l in c["levels"]}
    for r in (r for r in rows if r.get("mesh") == c["mesh"] and "frame_s" in r):
        l = lv.get(r["level"])
        err = "%.3g / %.3g" % (l["error_max"], l["error_rms"]) if l else "0 (the full mesh)"
        print("| %d | %s | %s | %.3f | %s |" % (r["level"], l["tets"] if l else c["tets"], err, r["frame_s"], r["psnr_db"]))
    print("\n| --max-ms | levels picked | pixel steps | predicted ms (median) | frame ms (median, max) | PSNR vs full (dB) |"
          "\n|---:|---:|---:|---:|---:|---:|")
    runs = [r for r in rows if r.get("mesh") == c["mesh"] and "max_ms" in r]
    for ms in sorted({r["max_ms"] for r in runs}):
        g = [r for r in runs if r["max_ms"] == ms]
        med = lambda k: statistics.median(r[k] for r in g)
        print("| %g | %s | %s | %.1f | %.1f, %.1f | %s |" % (
            ms, ",".join(str(r["level"]) for r in g), ",".join(str(r["pixel_step"]) for r in g), med("predicted_ms"),
            med("frame_ms"), max(r["frame_ms"] for r in g), ",".join(r["psnr_db"] for r in g)))
EOF
