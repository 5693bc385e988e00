#!/usr/bin/env bash
# Every crasher of tests/crashers/ through every subcommand that reads it: no crash, no hang, no
# sanitizer report; exit 0, 1 or 2 (tests/crashers/README.md).
source "$(dirname "$0")/common.sh"
CRASHERS=$SRC/tests/crashers

"$TPK" convert "$SRC/samples/cylinder.vtk" "$WORK/cylinder.tpk" --quiet || fail "cannot convert the sample"

# harmless NAME cmd...: the command ends by itself within 30 s, with exit 0..2 and no sanitizer report
harmless() {
    local name=$1 code=0
    shift
    timeout -s KILL 30 "$@" > "$WORK/out" 2> "$WORK/err" || code=$?
    if [ "$code" -gt 2 ] || grep -qE "Sanitizer|runtime error:" "$WORK/err"; then
        tail -20 "$WORK/err" >&2
        fail "$name: exit $code (137: killed after 30 s): $*"
    fi
    echo "ok $name: exit $code: $*"
}

count=0
for input in "$CRASHERS"/*; do
    name=$(basename "$input")
    case $name in
        README.md) continue ;;
        *.json) # a scene file
            harmless "$name" "$TPK" render "$WORK/cylinder.tpk" -o "$WORK/x.png" --scene "$input" --backend cpu --size 32x24
            harmless "$name" "$TPK" extract "$WORK/cylinder.tpk" "$WORK/x.tpk" --scene "$input"
            harmless "$name" "$TPK" check "$input" ;;
        *)
            harmless "$name" "$TPK" convert "$input" "$WORK/x.tpk"
            harmless "$name" "$TPK" check "$input"
            harmless "$name" "$TPK" check --json "$input"
            harmless "$name" "$TPK" info "$input"
            harmless "$name" "$TPK" render "$input" -o "$WORK/x.png" --backend cpu --size 32x24
            harmless "$name" "$TPK" extract "$input" "$WORK/x.tpk" ;;
    esac
    count=$((count + 1))
done
[ "$count" -gt 0 ] || fail "no crashers in $CRASHERS"

# HDF5 itself crashes on this one: the child process that read it dies, and tetpack says so.
code=0
"$TPK" convert "$CRASHERS/vtkhdf_hdf5_null_memcpy.vtkhdf" "$WORK/hdf5_crash.tpk" 2> "$WORK/err" || code=$?
[ "$code" = 2 ] && grep -q "vtkhdf_hdf5_null_memcpy.vtkhdf: the HDF5 library failed reading this file (its process ended with signal" "$WORK/err" \
    || fail "an HDF5 crash: exit $code, $(cat "$WORK/err")"
[ ! -e "$WORK/hdf5_crash.tpk" ] || fail "an HDF5 crash left an output"
echo "crashers: $count files, every subcommand harmless"
