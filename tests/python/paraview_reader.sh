#!/bin/sh
# ctest python.paraview_reader: run pv_reader.py under pvpython, headless. Exit 77 (a visible skip) when
# ParaView is not installed (./dev installs it; a build elsewhere may lack it). Debian's ParaView renders
# through GLX only, hence an Xvfb of its own (tests/with_xvfb.sh) when there is no DISPLAY.
# usage: paraview_reader.sh DATA_DIR OUT_DIR
set -e
if ! command -v pvpython >/dev/null 2>&1; then
    echo "SKIP: pvpython not found (apt-get install paraview python3-paraview xvfb)"
    exit 77
fi
mkdir -p "$2"
cd "$(dirname "$0")"
if [ -n "${DISPLAY:-}" ]; then
    exec pvpython pv_reader.py "$1" "$2"
fi
# A server that refuses the connection is the machine's fault, not the reader's: say so and try once
# more on a fresh server. Any other failure fails the test.
for try in 1 2; do
    status=0
    sh ../with_xvfb.sh pvpython pv_reader.py "$1" "$2" > "$2/pvpython.log" 2>&1 || status=$?
    cat "$2/pvpython.log"
    if [ "$status" -eq 0 ] || ! grep -q "bad X server connection" "$2/pvpython.log"; then
        exit "$status"
    fi
    echo "paraview_reader.sh: try $try: the X server refused pvpython's connection"
done
exit "$status"
