#!/bin/sh
# ctest python.paraview_reader: run pv_reader.py under pvpython, headless. Exit 77 (a visible skip) when
# ParaView is not installed (./dev installs it; a build elsewhere may lack it). Debian's ParaView renders
# through GLX only, hence Xvfb.
# usage: paraview_reader.sh DATA_DIR OUT_DIR
set -e
if ! command -v pvpython >/dev/null 2>&1; then
    echo "SKIP: pvpython not found (apt-get install paraview python3-paraview xvfb)"
    exit 77
fi
mkdir -p "$2"
cd "$(dirname "$0")"
if [ -z "${DISPLAY:-}" ]; then
    if ! command -v xvfb-run >/dev/null 2>&1; then
        echo "SKIP: no DISPLAY and no xvfb-run (apt-get install xvfb)"
        exit 77
    fi
    exec xvfb-run -a pvpython pv_reader.py "$1" "$2"
fi
exec pvpython pv_reader.py "$1" "$2"
