#!/usr/bin/python3
"""Open a big uncompressed .tpk from Python and sum its positions with NumPy, against meshio.read of the
same mesh as VTU (what `tetpack export --vtu` writes). Each measurement runs in a fresh python3, timed
from before the read to after the sum; peak RSS is that process's maximum resident set, less what it
held after importing numpy, meshio and tetpack. Run on demand (not in ctest):
    bench/python_open.py BUILD_DIR [N ...]     (grid edge N: 6*N^3 tets; default 119, about 10.1M tets)
Medians of TPK_BENCH_RUNS runs (default 3); files under TPK_BENCH_DIR (default /tmp/tpk_bench_python)."""
import json
import os
import statistics
import subprocess
import sys

RUNS = int(os.environ.get("TPK_BENCH_RUNS", "3"))
WORK = os.environ.get("TPK_BENCH_DIR", "/tmp/tpk_bench_python")

# What each child runs after its imports: (label, code that reads `path` and leaves a float in `total`).
READERS = {
    "tetpack.open + positions().sum()":
        "f = tetpack.open(path); total = float(f.positions().sum(dtype=np.float64))",
    "tetpack.open + points().sum() (float64 world copy)":
        "f = tetpack.open(path); total = float(f.points().sum())",
    "tetpack.open + tets() (recovered from Tet16)":
        "f = tetpack.open(path); total = float(f.tets()[:, 0].sum())",
    "meshio.read(VTU) + points.sum()":
        "m = meshio.read(path); total = float(m.points.sum())",
}

CHILD = """
import resource, sys, time
import meshio, numpy as np, tetpack
path = sys.argv[1]
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
start = time.perf_counter()
%s
seconds = time.perf_counter() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(seconds, (peak - base) / 1024.0, peak / 1024.0, total)
"""


def measure(code, path, env):
    runs = []
    for _ in range(RUNS):
        out = subprocess.run([sys.executable, "-c", CHILD % code, path], check=True, capture_output=True,
                             text=True, env=env).stdout.split()
        runs.append([float(x) for x in out])
    return [statistics.median(r[k] for r in runs) for k in range(4)]


def main():
    build = os.path.abspath(sys.argv[1])
    sizes = [int(n) for n in sys.argv[2:]] or [119]
    tetpack_exe = os.path.join(build, "tetpack")
    env = dict(os.environ, PYTHONPATH=os.path.join(build, "python"))
    here = os.path.dirname(os.path.abspath(__file__))
    os.makedirs(WORK, exist_ok=True)
    print("| mesh | reader | file | median time | peak RSS above imports | peak RSS / file |")
    print("|---|---|---|---|---|---|")
    for n in sizes:
        vtk = os.path.join(WORK, "grid%d.vtk" % n)
        tpk, vtu = os.path.join(WORK, "grid%d.tpk" % n), os.path.join(WORK, "grid%d.vtu" % n)
        if not os.path.exists(vtk):
            subprocess.run([sys.executable, os.path.join(here, "make_grid_vtk.py"), str(n), vtk], check=True)
        summary = json.loads(subprocess.run([tetpack_exe, "convert", vtk, tpk, "--json"], check=True,
                                            capture_output=True, text=True).stdout)
        subprocess.run([tetpack_exe, "export", tpk, "--vtu", vtu], check=True)
        sums = []
        for label, code in READERS.items():
            path = vtu if label.startswith("meshio") else tpk
            seconds, peak_above, _, total = measure(code, path, env)
            size = os.path.getsize(path)
            print("| grid %d³, %s tets | %s | %.1f MiB | %.4f s | %.1f MiB | %.3f |" % (
                n, format(summary["tets"], ","), label, size / 2**20, seconds, peak_above, peak_above * 2**20 / size))
            if "sum()" in label:
                sums.append(total)
        print("sums of coordinates (equal when the origin is 0):", sums, file=sys.stderr)


if __name__ == "__main__":
    main()
