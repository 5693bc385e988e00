"""tetpack from Python in 30 lines: convert the bundled sample, open it, do NumPy on its arrays.
Run from the repository root after `./dev build`:
    PYTHONPATH=build/python python3 samples/python_quickstart.py        (writes into out/)"""
import os
import sys

import numpy as np

import tetpack

out = sys.argv[1] if len(sys.argv) > 1 else "out"
os.makedirs(out, exist_ok=True)
path = os.path.join(out, "cylinder.tpk")
summary = tetpack.convert(os.path.join(os.path.dirname(__file__), "cylinder.vtk"), path, layouts=(32, 16))
print("converted: %d tets, %d vertices" % (summary["tets"], summary["vertices"]))

with tetpack.open(path) as f:
    print(f, "fields:", f.fields, "layouts:", f.layouts)
    p = f.points()                      # float64 world coordinates (origin + float32 positions)
    tets = f.tets()                     # int32 (tets, 4), positively oriented
    a, b, c, d = (p[tets[:, k]] for k in range(4))
    volume = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6
    print("volume %.6g, smallest tet %.3g, all positive: %s" % (volume.sum(), volume.min(), (volume > 0).all()))
    temperature = f.field("temperature")  # a view into the file: nothing copied
    print("volume-weighted mean temperature: %.4g" % np.average(temperature[tets].mean(axis=1), weights=volume))
    print("converted by:", f.meta["converter"], "from", f.meta["source"]["path"])
