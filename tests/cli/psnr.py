#!/usr/bin/env python3
"""PSNR (dB) between two 8-bit RGBA PNGs of the same size, as tetpack render writes them, over the
RGB channels; prints "psnr DB max_diff N". Exit 1 when below --min (default none). A small PNG reader
(zlib + the five scanline filters) so the tests need no imaging library."""
import sys
import zlib

import numpy as np


def read_png(path):
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit("%s: not a PNG" % path)
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        n = int.from_bytes(data[pos:pos + 4], "big")
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            width, height = int.from_bytes(body[0:4], "big"), int.from_bytes(body[4:8], "big")
            if body[8] != 8 or body[9] != 6 or body[12] != 0:
                sys.exit("%s: expected 8-bit RGBA, not interlaced" % path)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(height, 1 + 4 * width)
    out = np.zeros((height, 4 * width), dtype=np.int32)
    for y in range(height):
        f, line = raw[y, 0], raw[y, 1:].astype(np.int32)
        prev = out[y - 1] if y else np.zeros(4 * width, dtype=np.int32)
        row = np.zeros(4 * width, dtype=np.int32)
        for x in range(4 * width):
            a = row[x - 4] if x >= 4 else 0
            b = prev[x]
            c = prev[x - 4] if x >= 4 else 0
            if f == 0:
                p = 0
            elif f == 1:
                p = a
            elif f == 2:
                p = b
            elif f == 3:
                p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            row[x] = (line[x] + p) & 255
        out[y] = row
    return out.reshape(height, width, 4)


def main():
    args = sys.argv[1:]
    minimum = None
    if "--min" in args:
        i = args.index("--min")
        minimum = float(args[i + 1])
        del args[i:i + 2]
    a, b = read_png(args[0]), read_png(args[1])
    if a.shape != b.shape:
        sys.exit("sizes differ: %s vs %s" % (a.shape, b.shape))
    diff = (a[:, :, :3] - b[:, :, :3]).astype(np.float64)
    mse = float(np.mean(diff * diff))
    psnr = float("inf") if mse == 0 else 10 * np.log10(255.0 * 255.0 / mse)
    print("psnr %.2f max_diff %d" % (psnr, int(np.max(np.abs(diff)))))
    if minimum is not None and psnr < minimum:
        sys.exit(1)


main()
