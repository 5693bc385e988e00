# Sourced by the CLI tests: $1 = tetpack binary, $2 = shared data dir, $3 = source dir.
set -euo pipefail
TPK=$1
DATA=$2
SRC=$3
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tpk_cli_XXXXXX")
trap 'rm -rf "$WORK"' EXIT
# Debian's python3 (with python3-meshio and numpy), not whatever python3 comes first on PATH.
PY=/usr/bin/python3
fail() { echo "FAIL: $*" >&2; exit 1; }
# cli_py ARGS: $PY with the helper modules of tests/cli/ importable (vtk_write.py, png_read.py, ...)
cli_py() { PYTHONPATH="$SRC/tests/cli" "$PY" "$@"; }
# tpk ARGS: the tetpack under test; under the sanitizers CMake sets TPK_VK_PRELOAD (libasan and lavapipe,
# tests/CMakeLists.txt) for the Vulkan scripts, preloaded for the tetpack runs only (not for bash), so that
# LeakSanitizer can name the drivers' own leaks.
tpk() {
    if [ -n "${TPK_VK_PRELOAD:-}" ]; then LD_PRELOAD="$TPK_VK_PRELOAD" "$TPK" "$@"; else "$TPK" "$@"; fi
}
# psnr A.png B.png: their PSNR in dB ("inf" when equal); at_least X Y: X >= Y, as numbers
psnr() { "$PY" "$SRC/tests/cli/psnr.py" "$1" "$2" | sed -n 's/^psnr \([0-9.inf]*\).*/\1/p'; }
at_least() { "$PY" -c "import sys; sys.exit(0 if float(sys.argv[1]) >= float(sys.argv[2]) else 1)" "$1" "$2"; }
# skip WHY: this test cannot run here (an optional component is missing): exit 77, ctest's SKIP_RETURN_CODE,
# so it shows as Skipped; under TETPACK_REQUIRE_ALL=1 (./dev test, CI) a skip is a failure.
skip() {
    [ "${TETPACK_REQUIRE_ALL:-0}" = 1 ] && fail "TETPACK_REQUIRE_ALL=1 forbids skips: $*"
    echo "SKIP: $*"
    exit 77
}
# expect_exit CODE cmd...: run cmd, capture stderr in $WORK/err, check the exit code.
expect_exit() {
    local want=$1
    shift
    set +e
    "$@" >"$WORK/out" 2>"$WORK/err"
    local got=$?
    set -e
    [ "$got" -eq "$want" ] || { cat "$WORK/err" >&2; fail "expected exit $want, got $got: $*"; }
}
expect_stderr() { grep -q -- "$1" "$WORK/err" || { cat "$WORK/err" >&2; fail "stderr lacks '$1'"; }; }
# check_6xx FILE.tpk: the format's MUSTs (tetpack check 600..613) hold for a written file. Other groups
# may report the source mesh's own problems (slivers, a fold cut with --cut-folds): not asserted here.
check_6xx() { # FILE.tpk [LAST_ID: 613, or 615 to take in the levels of detail (spec §16)]
    local code=0
    "$TPK" check "$1" --json --no-self-intersections --no-progress > "$WORK/check6.json" 2> "$WORK/check6.err" || code=$?
    [ "$code" -le 1 ] || { cat "$WORK/check6.err" >&2; fail "tetpack check cannot read $1"; }
    "$PY" - "$WORK/check6.json" "$1" "${2:-613}" <<'PYEOF' || fail "$1 breaks a MUST of the spec"
import json, sys
bad = [f for f in json.load(open(sys.argv[1]))["findings"] if 600 <= f["id"] <= int(sys.argv[3]) and f["count"]]
for f in bad:
    print("%s: check %d %s: %d, first %s" % (sys.argv[2], f["id"], f["name"], f["count"], f["examples"][:1]), file=sys.stderr)
sys.exit(1 if bad else 0)
PYEOF
}
# convert_checked INPUT OUTPUT.tpk [options...]: tetpack convert (stdout as the caller redirects it),
# then check_6xx on what it wrote. Every CLI test that converts a file successfully goes through here.
convert_checked() {
    "$TPK" convert "$@"
    check_6xx "$2"
}

# bound_beats_plain NAME SOURCE PLAIN.tpk BOUND: SOURCE (two higher-order cells) converted with
# --max-error BOUND; check --against (sampling the source cells through their own functions) samples both
# cells, finds the recorded bound met and a sampled error within BOUND, where the plain split PLAIN.tpk's
# is above it. NAME labels the failures.
bound_beats_plain() {
    local name=$1 source=$2 plain_tpk=$3 bound=$4 plain got
    "$TPK" check "$plain_tpk" --against "$source" --samples 8 > "$WORK/plain.txt" ||
        fail "$name: check --against of the plain split: $(cat "$WORK/plain.txt")"
    convert_checked "$source" "$WORK/me.tpk" --max-error "$bound" 2> "$WORK/err" ||
        fail "$name: convert --max-error $bound: $(cat "$WORK/err")"
    "$TPK" check "$WORK/me.tpk" --against "$source" --samples 8 > "$WORK/against.txt" 2>&1 ||
        fail "$name: check --against: $(cat "$WORK/against.txt")"
    grep -q "in 2 source cells" "$WORK/against.txt" && grep -q "bound recorded in META: $bound: met" "$WORK/against.txt" ||
        fail "$name: check --against did not sample both cells: $(cat "$WORK/against.txt")"
    plain=$(sed -n 's/.*max error \([^ ]*\) .*/\1/p' "$WORK/plain.txt")
    got=$(sed -n 's/.*max error \([^ ]*\) .*/\1/p' "$WORK/against.txt")
    "$PY" -c "import sys; sys.exit(not ($got <= $bound < $plain))" ||
        fail "$name: sampled error $got at --max-error $bound (plain split $plain)"
}

# keys OUT FILE.tpk... : into OUT, sorted tet keys (their 4 world positions, sorted) and outer-face keys of the
# union of the files, through tetpack export --vtu and meshio.
keys() {
    local out=$1
    shift
    local vtus=()
    for f in "$@"; do
        "$TPK" export "$f" --vtu "$f.vtu" > /dev/null
        vtus+=("$f.vtu")
    done
    "$PY" - "$out" "${vtus[@]}" <<'PYEOF'
import sys, collections, meshio, numpy as np
tets, faces = [], collections.Counter()
for path in sys.argv[2:]:
    m = meshio.read(path)
    pts = m.points
    for block in m.cells:
        if block.type != "tetra":
            continue
        for t in block.data:
            p = [tuple(pts[i]) for i in t]
            tets.append(tuple(sorted(p)))
            for k in range(4):
                faces[tuple(sorted(p[:k] + p[k + 1:]))] += 1
outer = sorted(f for f, n in faces.items() if n == 1)
with open(sys.argv[1], "w") as out:
    out.write("%d tets %d outer faces\n" % (len(tets), len(outer)))
    for t in sorted(tets):
        out.write("T %r\n" % (t,))
    for f in outer:
        out.write("F %r\n" % (f,))
PYEOF
}
