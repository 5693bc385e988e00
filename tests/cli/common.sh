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
