#!/usr/bin/env python3
"""module_graph.py must fail a tree that breaks the folder order (ctest house.folder_order).

tests/deps/bad_tree/ is a tiny fake project: tools/base/low.c includes a header of mesh/ and calls a
function of mesh/; tools/check/sibling.c includes a header of export/, its sibling. This compiles it into
a fake build tree laid out as CMake lays out tetpack_tools, runs module_graph.py on it (includes and
symbols) and on the sources alone, and asserts that each run exits 1 naming every breach.

usage: folder_order_test.py [CC]
"""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
TREE = os.path.join(HERE, "bad_tree")
GRAPH = os.path.join(HERE, "module_graph.py")

INCLUDE_BREACHES = (
    'tools/base/low.c: includes "mesh/high.h", from tools/mesh/high.h, but mesh/ is above base/',
    'tools/check/sibling.c: includes "export/exporter.h", from tools/export/exporter.h, but export/ is the '
    "same level as check/",
)
SYMBOL_BREACH = "tools/base/low.c: uses a symbol of tools/mesh/high.c, but mesh/ is above base/"


def run(build_dir):
    done = subprocess.run([sys.executable, GRAPH, TREE, build_dir], capture_output=True, text=True)
    print(done.stdout, end="")
    return done.returncode, done.stdout


def expect(rc, out, wanted):
    ok = rc == 1
    if not ok:
        print(f"FAIL: module_graph exited {rc}, not 1, on a tree that breaks the folder order")
    for line in wanted:
        if line not in out:
            print(f"FAIL: module_graph did not report: {line}")
            ok = False
    return ok


def main(argv):
    cc = argv[1] if len(argv) > 1 else os.environ.get("CC", "cc")
    ok = expect(*run("-"), INCLUDE_BREACHES)
    with tempfile.TemporaryDirectory() as build:
        for src in ("base/low.c", "mesh/high.c", "check/sibling.c"):
            obj = os.path.join(build, "tools", "CMakeFiles", "tetpack_tools.dir", src + ".o")
            os.makedirs(os.path.dirname(obj), exist_ok=True)
            subprocess.run([cc, "-c", "-I", os.path.join(TREE, "tools"), os.path.join(TREE, "tools", src),
                            "-o", obj], check=True)
        ok = expect(*run(build), INCLUDE_BREACHES + (SYMBOL_BREACH,)) and ok
    print("folder_order_test: " + ("module_graph fails the bad tree, as it must" if ok else "FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
