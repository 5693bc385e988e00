#!/bin/bash
# convert --max-error (issue 36): tets and conversion time for a proved bound E, against the uniform
# subdivision (--subdivide L: every tet into 8, L times, as ParaView's levels) whose proved bound meets
# the same E, and against a plain conversion. For each mesh and E in 1% and 0.1%: the tets --max-error
# makes; the smallest L whose --subdivide bound is <= E, and its tets (levels are made up to MAX_TETS
# tets; beyond, the last level's tets times 8 per level still needed, its bound divided by 4 per level,
# as the quadratic terms fall, noted as extrapolated);
# seconds per output tet of --max-error over those of the plain conversion (median of RUNS, THREADS).
# One JSON line per measurement on stdout, a Markdown table on stderr.
# usage: bench/bench_max_error.sh [BUILD_DIR] [WORK_DIR] [RUNS] [THREADS] [MAX_TETS] [MESHES]
#   defaults: build, /tmp/tpk_bench_max_error, 3, 2, 8000000 (the largest uniform subdivision made),
#   "exomerge t5"
# Meshes: SEACAS's exomerge test (../shared/data/seacas: 1,300 hex8, 8 point fields x 5 steps), and gmsh's
# t5 (../shared/data/gmsh/t5.geo) meshed at order 2 (13,391 ten-node tets) with the point field
# sin(3x) cos(2y) + z^2 (gmsh 2.2 ASCII, $NodeData appended).
set -euo pipefail
SRC=$(cd "$(dirname "$0")/.." && pwd)
TPK=${1:-$SRC/build}/tetpack
WORK=${2:-/tmp/tpk_bench_max_error}
RUNS=${3:-3}
THREADS=${4:-2}
MAX_TETS=${5:-8000000}
MESHES=${6:-exomerge t5}
SHARED=${TETPACK_DATA_DIR:-$SRC/../shared/data}
PY=/usr/bin/python3
mkdir -p "$WORK"
if [ ! -f "$WORK/t5.msh" ]; then
    gmsh -3 -nt 1 -order 2 -format msh22 "$SHARED/gmsh/t5.geo" -o "$WORK/t5_plain.msh" > /dev/null 2>&1
    "$PY" - "$WORK/t5_plain.msh" "$WORK/t5.msh" <<'PYEOF'
import math, sys
lines = open(sys.argv[1]).read().split("\n")
i = lines.index("$Nodes"); n = int(lines[i + 1]); vals = []
for line in lines[i + 2:i + 2 + n]:
    k, x, y, z = line.split()[:4]
    x, y, z = float(x), float(y), float(z)
    vals.append("%s %.17g" % (k, math.sin(3 * x) * math.cos(2 * y) + z * z))
open(sys.argv[2], "w").write("\n".join(lines).rstrip("\n") + "\n" +
    '$NodeData\n1\n"f"\n1\n0.0\n3\n0\n1\n%d\n%s\n$EndNodeData\n' % (n, "\n".join(vals)))
PYEOF
fi
median() { "$PY" -c 'import statistics,sys; print(statistics.median(float(x) for x in sys.argv[1:]))' "$@"; }
# run NAME INPUT OPTIONS...: median seconds of RUNS conversions, the last's JSON in $WORK/NAME.json
run() {
    local name=$1 input=$2 t=()
    shift 2
    for r in $(seq "$RUNS"); do
        t+=("$("$TPK" convert "$input" "$WORK/$name.tpk" --threads "$THREADS" --json "$@" 2> /dev/null |
              tee "$WORK/$name.json" | "$PY" -c 'import json,sys; print(json.load(sys.stdin)["seconds"]["total"])')")
    done
    median "${t[@]}"
}
field() { "$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); print($2)" "$WORK/$1.json"; }

echo "| mesh | E | tets --max-error | proved | uniform level, tets | ratio | s/tet --max-error / plain |" >&2
echo "|---|---|---|---|---|---|---|" >&2
for mesh in $MESHES; do
    input=$SHARED/seacas/exomerge_unit_test.e
    [ $mesh = t5 ] && input=$WORK/t5.msh
    plain=$(run "${mesh}_plain" "$input")
    plain_tets=$(field "${mesh}_plain" "d['tets']")
    run "${mesh}_u0" "$input" --max-error 0.99 > /dev/null  # level 0: the plain split's proved bound
    bounds=("$(field "${mesh}_u0" "d['max_error']['measured']") $(field "${mesh}_u0" "d['tets']")")
    for L in 1 2 3 4 5; do
        [ $((plain_tets * 8 ** L)) -le "$MAX_TETS" ] || break
        run "${mesh}_u$L" "$input" --subdivide "$L" > /dev/null
        bounds+=("$(field "${mesh}_u$L" "d['max_error']['measured']") $(field "${mesh}_u$L" "d['tets']")")
    done
    for e in 0.01 0.001; do
        secs=$(run "${mesh}_$e" "$input" --max-error "$e")
        tets=$(field "${mesh}_$e" "d['tets']")
        proved=$(field "${mesh}_$e" "d['max_error']['measured']")
        "$PY" - "$mesh" "$e" "$tets" "$proved" "$secs" "$plain" "$plain_tets" "${bounds[@]}" <<'PYEOF'
import json, sys
mesh, e, tets, proved, secs, plain, plain_tets = sys.argv[1:8]
e, tets, proved, secs, plain, plain_tets = float(e), int(tets), float(proved), float(secs), float(plain), int(plain_tets)
levels = [tuple(map(float, b.split())) for b in sys.argv[8:]]
level, utets, note = None, None, ""
for k, (bound, n) in enumerate(levels):
    if bound <= e:
        level, utets = k, int(n)
        break
if level is None:  # beyond the levels run: the bound falls at most 4x per level
    bound, n = levels[-1]
    level = len(levels) - 1
    while bound > e:
        bound, n, level = bound / 4, n * 8, level + 1
    utets, note = int(n), " (extrapolated)"
per = (secs / tets) / (plain / plain_tets)
print(json.dumps({"mesh": mesh, "max_error": e, "tets": tets, "proved": proved, "seconds": secs,
                  "uniform_level": level, "uniform_tets": utets, "uniform_extrapolated": bool(note),
                  "ratio": tets / utets, "plain_seconds": plain, "plain_tets": plain_tets,
                  "seconds_per_tet_ratio": per}))
print("| %s | %g%% | %d | %.3g%% | %d: %d%s | %.3f | %.2f |" % (mesh, 100 * e, tets, 100 * proved, level, utets, note,
                                                           tets / utets, per), file=sys.stderr)
PYEOF
    done
done
