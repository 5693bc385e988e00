#!/bin/bash
# convert --max-error: time per output tet against a plain conversion (issue 36's target: at most 2x), on
# meshes large enough to time: a real hex mesh of 169,680 hexahedra (1.02M tets), made by gmsh from
# ../shared/data/gmsh/hexrecomb.geo at a coarser size (lc 0.017, 40 layers), and gmsh's t5 at order 2
# (13,391 ten-node tets), each with bench/fidelity.py's smooth point field "f". One thread; plain and
# --max-error E runs alternate (RUNS each); medians of convert's seconds.total and of the process CPU
# (user + system). With a second binary OLD, each row is run with both, alternating, on the same load.
# usage: bench/bench_max_error_speed.sh [BUILD_DIR] [WORK_DIR] [RUNS] [E] [OLD_TETPACK]
#   defaults: build, /tmp/tpk_bench_max_error_speed, 5, 1%, none
# Needs gmsh and python3-numpy. Prints a Markdown table.
set -euo pipefail
SRC=$(cd "$(dirname "$0")/.." && pwd)
TPK=${1:-$SRC/build}/tetpack
WORK=${2:-/tmp/tpk_bench_max_error_speed}
RUNS=${3:-5}
E=${4:-1%}
OLD=${5:-}
SHARED=${TETPACK_DATA_DIR:-$SRC/../shared/data}
PY=/usr/bin/python3
mkdir -p "$WORK"
if [ ! -f "$WORK/hex.vtk" ]; then
    sed -e 's/lc = 0.0085/lc = 0.017/' -e 's/Layers{60}/Layers{40}/' "$SHARED/gmsh/hexrecomb.geo" > "$WORK/hex.geo"
    gmsh -3 -nt 1 "$WORK/hex.geo" -format mesh -o "$WORK/hex.mesh" > "$WORK/gmsh.log" 2>&1 || true # see MANIFEST
    "$PY" "$SRC/bench/fidelity.py" source hex8 "$WORK/hex.mesh" "$WORK/hex.vtk"
fi
if [ ! -f "$WORK/t5.vtk" ]; then
    gmsh -3 -nt 1 -order 2 "$SHARED/gmsh/t5.geo" -format vtk -o "$WORK/t5_order2.vtk" > "$WORK/gmsh.log" 2>&1
    "$PY" "$SRC/bench/fidelity.py" source tet10 "$WORK/t5_order2.vtk" "$WORK/t5.vtk"
fi
# one BINARY INPUT [OPTIONS...]: "seconds cpu tets" of one conversion
one() {
    local bin=$1 input=$2
    shift 2
    /usr/bin/time -f "%U %S" -o "$WORK/time.txt" "$bin" convert "$input" "$WORK/out.tpk" --no-progress --threads 1 \
        --json "$@" > "$WORK/conv.json"
    "$PY" -c 'import json,sys; d=json.load(open(sys.argv[1])); u,s=open(sys.argv[2]).read().split()[-2:];
print(d["seconds"]["total"], float(u)+float(s), d["tets"])' "$WORK/conv.json" "$WORK/time.txt"
}
echo "| mesh | binary | plain tets | --max-error $E tets | plain s (CPU s) | --max-error s (CPU s) | per tet vs plain, wall (CPU) |"
echo "|---|---|---|---|---|---|---|"
for mesh in hex t5; do
    bins=("$TPK")
    [ -n "$OLD" ] && bins+=("$OLD")
    declare -A res=()
    for r in $(seq "$RUNS"); do
        for b in "${!bins[@]}"; do
            res[$b plain]+="$(one "${bins[$b]}" "$WORK/$mesh.vtk");"
            res[$b bound]+="$(one "${bins[$b]}" "$WORK/$mesh.vtk" --max-error "$E");"
        done
    done
    for b in "${!bins[@]}"; do
        "$PY" - "$mesh" "${bins[$b]}" "${res[$b plain]}" "${res[$b bound]}" <<'PYEOF'
import statistics, sys
mesh, binary, plain, bound = sys.argv[1:5]
def med(runs, k):
    return statistics.median(float(x.split()[k]) for x in runs.strip(";").split(";"))
p, b = plain.strip(";").split(";")[0].split(), bound.strip(";").split(";")[0].split()
pt, bt = int(p[2]), int(b[2])
pw, pc, bw, bc = med(plain, 0), med(plain, 1), med(bound, 0), med(bound, 1)
print("| %s | %s | %d | %d | %.3f (%.2f) | %.3f (%.2f) | %.2fx (%.2fx) |" % (mesh, binary, pt, bt, pw, pc, bw, bc,
      (bw / bt) / (pw / pt), (bc / bt) / (pc / pt)))
PYEOF
    done
    unset res
done
