#!/usr/bin/env python3
"""PSNR (dB) between two 8-bit PNGs of the same size, as tetpack render writes them, over the RGB
channels; prints "psnr DB max_diff N". Exit 1 when below --min (default none). Decoded by png_read.py
beside it (zlib and the scanline filters), so the tests need no imaging library."""
import sys

import numpy as np

from png_read import pixels as read_png


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
