#!/usr/bin/python3
"""Derive the bundled samples from the shared real meshes (run from the repository root).

cylinder.vtk: ../shared/data/sfepy/cylinder.vtk (sfepy 2021.4, BSD-3) unchanged, plus a point field
'temperature' = a smooth analytic function of the coordinates, so the sample has something to render.
"""
import math
import sys

SRC = "../shared/data/sfepy/cylinder.vtk"
DST = "samples/cylinder.vtk"


def temperature(x, y, z):
    # A hot spot near one end of the cylinder, decaying along the axis, with a swirl across it.
    r = math.hypot(y, z)
    return 300.0 + 80.0 * math.exp(-((x - 0.02) / 0.03) ** 2) * (1.0 - (r / 0.02) ** 2) \
        + 10.0 * math.sin(40.0 * x + 3.0 * math.atan2(z, y))


def main():
    lines = open(SRC).read().splitlines()
    header = lines.index(next(l for l in lines if l.startswith("POINTS")))
    count = int(lines[header].split()[1])
    coords = []
    i = header + 1
    while len(coords) < 3 * count:
        coords.extend(float(v) for v in lines[i].split())
        i += 1
    out = lines[:1] + ["tetpack sample: sfepy cylinder.vtk (BSD-3) + analytic point field 'temperature'"]
    out += lines[2:]
    out.append("POINT_DATA %d" % count)
    out.append("SCALARS temperature float 1")
    out.append("LOOKUP_TABLE default")
    for p in range(count):
        out.append("%.6f" % temperature(*coords[3 * p:3 * p + 3]))
    open(DST, "w").write("\n".join(out) + "\n")
    print("wrote %s: %d points" % (DST, count), file=sys.stderr)


if __name__ == "__main__":
    main()
