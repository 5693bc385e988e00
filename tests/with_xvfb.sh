#!/bin/sh
# with_xvfb.sh [-screen WxHxD] [-audit] CMD [ARG...]: run CMD with DISPLAY on a fresh Xvfb of its own, then
# stop that server and wait for it to exit. -audit: the server logs each client's connection and
# disconnection, with its pid, to the file named by TPK_XVFB_LOG in CMD's environment.
#
# Why not `xvfb-run -a`: it picks the display by looking for a free /tmp/.XN-lock, which races with a
# server still exiting (or with one that another container started under a different /tmp but the same
# abstract socket namespace); a CI run failed with "bad X server connection. DISPLAY=:100". Here Xvfb
# picks the display itself (-displayfd: it takes the first number whose lock and sockets it gets, and
# writes it once it accepts connections), refuses to run with only some of its sockets (-nopn), and gets
# its own cookie (xauth), so no client reaches another server by mistake.
#
# -noreset: by default an X server resets when its last client leaves, and a connection made while it
# does is refused ("Failed to open display"): a CI run failed so, at a client closing its only connection
# and opening another at once (tetpack view's fallback to OpenGL then did so; it keeps one now, and
# tests/cli/view.sh checks that through -audit). Consecutive clients are not this test's subject.
#
# Exit status: CMD's; 77 (ctest's skip) when Xvfb or xauth is missing; 1 when the server does not start.
set -eu
screen=640x480x24
audit=
if [ "${1:-}" = "-screen" ]; then screen=$2; shift 2; fi
if [ "${1:-}" = "-audit" ]; then audit="-audit 4"; shift; fi # level 4: connections (Xvfb 21 logs none below)
for tool in Xvfb xauth mcookie; do
    command -v "$tool" > /dev/null 2>&1 || { echo "SKIP: $tool not found (apt-get install xvfb xauth)"; exit 77; }
done
dir=$(mktemp -d "${TMPDIR:-/tmp}/tpk-xvfb.XXXXXX")
pid=
cleanup() {
    if [ -n "$pid" ]; then kill "$pid" 2> /dev/null || :; wait "$pid" 2> /dev/null || :; fi
    rm -rf "$dir"
}
trap cleanup EXIT
trap 'exit 129' HUP
trap 'exit 130' INT
trap 'exit 143' TERM
cookie=$(mcookie)
# The server reads every cookie in its -auth file; the display number is not known yet, so the entry
# names display 0 and the client's entry is added once the number is known.
: > "$dir/server.auth"; : > "$dir/client.auth"
XAUTHORITY="$dir/server.auth" xauth -q add :0 . "$cookie"
mkfifo "$dir/displayfd"
# shellcheck disable=SC2086 # $audit: none or two words
Xvfb -displayfd 3 -nopn -noreset -nolisten tcp -auth "$dir/server.auth" -screen 0 "$screen" $audit \
    3> "$dir/displayfd" > "$dir/xvfb.log" 2>&1 &
pid=$!
# Read the number (the fifo's writer is the server; it closes when the server exits). A server that
# has not written one in 30 s is taken as failed.
display=$(timeout 30 head -n 1 "$dir/displayfd" || :)
case "$display" in
    ''|*[!0-9]*)
        echo "FAIL: Xvfb did not start (no display number); its log:" >&2
        cat "$dir/xvfb.log" >&2
        exit 1 ;;
esac
XAUTHORITY="$dir/client.auth" xauth -q add ":$display" . "$cookie"
status=0
DISPLAY=":$display" XAUTHORITY="$dir/client.auth" TPK_XVFB_LOG="$dir/xvfb.log" "$@" || status=$?
if [ "$status" -ne 0 ] && [ -s "$dir/xvfb.log" ]; then
    echo "(Xvfb :$display log follows)" >&2
    cat "$dir/xvfb.log" >&2
fi
exit "$status"
