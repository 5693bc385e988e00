#!/usr/bin/env bash
# convert's progress bar: on stderr with --progress, one bar per stage in pipeline order, and nothing
# else changes (the file is byte-identical); not a byte on stderr by default off a terminal, with
# --no-progress or with --quiet.
source "$(dirname "$0")/common.sh" "$@"
IN="$SRC/samples/cylinder.vtk"

convert_checked "$IN" "$WORK/quiet.tpk" > /dev/null 2> "$WORK/default.err"
[ ! -s "$WORK/default.err" ] || { cat "$WORK/default.err" >&2; fail "stderr not a terminal: progress printed"; }

"$TPK" convert "$IN" "$WORK/bar.tpk" --progress > /dev/null 2> "$WORK/bar.err"
cmp "$WORK/quiet.tpk" "$WORK/bar.tpk" || fail "the .tpk differs with --progress"
# Each redraw starts with \r; the stages in the order of their first bar.
stages=$(tr '\r' '\n' < "$WORK/bar.err" | sed -n 's/^convert: \([a-z ]*[a-z]\) *\[.*/\1/p' | uniq | paste -sd,)
[ "$stages" = "import,tetrahedralize,reorder,orient,connect,write" ] || fail "stages on stderr: '$stages'"
# Every stage reaches 100%, and the last line is erased: the terminal is left clean.
for stage in import tetrahedralize reorder orient connect write; do
    tr '\r' '\n' < "$WORK/bar.err" | grep -q "^convert: $stage *\[#*\] 100%$" || fail "$stage did not complete its bar"
done
[ -z "$(tr '\r' '\n' < "$WORK/bar.err" | tail -n 1 | tr -d ' ')" ] || fail "the last bar was not erased"

# 42^3 hexahedra (awk, not to depend on a mesher): more than the 65536 cells between two reports of the split, so its bar moves between
# 0 and 100% (at 65536 of 74088 cells: 88%); the split file too is the same with and without the bar.
awk -v n=42 'BEGIN {
    m = n + 1
    print "# vtk DataFile Version 3.0"; print "hexahedra"; print "ASCII"; print "DATASET UNSTRUCTURED_GRID"
    printf "POINTS %d double\n", m * m * m
    for (k = 0; k < m; k++) for (j = 0; j < m; j++) for (i = 0; i < m; i++) print i, j, k
    printf "CELLS %d %d\n", n * n * n, 9 * n * n * n
    for (k = 0; k < n; k++) for (j = 0; j < n; j++) for (i = 0; i < n; i++) {
        p = i + m * (j + m * k)
        print 8, p, p + 1, p + 1 + m, p + m, p + m * m, p + 1 + m * m, p + 1 + m + m * m, p + m + m * m
    }
    printf "CELL_TYPES %d\n", n * n * n
    for (c = 0; c < n * n * n; c++) print 12
}' > "$WORK/hex.vtk"
convert_checked "$WORK/hex.vtk" "$WORK/hex.tpk" > /dev/null
"$TPK" convert "$WORK/hex.vtk" "$WORK/hex_bar.tpk" --progress > /dev/null 2> "$WORK/hex.err"
cmp "$WORK/hex.tpk" "$WORK/hex_bar.tpk" || fail "the split .tpk differs with --progress"
tr '\r' '\n' < "$WORK/hex.err" | grep -q '^convert: tetrahedralize \[#*\.*\]  88%$' ||
    { tr '\r' '\n' < "$WORK/hex.err" >&2; fail "tetrahedralize did not report the cells split"; }
# The legacy VTK reader reports bytes read after each section (POINTS, CELLS, ...): a bar between 0 and 100%.
tr '\r' '\n' < "$WORK/hex.err" | grep -Eq '^convert: import +\[#+\.+\] +[1-9][0-9]?%$' ||
    { tr '\r' '\n' < "$WORK/hex.err" >&2; fail "import did not report the bytes read"; }

"$TPK" convert "$IN" "$WORK/no.tpk" --progress --no-progress > /dev/null 2> "$WORK/no.err"
[ ! -s "$WORK/no.err" ] || fail "--no-progress printed on stderr"
cmp "$WORK/quiet.tpk" "$WORK/no.tpk" || fail "the .tpk differs with --no-progress"
"$TPK" convert "$IN" "$WORK/q.tpk" --progress --quiet > "$WORK/q.out" 2> "$WORK/q.err"
[ ! -s "$WORK/q.err" ] && [ ! -s "$WORK/q.out" ] || fail "--quiet --progress printed"

# A conversion failing inside a stage erases its bar (ESC[K) before the message, which reads whole.
printf '# vtk DataFile Version 3.0\ntruncated\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0\n' > "$WORK/cut.vtk"
expect_exit 2 "$TPK" convert "$WORK/cut.vtk" "$WORK/cut.tpk" --progress
expect_stderr "convert: import"
tr '\r' '\n' < "$WORK/err" | grep -q "^$(printf '\033')\[Ktetpack convert: error: .*cut.vtk:5: POINTS" ||
    { cat -v "$WORK/err" >&2; fail "the failing stage's bar was not erased before the message"; }
echo ok
