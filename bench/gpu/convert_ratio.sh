#!/usr/bin/env bash
# Issue 22's conversion target on whatever machine runs it: `convert --levels 4` against the same
# conversion without levels (target: at most 2x), and the file size with the levels (target: at most
# 1.3x). The GPU host is the many-core machine a session can reach (16 cores), so this is one of the
# bundle's modes (run.sh --convert; the bundle's run-gpu-bench.sh --convert), though it uses no GPU.
# On a grid (bench/make_grid_vtk.py GRID: python3 with numpy), RUNS rounds, each the conversion without
# levels then with them, alternating so that both see the same load; `tetpack convert --json` on all the
# machine's threads. Every run's JSON line goes to convert.jsonl, the medians to convert.md.
# Called by run.sh --convert [--small] [--bin DIR] [--out DIR] as convert_ratio.sh TETPACK OUT_DIR SMALL
# (1: the test form, ctest bench.convert_ratio_small: grid 6, 1 round). TPK_CONVERT_GRID (200: 48M
# tets, about 30 s a round on 16 cores) and TPK_CONVERT_RUNS (3) change the full form.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
TPK=$1 OUT=$2 SMALL=$3
[ -x "$TPK" ] || { echo "convert_ratio.sh: no tetpack at $TPK" >&2; exit 2; }
mkdir -p "$OUT"
if [ "$SMALL" = 1 ]; then
    GRID=6 RUNS=1
else
    GRID=${TPK_CONVERT_GRID:-200} RUNS=${TPK_CONVERT_RUNS:-3}
fi
[ -n "${PYTHON:-}" ] || { echo "convert_ratio.sh: no PYTHON: run it through run.sh --convert, which finds python3 with numpy" >&2; exit 2; }
PY=$PYTHON
vtk=$OUT/grid$GRID.vtk
[ -s "$vtk" ] || "$PY" "$ROOT/bench/make_grid_vtk.py" "$GRID" "$vtk" >&2
JSONL=$OUT/convert.jsonl
: > "$JSONL"
one() { # FORM (plain or levels), then convert's extra options: its JSON line, tagged
    local form=$1
    shift
    "$TPK" convert "$vtk" "$OUT/grid${GRID}_$form.tpk" --json "$@" |
        "$PY" -c 'import json,os,sys; d=json.loads(sys.stdin.readline()); d.update(form=sys.argv[1], grid=int(sys.argv[2]), cores=os.cpu_count()); print(json.dumps(d))' \
            "$form" "$GRID" >> "$JSONL"
}
for r in $(seq "$RUNS"); do
    echo "# round $r of $RUNS: grid $GRID, without levels, then --levels 4" >&2
    one plain
    one levels --levels 4
done
rm -f "$OUT/grid${GRID}_plain.tpk" "$OUT/grid${GRID}_levels.tpk"
"$PY" - "$JSONL" > "$OUT/convert.md" <<'EOF'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
plain = [r for r in rows if r["form"] == "plain"]
levels = [r for r in rows if r["form"] == "levels"]
def med(rs, *key):
    values = []
    for r in rs:
        for k in key:
            r = r[k]
        values.append(r)
    return statistics.median(values)
def each(rs):
    return ", ".join("%.3f" % r["seconds"]["total"] for r in rs)
p, l = med(plain, "seconds", "total"), med(levels, "seconds", "total")
print("| target (grid %d, %d tets, %d cores, median of %d) | measured | goal |" % (
    plain[0]["grid"], plain[0]["tets"], plain[0]["cores"], len(plain)))
print("|---|---|---|")
print("| convert --levels 4 / convert | %.2fx: %.3f s (%s; levels stage %.3f s) / %.3f s (%s) | <= 2x |" % (
    l / p, l, each(levels), med(levels, "seconds", "levels"), p, each(plain)))
print("| file with 4 levels / without | %.3fx: %d / %d bytes, %d levels | <= 1.3x |" % (
    levels[0]["output_bytes"] / plain[0]["output_bytes"], levels[0]["output_bytes"], plain[0]["output_bytes"], len(levels[0]["levels"])))
EOF
cat "$OUT/convert.md"
