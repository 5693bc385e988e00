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
[ "$(tr '\r' '\n' < "$WORK/bar.err" | grep -c '100%')" -eq 6 ] || fail "not every stage completed its bar"
[ -z "$(tr '\r' '\n' < "$WORK/bar.err" | tail -n 1 | tr -d ' ')" ] || fail "the last bar was not erased"

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
