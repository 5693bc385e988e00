# Issue 10: inputs that crashed or hung tetpack inside TetGen. Each is an error through `tetpack convert`
# (exit 2, the file and the reason named, no output left) and through `tetpack check` (exit 2, no crash);
# a volume bound that would make too many tets is refused at once naming --max-tets, and runs once raised.
source "$(dirname "$0")/common.sh"

"$PY" - "$WORK" <<'PYEOF'
import sys
out = sys.argv[1]
# The unit cube: corner (x, y, z) is point 4x + 2y + z; six outward quads, two triangles each.
corners = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
def stl(name, points):
    with open(out + '/' + name, 'w') as f:
        f.write('solid cube\n')
        for a, b, c, d in quads:
            for t in ((a, b, c), (a, c, d)):
                f.write('facet normal 0 0 0\nouter loop\n' + ''.join('vertex %r %r %r\n' % points[v] for v in t)
                        + 'endloop\nendfacet\n')
        f.write('endsolid cube\n')
def csv(name, points):
    with open(out + '/' + name, 'w') as f:
        f.write('x,y,z\n' + ''.join('%r,%r,%r\n' % p for p in points))
stl('cube.stl', corners)
stl('spike.stl', [(0.0, 1e15, 1.0) if p == (0, 1, 1) else p for p in corners])
stl('huge_cube.stl', [tuple(1e300 * c for c in p) for p in corners])
csv('line.csv', [(i, i, i) for i in range(20)])
csv('extremes.csv', corners + [(0.5, 0.5, 0.5), (1e300, 0.25, 0.5), (1e-300, 0.75, 0.5)])
PYEOF

if ! "$TPK" convert "$WORK/cube.stl" "$WORK/probe.tpk" --quiet 2>"$WORK/err"; then
    expect_stderr "built without TetGen"
    skip "tetpack built without TetGen: refusal checked, nothing else to test"
fi

# refused FILE NEEDLE...: convert and check both exit 2 naming FILE and each NEEDLE; no output is left.
# `timeout` turns a hang into a failure instead of a stuck test.
refused() {
    local file=$1
    shift
    for cmd in "convert $WORK/$file $WORK/out.tpk" "check $WORK/$file"; do
        expect_exit 2 timeout 120 "$TPK" $cmd
        expect_stderr "$file: "
        for needle in "$@"; do expect_stderr "$needle"; done
    done
    [ ! -e "$WORK/out.tpk" ] || fail "$file: output left behind"
}
refused line.csv "all 20 points lie on one line"
refused extremes.csv "point 9 has coordinate 1.0000000000000001e+300" "|x| <= 1e+50"
refused huge_cube.stl "has coordinate 1.0000000000000001e+300"
# TetGen itself crashes on this one (it finds the cube flat next to the spike, then faults freeing its
# memory): the child process's death is reported with its last words: TetGen's, or under
# AddressSanitizer (whose SEGV handler ends the child with status 1) the sanitizer's report.
refused spike.stl "TetGen crashed (" "while checking the surface for self-intersections"
if grep -q "exited with status 1" "$WORK/err"; then
    expect_stderr "it said: .*AddressSanitizer: SEGV"
else
    expect_stderr "(signal 11, SIGSEGV, a bad memory access)"
    expect_stderr "it said: Exception:  All vertices are coplanar"
fi

# The hang: 1e-9 in a unit cube is about 2e9 tets. Refused before TetGen starts, naming the option.
expect_exit 2 timeout 60 "$TPK" convert "$WORK/cube.stl" "$WORK/out.tpk" --tetgen-max-volume 1e-9
expect_stderr "cube.stl: a largest tet volume of 1e-09"
expect_stderr "about 2e+09 tets, more than the limit of 10000000 (--max-tets N raises it"
# A small bound against a small limit: refused, then accepted once --max-tets is raised (about 2000 tets
# estimated, 2995 made).
expect_exit 2 "$TPK" convert "$WORK/cube.stl" "$WORK/out.tpk" --tetgen-max-volume 1e-3 --max-tets 1000
expect_stderr "more than the limit of 1000 (--max-tets"
[ ! -e "$WORK/out.tpk" ] || fail "output left behind"
"$TPK" convert "$WORK/cube.stl" "$WORK/out.tpk" --tetgen-max-volume 1e-3 --max-tets 5000 --json > "$WORK/ok.json"
"$PY" -c "import json; d=json.load(open('$WORK/ok.json')); assert 1000 < d['tets'] <= 5000, d"
# A run that fits the tet limit but not the time limit is stopped (it would take minutes).
rm -f "$WORK/out.tpk"
expect_exit 2 timeout 120 "$TPK" convert "$WORK/cube.stl" "$WORK/out.tpk" --tetgen-max-volume 1e-7 \
    --max-tets 100000000 --tetgen-time-limit 0.5
expect_stderr "cube.stl: TetGen ran past the time limit of 0.5 s while tetrahedralizing the surface"
expect_stderr "(--tetgen-time-limit raises it)"
[ ! -e "$WORK/out.tpk" ] || fail "output left behind"
# Progress: a line per TetGen stage on stderr (check --progress forces it without a terminal).
"$TPK" check --progress "$WORK/cube.stl" > /dev/null 2> "$WORK/err"
expect_stderr "TetGen: checking the surface for self-intersections (switches dzQ)... [0-9][0-9]* s"
expect_stderr "TetGen: tetrahedralizing the surface (switches p180zQq1.414)... [0-9][0-9]* s (of at most 3600)"
"$TPK" check "$WORK/cube.stl" > /dev/null 2> "$WORK/err"
[ ! -s "$WORK/err" ] || fail "progress printed without --progress"
expect_exit 2 "$TPK" convert "$WORK/cube.stl" "$WORK/out.tpk" --max-tets 0
expect_stderr "--max-tets expects a tet count >= 1"
echo "TetGen guard CLI tests passed"
