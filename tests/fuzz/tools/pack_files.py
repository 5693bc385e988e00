#!/usr/bin/env python3
"""Pack files into one fuzz input of a multi-file target (tests/fuzz/support.h): each file after a line
"@@ NAME", NAME relative to ROOT. Usage: pack_files.py ROOT NAME... > seed"""
import sys


def main():
    root, names = sys.argv[1], sys.argv[2:]
    out = sys.stdout.buffer
    for k, name in enumerate(names):
        with open(f"{root}/{name}", "rb") as f:
            body = f.read()
        out.write(b"" if k == 0 else b"\n")
        out.write(b"@@ " + name.encode() + b"\n" + body)


main()
