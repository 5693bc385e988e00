# Output paths (issue 10, items 3-5): an output that is a file the command reads, a directory, an empty
# path or not a regular file is refused up front (exit 2, naming the argument) and every input keeps
# its bytes; a process killed while its output is complete but not yet in place leaves no temporary
# file and the older output intact (tools/base/output_file.c; its test hooks TPK_TEST_OUTPUT_HOLD and
# TPK_TEST_OUTPUT_NAMED make the kill deterministic).
source "$(dirname "$0")/common.sh"

cp "$SRC/samples/cylinder.vtk" "$WORK/small.vtk"
"$TPK" convert "$WORK/small.vtk" "$WORK/good.tpk" --quiet
cp "$DATA/tetgen/hinge_small.node" "$WORK/t.node"
cp "$DATA/tetgen/hinge_small.ele" "$WORK/t.ele"
# A ParaView series of two pieces (the same mesh twice), which converts.
"$TPK" export "$WORK/good.tpk" --vtu "$WORK/p0.vtu" >/dev/null
"$TPK" export "$WORK/good.tpk" --vtu "$WORK/p1.vtu" >/dev/null
printf '<VTKFile type="Collection"><Collection>\n<DataSet timestep="0" file="p0.vtu"/>\n<DataSet timestep="1" file="p1.vtu"/>\n</Collection></VTKFile>\n' > "$WORK/p.pvd"
"$TPK" convert "$WORK/p.pvd" "$WORK/p.tpk" --quiet
printf '0 0 0 0 0\n1 1 1 1 1\n' > "$WORK/tf.txt"

sums() { (cd "$WORK" && sha1sum small.vtk good.tpk t.node t.ele p.pvd p0.vtu p1.vtu tf.txt); }
sums > "$WORK/sums.before"
# refused MESSAGE cmd...: exit 2, the message on stderr, every input byte-identical.
refused() {
    local message=$1
    shift
    expect_exit 2 "$@"
    expect_stderr "$message"
    sums | cmp -s - "$WORK/sums.before" || fail "an input changed: $*"
}

# ---- item 3: an output that is an input -------------------------------------------------------------
refused "OUTPUT '$WORK/small.vtk' is the input file (same file as INPUT '$WORK/small.vtk'); choose another output path" \
    "$TPK" convert "$WORK/small.vtk" "$WORK/small.vtk"
(cd "$WORK" && refused "OUTPUT './small.vtk' is the input file (same file as INPUT 'small.vtk')" \
    "$TPK" convert small.vtk ./small.vtk)
# Same device and inode, not the same name: a hard link and a symbolic link to the input.
ln "$WORK/small.vtk" "$WORK/hard.vtk"
refused "OUTPUT '$WORK/hard.vtk' is the input file (same file as INPUT '$WORK/small.vtk')" \
    "$TPK" convert "$WORK/small.vtk" "$WORK/hard.vtk"
ln -s small.vtk "$WORK/soft.vtk"
refused "OUTPUT '$WORK/soft.vtk' is the input file" "$TPK" convert "$WORK/small.vtk" "$WORK/soft.vtk"
# TetGen's sibling, from either file and from the stem.
refused "OUTPUT '$WORK/t.node' is a file the input reads (same file as '$WORK/t.node', read for INPUT '$WORK/t.ele')" \
    "$TPK" convert "$WORK/t.ele" "$WORK/t.node"
refused "OUTPUT '$WORK/t.ele' is a file the input reads" "$TPK" convert "$WORK/t.node" "$WORK/t.ele"
refused "OUTPUT '$WORK/t.ele' is a file the input reads" "$TPK" convert "$WORK/t" "$WORK/t.ele"
# A piece the .pvd names.
refused "OUTPUT '$WORK/p1.vtu' is a file the input reads (same file as '$WORK/p1.vtu', read for INPUT '$WORK/p.pvd')" \
    "$TPK" convert "$WORK/p.pvd" "$WORK/p1.vtu"
# An OpenFOAM case's polyMesh files (a copy: the output would overwrite it), given as the case or its .foam.
cp -r "$SRC/tests/data/openfoam/cases/cavity_gzip" "$WORK/foam"
refused "OUTPUT '$WORK/foam/constant/polyMesh/owner.gz' is a file the input reads" \
    "$TPK" convert "$WORK/foam" "$WORK/foam/constant/polyMesh/owner.gz"
refused "OUTPUT '$WORK/foam/constant/polyMesh/faces.gz' is a file the input reads" \
    "$TPK" convert "$WORK/foam/cavity.foam" "$WORK/foam/constant/polyMesh/faces.gz"
# export and render.
refused "--vtu '$WORK/good.tpk' is the input file (same file as FILE.tpk '$WORK/good.tpk')" \
    "$TPK" export "$WORK/good.tpk" --vtu "$WORK/good.tpk"
ln "$WORK/good.tpk" "$WORK/good_link.ply"
refused "--shell '$WORK/good_link.ply' is the input file" "$TPK" export "$WORK/good.tpk" --shell "$WORK/good_link.ply"
refused "-o '$WORK/good.tpk' is the input file (same file as FILE.tpk '$WORK/good.tpk')" \
    "$TPK" render "$WORK/good.tpk" -o "$WORK/good.tpk" --size 8x8
refused "-o '$WORK/tf.txt' is the input file (same file as --tf '$WORK/tf.txt')" \
    "$TPK" render "$WORK/good.tpk" -o "$WORK/tf.txt" --tf "$WORK/tf.txt" --size 8x8
refused "--save-scene '$WORK/good.tpk' is the input file (same file as FILE.tpk '$WORK/good.tpk')" \
    "$TPK" render "$WORK/good.tpk" -o "$WORK/x.png" --save-scene "$WORK/good.tpk" --size 8x8
# extract.
refused "OUT.tpk '$WORK/good.tpk' is the input file (same file as IN.tpk '$WORK/good.tpk')" \
    "$TPK" extract "$WORK/good.tpk" "$WORK/good.tpk"
refused "--save-scene '$WORK/good.tpk' is the input file (same file as IN.tpk '$WORK/good.tpk')" \
    "$TPK" extract "$WORK/good.tpk" "$WORK/x.tpk" --save-scene "$WORK/good.tpk"
refused "OUT.tpk '$WORK' is a directory" "$TPK" extract "$WORK/good.tpk" "$WORK"

# ---- item 3: never replace what is not a regular file -------------------------------------------------
mkfifo "$WORK/fifo"
refused "OUTPUT '$WORK/fifo' is a FIFO; tetpack replaces only regular files" \
    "$TPK" convert "$WORK/small.vtk" "$WORK/fifo"
[ -p "$WORK/fifo" ] || fail "the FIFO was replaced"
ln -s "$WORK/elsewhere.tpk" "$WORK/dangling.tpk"
refused "OUTPUT '$WORK/dangling.tpk' is a symbolic link; tetpack replaces only regular files" \
    "$TPK" convert "$WORK/small.vtk" "$WORK/dangling.tpk"
[ -L "$WORK/dangling.tpk" ] && [ ! -e "$WORK/elsewhere.tpk" ] || fail "the link was replaced or followed"
if [ "$(id -u)" = 0 ] && mknod "$WORK/cdev" c 1 3 2>/dev/null; then # the null device's numbers
    refused "OUTPUT '$WORK/cdev' is a character device; tetpack replaces only regular files" \
        "$TPK" convert "$WORK/small.vtk" "$WORK/cdev"
    refused "--vtu '$WORK/cdev' is a character device" "$TPK" export "$WORK/good.tpk" --vtu "$WORK/cdev"
    refused "-o '$WORK/cdev' is a character device" "$TPK" render "$WORK/good.tpk" -o "$WORK/cdev" --size 8x8
    [ -c "$WORK/cdev" ] || fail "the character device was replaced"
else
    echo "SKIP: a character device as output (mknod needs root and a filesystem that allows it)"
fi

# ---- item 5: empty paths and directories, refused before any work, naming the argument ---------------
refused "OUTPUT is empty; expected a file path" "$TPK" convert "$WORK/small.vtk" ""
refused "OUTPUT '$WORK' is a directory; expected a file path" "$TPK" convert "$WORK/small.vtk" "$WORK"
refused "OUTPUT '$WORK/new/' names a directory (ends with '/')" "$TPK" convert "$WORK/small.vtk" "$WORK/new/"
refused "OUTPUT '$WORK/no/such/x.tpk': the directory '$WORK/no/such' does not exist" \
    "$TPK" convert "$WORK/small.vtk" "$WORK/no/such/x.tpk"
# Before the work: a broken input is not even read when the output is unusable.
printf '# vtk DataFile Version 2.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n' > "$WORK/trunc.vtk"
refused "OUTPUT '$WORK' is a directory" "$TPK" convert "$WORK/trunc.vtk" "$WORK"
refused "--vtu is empty" "$TPK" export "$WORK/good.tpk" --vtu ""
refused "--shell '$WORK' is a directory" "$TPK" export "$WORK/good.tpk" --shell "$WORK"
# Two outputs of one export that are one file: the second would replace the first.
refused "--vtu '$WORK/both.vtu' and --shell '$WORK/both.vtu' name the same file" \
    "$TPK" export "$WORK/good.tpk" --vtu "$WORK/both.vtu" --shell "$WORK/both.vtu"
[ ! -e "$WORK/both.vtu" ] || fail "a refused export wrote $WORK/both.vtu"
refused "-o '$WORK' is a directory" "$TPK" render "$WORK/good.tpk" -o "$WORK"
# ... and the directory check comes before opening FILE.tpk (a broken one is not read either).
refused "-o is empty" "$TPK" render "$WORK/trunc.vtk" -o ""

# ---- item 4: killed while writing ---------------------------------------------------------------------
# Outputs go to their own directory, so that its listing shows every temporary file.
OUT="$WORK/o"
mkdir "$OUT"
# O_TMPFILE is what lets even SIGKILL leave nothing; a filesystem without it gets the named fallback.
if "$PY" -c "import os,sys; os.close(os.open(sys.argv[1], os.O_TMPFILE | os.O_WRONLY))" "$OUT" 2>/dev/null; then
    UNNAMED=1
else
    UNNAMED=0
    echo "SKIP: SIGKILL cases ($OUT has no O_TMPFILE: a killed process can leave a named temporary file there)"
fi

# start_held MODE cmd...: start cmd in the background ($pid) with the output hook on (MODE named: the
# fallback without O_TMPFILE) and wait until it holds there, its output complete but not in place, or
# ends. Succeeds when it holds. It waits for the hook, not for a time: the bound turns a hang into a failure.
start_held() {
    local named=0
    [ "$1" = named ] && named=1
    shift
    rm -f "$WORK/hold"
    TPK_TEST_OUTPUT_NAMED=$named TPK_TEST_OUTPUT_HOLD="$WORK/hold" "$@" >"$WORK/out" 2>"$WORK/err" &
    pid=$!
    for _ in $(seq 1200); do
        [ ! -e "$WORK/hold" ] && kill -0 "$pid" 2>/dev/null || break
        sleep 0.05
    done
    [ -e "$WORK/hold" ]
}

# end_held [SIGNAL]: kill the held process with SIGNAL, or without one let it go on; its status in $rc.
end_held() {
    if [ $# = 1 ]; then kill -"$1" "$pid"; else rm -f "$WORK/hold"; fi
    set +e
    { wait "$pid"; } 2>/dev/null # bash would report a death by signal on stderr
    rc=$?
    set -e
    rm -f "$WORK/hold"
}

# held MODE SIGNAL TARGET cmd...: kill cmd with SIGNAL while it holds its output TARGET, after checking
# what the output directory shows then (unnamed: nothing new; named: one TARGET.tmp.* file); afterwards
# the directory lists what it did before and TARGET (if there was one) kept its bytes.
held() {
    local mode=$1 sig=$2 target=$3
    shift 3
    local before during sum="none"
    before=$(ls -A "$OUT")
    [ ! -e "$target" ] || sum=$(sha1sum < "$target")
    start_held "$mode" "$@" || { kill -KILL "$pid" 2>/dev/null || true; cat "$WORK/err" >&2; fail "never held its output: $*"; }
    during=$(ls -A "$OUT")
    if [ "$mode" = named ]; then
        [ "$(echo "$during" | grep -c "^$(basename "$target")\.tmp\.")" = 1 ] ||
            fail "expected one named temporary file while held, found: $during"
    else
        [ "$during" = "$before" ] || fail "a file is visible before the output is in place: $during"
    fi
    end_held "$sig"
    [ "$rc" -ge 128 ] || fail "expected death by SIG$sig, got exit $rc: $*"
    [ "$(ls -A "$OUT")" = "$before" ] || fail "left behind by SIG$sig: $(ls -A "$OUT")"
    if [ "$sum" = none ]; then
        [ ! -e "$target" ] || fail "an output appeared"
    else
        [ "$(sha1sum < "$target")" = "$sum" ] || fail "the older output changed after SIG$sig"
    fi
}

# released MODE cmd...: run cmd through the hook and let it go on: it succeeds and leaves no temporary file.
released() {
    local mode=$1
    shift
    start_held "$mode" "$@" || fail "never held its output: $*"
    end_held
    [ "$rc" = 0 ] || { cat "$WORK/err" >&2; fail "failed after the hook: $*"; }
    [ -z "$(ls -A "$OUT" | grep '\.tmp\.')" ] || fail "temporary file left after success: $(ls -A "$OUT")"
}

# An older output to keep: a conversion with other options, so that any replacement would show.
"$TPK" convert "$WORK/small.vtk" "$OUT/old.tpk" --zstd 3 --quiet
"$TPK" export "$WORK/good.tpk" --vtu "$OUT/old.vtu" --shell "$OUT/old.ply" >/dev/null
"$TPK" render "$WORK/good.tpk" -o "$OUT/old.png" --size 16x16 >/dev/null
modes=named
[ "$UNNAMED" = 0 ] || modes="unnamed named"
for mode in $modes; do
    # A named temporary file survives SIGKILL: the fallback can only promise the signals it catches.
    sigs="KILL TERM"
    [ "$mode" = unnamed ] || sigs="TERM HUP"
    for sig in $sigs; do
        held "$mode" "$sig" "$OUT/old.tpk" "$TPK" convert "$WORK/small.vtk" "$OUT/old.tpk" --quiet
        held "$mode" "$sig" "$OUT/new.tpk" "$TPK" convert "$WORK/small.vtk" "$OUT/new.tpk" --quiet
        held "$mode" "$sig" "$OUT/old.vtu" "$TPK" export "$WORK/good.tpk" --vtu "$OUT/old.vtu"
        held "$mode" "$sig" "$OUT/old.ply" "$TPK" export "$WORK/good.tpk" --shell "$OUT/old.ply"
        held "$mode" "$sig" "$OUT/old.png" "$TPK" render "$WORK/good.tpk" -o "$OUT/old.png" --size 16x16
        held "$mode" "$sig" "$OUT/old.tpk" "$TPK" extract "$WORK/good.tpk" "$OUT/old.tpk"
    done
    # Let go, the outputs replace the old ones (or appear) whole: the same bytes as a plain run.
    released "$mode" "$TPK" convert "$WORK/small.vtk" "$OUT/old.tpk" --quiet
    released "$mode" "$TPK" convert "$WORK/small.vtk" "$OUT/new.tpk" --quiet
    cmp "$OUT/old.tpk" "$WORK/good.tpk" || fail "$mode: the replaced output differs from a plain conversion"
    cmp "$OUT/new.tpk" "$WORK/good.tpk" || fail "$mode: the new output differs from a plain conversion"
    released "$mode" "$TPK" export "$WORK/good.tpk" --vtu "$OUT/old.vtu"
    cmp "$OUT/old.vtu" "$WORK/p0.vtu" || fail "$mode: the replaced VTU differs from a plain export"
    [ "$(stat -c %a "$OUT/new.tpk")" = 644 ] || fail "$mode: output mode $(stat -c %a "$OUT/new.tpk"), expected 644"
    rm "$OUT/new.tpk"
    "$TPK" convert "$WORK/small.vtk" "$OUT/old.tpk" --zstd 3 --quiet
done
# Checked up front and again when put in place: a FIFO made at the path meanwhile is not replaced.
start_held unnamed "$TPK" convert "$WORK/small.vtk" "$OUT/race.tpk" --quiet || fail "never held its output"
mkfifo "$OUT/race.tpk"
end_held
[ "$rc" = 2 ] || fail "expected exit 2 when a FIFO appeared at the output, got $rc"
expect_stderr "$OUT/race.tpk is now a FIFO; tetpack replaces only regular files"
[ -p "$OUT/race.tpk" ] || fail "the FIFO that appeared was replaced"
[ -z "$(ls -A "$OUT" | grep '\.tmp\.')" ] || fail "temporary file left: $(ls -A "$OUT")"
# A write that fails part-way (the file-size limit, with SIGXFSZ ignored so write() fails with EFBIG), at
# one thread and at two (where the writer's calls run on a thread of their own): exit 2, the system's
# reason in the message, the older output intact and nothing left behind.
cp "$WORK/good.tpk" "$OUT/limited.tpk"
limit_kb=$(( $(stat -c %s "$WORK/good.tpk") / 2048 ))
for threads in 1 2; do
    set +e
    (ulimit -f "$limit_kb"; trap '' XFSZ; exec "$TPK" convert "$WORK/small.vtk" "$OUT/limited.tpk" --quiet \
        --threads "$threads") >"$WORK/out" 2>"$WORK/err"
    rc=$?
    set -e
    [ "$rc" = 2 ] || { cat "$WORK/err" >&2; fail "expected exit 2 past the file-size limit ($threads threads), got $rc"; }
    expect_stderr "cannot write .*: File too large"
    cmp "$OUT/limited.tpk" "$WORK/good.tpk" || fail "the older output changed after a failed write"
    [ -z "$(ls -A "$OUT" | grep '\.tmp\.')" ] || fail "temporary file left: $(ls -A "$OUT")"
done
echo "outputs: ok"
