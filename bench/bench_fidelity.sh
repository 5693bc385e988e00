#!/bin/bash
# Fidelity (issue 36): how far a converted file is from its source cells' own interpolants, and what a
# tighter bound costs. For each mesh and each way of converting it (plain; `convert --max-error 1%` and
# 0.1%; uniform subdivision at 1, 2 and 3 levels made by bench/fidelity.py, ParaView's "Nonlinear
# Subdivision Level" for the volume), one JSON line: tets, file bytes, conversion seconds (median of
# RUNS), CPU render seconds at SIZE² (median of RUNS), and `check --against`'s max and RMS error of the
# point field (fractions of its range) with the share of samples outside the file.
# usage: bench/bench_fidelity.sh [BUILD_DIR] [WORK_DIR] [RUNS] [SIZE] [MAX_LEVEL]
#   defaults: build, /tmp/tpk_bench_fidelity, 3, 256, 3
# Meshes: gmsh's tutorial t5 (../shared/data/gmsh/t5.geo) meshed at order 2 (13,391 ten-node tets) and
# sfepy's acoustics_mesh3d (4,380 hexahedra), each with a smooth point field "f" at every node
# (bench/fidelity.py). Needs gmsh and python3-numpy.
set -euo pipefail
SRC=$(cd "$(dirname "$0")/.." && pwd)
TPK=${1:-$SRC/build}/tetpack
WORK=${2:-/tmp/tpk_bench_fidelity}
RUNS=${3:-3}
SIZE=${4:-256}
MAX_LEVEL=${5:-3}
SHARED=${TETPACK_DATA_DIR:-$SRC/../shared/data}
PY=/usr/bin/python3
mkdir -p "$WORK"
median() { "$PY" -c 'import statistics,sys; print(statistics.median(float(x) for x in sys.argv[1:]))' "$@"; }
has_max_error=0
help=$("$TPK" convert --help 2>&1) # not piped into grep -q: under pipefail an early exit fails the pipe
grep -q -- "--max-error" <<< "$help" && has_max_error=1

gmsh -3 -nt 1 -order 2 "$SHARED/gmsh/t5.geo" -format vtk -o "$WORK/t5_order2.vtk" > "$WORK/gmsh.log" 2>&1 ||
    { tail "$WORK/gmsh.log" >&2; exit 1; }
"$PY" "$SRC/bench/fidelity.py" source tet10 "$WORK/t5_order2.vtk" "$WORK/t5.vtk"
"$PY" "$SRC/bench/fidelity.py" source hex8 "$SHARED/sfepy/acoustics_mesh3d.mesh" "$WORK/hex.vtk"

row() { # MESH SOURCE METHOD INPUT [CONVERT OPTIONS...]
    local mesh=$1 source=$2 method=$3 input=$4 conv=() ren=()
    shift 4
    for r in $(seq "$RUNS"); do
        conv+=("$("$TPK" convert "$input" "$WORK/out.tpk" --no-progress --json "$@" | tee "$WORK/conv.json" |
                 "$PY" -c 'import json,sys; print(json.load(sys.stdin)["seconds"]["total"])')")
        ren+=("$("$TPK" render "$WORK/out.tpk" -o "$WORK/out.png" --backend cpu --size "${SIZE}x$SIZE" --json |
                "$PY" -c 'import json,sys; print(json.load(sys.stdin)["seconds"])')")
    done
    local status=0
    "$TPK" check "$WORK/out.tpk" --against "$source" --json > "$WORK/against.json" || status=$?
    "$PY" - "$WORK/conv.json" "$WORK/against.json" "$mesh" "$method" "$(median "${conv[@]}")" "$(median "${ren[@]}")" \
        "$(stat -c %s "$WORK/out.tpk")" "$status" <<'EOF'
import json, sys
c, a = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
f = a["fields"][0] if a["fields"] else {}
print(json.dumps({"mesh": sys.argv[3], "method": sys.argv[4], "tets": c["tets"], "bytes": int(sys.argv[7]),
                  "convert_s": float(sys.argv[5]), "render_s": float(sys.argv[6]),
                  "max_error": f.get("max_error"), "rms_error": f.get("rms_error"),
                  "samples": a["samples"], "outside": a["outside"], "bound": a["bound"],
                  "check_exit": int(sys.argv[8]),
                  "measured_bound": c.get("max_error_measured")}))
EOF
}

for mesh in t5 hex; do
    row "$mesh" "$WORK/$mesh.vtk" none "$WORK/$mesh.vtk"
    if [ $has_max_error = 1 ]; then
        row "$mesh" "$WORK/$mesh.vtk" "max-error 1%" "$WORK/$mesh.vtk" --max-error 1%
        row "$mesh" "$WORK/$mesh.vtk" "max-error 0.1%" "$WORK/$mesh.vtk" --max-error 0.1%
    else
        echo "{\"mesh\":\"$mesh\",\"method\":\"max-error\",\"missing\":\"this tetpack has no convert --max-error\"}"
    fi
    for level in $(seq "$MAX_LEVEL"); do
        "$PY" "$SRC/bench/fidelity.py" uniform "$WORK/$mesh.vtk" "$level" "$WORK/${mesh}_u.vtk"
        row "$mesh" "$WORK/$mesh.vtk" "uniform $level" "$WORK/${mesh}_u.vtk"
    done
done
