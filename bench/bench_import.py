#!/usr/bin/python3
"""Issue 11's speed table, measured side by side: tetpack's importers against meshio's readers, and the
whole conversion of a 971k-hexahedron mesh against the VTK pipeline (read, vtkDataSetTriangleFilter,
vtkDataSetSurfaceFilter).

    bench/bench_import.py [TETPACK] [--runs N] [--vtk-runs N] [--dir DIR] [--baseline OLD_TETPACK]

Makes the meshes once (gmsh 4.1 binary from ../shared/data/gmsh/*.geo, ASCII and VTU from those; cached
in DIR, default /tmp/tpk_bench_import), then runs every measurement of a round before the next round
starts (A B C A B C ...), so that the load of a shared machine falls on all of them alike, and prints
medians as a markdown table. Needs Debian's python3 with python3-meshio and python3-paraview (VTK).
Import alone: bench_read (bench/bench_read.c: the registry's importer, as convert runs it) against
meshio.read(), each in a fresh process, timed inside it (start-up left out), wall and CPU seconds (the CPU
time of all threads is the steadier measure when the machine is loaded). Whole conversions are process
wall times with the stages of `tetpack convert --json`; peak memory is /usr/bin/time's maximum resident
set size. With --baseline, another tetpack binary (a build of an older
commit) is run in the same rounds and its medians are printed beside ours.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GEO = os.path.join(ROOT, "..", "shared", "data", "gmsh")
PY = "/usr/bin/python3"

MESHIO_READ = """
import sys, time, meshio
t, c = time.perf_counter(), time.process_time(); meshio.read(sys.argv[1])
print(time.perf_counter() - t, time.process_time() - c)
"""
TO_VTU = """
import sys, meshio
m = meshio.read(sys.argv[1])
keep = [i for i, c in enumerate(m.cells) if c.type in ("tetra", "hexahedron", "wedge", "pyramid")]
meshio.write(sys.argv[2], meshio.Mesh(m.points, [m.cells[i] for i in keep]), binary=True, compression="zlib")
"""
VTK_PIPELINE = """
import sys
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
from vtkmodules.vtkFiltersGeneral import vtkDataSetTriangleFilter
from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter
r = vtkXMLUnstructuredGridReader(); r.SetFileName(sys.argv[1])
t = vtkDataSetTriangleFilter(); t.SetInputConnection(r.GetOutputPort())
s = vtkDataSetSurfaceFilter(); s.SetInputConnection(t.GetOutputPort()); s.Update()
print(t.GetOutput().GetNumberOfCells(), s.GetOutput().GetNumberOfCells())
"""


def make_meshes(d):
    """The issue's meshes: t5.geo at -clscale 0.215 (1.05M tets), hexrecomb.geo (971k hexahedra)."""
    os.makedirs(d, exist_ok=True)
    made = {"tets.msh": ["t5.geo", "-clscale", "0.215"], "hex.msh": ["hexrecomb.geo"]}
    for name, args in made.items():
        path = os.path.join(d, name)
        if not os.path.exists(path):
            print(f"making {path} with gmsh", file=sys.stderr)
            # gmsh 4.8 exits 1 on hexrecomb.geo (errors about extruded curves it reports and meshes past):
            # a written file is what counts.
            subprocess.run(["gmsh", os.path.join(GEO, args[0]), "-3", *args[1:], "-nt", "1", "-format", "msh41",
                            "-bin", "-o", path + ".part"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            if not os.path.exists(path + ".part"):
                sys.exit(f"gmsh wrote no {path}.part")
            os.replace(path + ".part", path)
    ascii_path = os.path.join(d, "tets_ascii.msh")
    if not os.path.exists(ascii_path):
        subprocess.run(["gmsh", os.path.join(d, "tets.msh"), "-save", "-format", "msh41", "-o",
                        ascii_path + ".msh"], check=True, stdout=subprocess.DEVNULL)
        os.replace(ascii_path + ".msh", ascii_path)
    for name in ("tets", "hex"):
        vtu = os.path.join(d, name + ".vtu")
        if not os.path.exists(vtu):
            subprocess.run([PY, "-c", TO_VTU, os.path.join(d, name + ".msh"), vtu + ".vtu"], check=True)
            os.replace(vtu + ".vtu", vtu)


def timed(cmd):
    """(wall seconds, peak RSS KiB, stdout) of one process."""
    with tempfile.NamedTemporaryFile("r") as rss:
        t = time.perf_counter()
        out = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", rss.name, *cmd], check=True,
                             stdout=subprocess.PIPE, text=True).stdout
        wall = time.perf_counter() - t
        return wall, int(rss.read().split()[-1]), out


def tetpack(exe, src, out):
    wall, rss, text = timed([exe, "convert", src, out, "--json", "--no-progress"])
    d = json.loads(text)
    return {"wall": wall, "rss": rss, "tets": d["tets"], **{k: v for k, v in d["seconds"].items()}}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("tetpack", nargs="?", default=os.path.join(ROOT, "build", "tetpack"))
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--read-runs", type=int, default=11)
    ap.add_argument("--bench-read", default=None, help="bench_read binary (default: next to TETPACK in bench/)")
    ap.add_argument("--vtk-runs", type=int, default=3)
    ap.add_argument("--dir", default="/tmp/tpk_bench_import")
    ap.add_argument("--baseline", help="an older tetpack binary, run in the same rounds")
    a = ap.parse_args()
    make_meshes(a.dir)
    files = ["tets.msh", "hex.msh", "tets.vtu", "hex.vtu", "tets_ascii.msh"]
    ours = {f: [] for f in files}
    base = {f: [] for f in files}
    vtk = []
    out = os.path.join(a.dir, "out.tpk")
    bench_read = a.bench_read or os.path.join(os.path.dirname(os.path.abspath(a.tetpack)), "bench", "bench_read")
    reads = {f: [] for f in files}   # (wall, cpu) of bench_read
    mreads = {f: [] for f in files}  # (wall, cpu) of meshio.read
    for r in range(a.read_runs):
        for f in files:
            path = os.path.join(a.dir, f)
            d = json.loads(subprocess.run([bench_read, path], check=True, stdout=subprocess.PIPE, text=True).stdout)
            reads[f].append((d["seconds"], d["cpu_seconds"]))
            w, c = subprocess.run([PY, "-c", MESHIO_READ, path], check=True, stdout=subprocess.PIPE,
                                  text=True).stdout.split()
            mreads[f].append((float(w), float(c)))
        print(f"read round {r + 1}/{a.read_runs} done", file=sys.stderr)
    for r in range(a.runs):
        for f in files:
            path = os.path.join(a.dir, f)
            ours[f].append(tetpack(a.tetpack, path, out))
            if a.baseline:
                base[f].append(tetpack(a.baseline, path, out))
        if r < a.vtk_runs:
            wall, rss, _ = timed([PY, "-c", VTK_PIPELINE, os.path.join(a.dir, "hex.vtu")])
            vtk.append((wall, rss))
        print(f"round {r + 1}/{a.runs} done", file=sys.stderr)

    med = statistics.median
    print(f"Medians of {a.read_runs} interleaved reads, {a.runs} conversions, {a.vtk_runs} VTK runs;"
          f" {time.strftime('%Y-%m-%d %H:%M')}, load average {os.getloadavg()[0]:.1f} at the end\n")
    print("| file | size | our import (wall / CPU) | meshio read (wall / CPU) | meshio / ours, wall | CPU | target |")
    print("|---|---|---|---|---|---|---|")
    for f in files:
        mb = os.path.getsize(os.path.join(a.dir, f)) / 1e6
        ow, oc = med(x[0] for x in reads[f]), med(x[1] for x in reads[f])
        mw, mc = med(x[0] for x in mreads[f]), med(x[1] for x in mreads[f])
        pair = med(m[0] / o[0] for m, o in zip(mreads[f], reads[f]))
        target = 1.5 if "ascii" in f else 3.0
        ok = "met" if mw / ow >= target else "NOT met"
        print(f"| {f} | {mb:.0f} MB | {ow:.3f} / {oc:.3f} s | {mw:.3f} / {mc:.3f} s | {mw / ow:.2f}x (pairs {pair:.2f}x)"
              f" | {mc / oc:.2f}x | {target}x: {ok} |")
    print("\n| conversion | tets | import | tetrahedralize | orient | reorder | connect | write | total (json)"
          " | process wall | peak RSS |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for f in files:
        runs = ours[f]
        stages = " | ".join(f"{med(x[k] for x in runs):.3f}" for k in
                            ("import", "tetrahedralize", "orient", "reorder", "connect", "write", "total"))
        print(f"| {f} | {runs[0]['tets']:,} | {stages} | {med(x['wall'] for x in runs):.3f} s"
              f" | {med(x['rss'] for x in runs) / 1024:.0f} MiB |")
    if a.baseline:
        print(f"\nBaseline {a.baseline}, same rounds:\n")
        print("| file | import: baseline | ours | total: baseline | ours | peak RSS: baseline | ours |")
        print("|---|---|---|---|---|---|---|")
        for f in files:
            b, o = base[f], ours[f]
            print(f"| {f} | {med(x['import'] for x in b):.3f} s | {med(x['import'] for x in o):.3f} s"
                  f" | {med(x['wall'] for x in b):.3f} s | {med(x['wall'] for x in o):.3f} s"
                  f" | {med(x['rss'] for x in b) / 1024:.0f} MiB | {med(x['rss'] for x in o) / 1024:.0f} MiB |")
        bt = med(x["tetrahedralize"] for x in base["hex.vtu"])
        print(f"\nbaseline tetrahedralize, hex.vtu: {base['hex.vtu'][0]['tets'] / bt / 1e6:.1f} M output tets/s")
    hexes = ours["hex.vtu"]
    tetra = med(x["tetrahedralize"] for x in hexes)
    print(f"\ntetrahedralize, hex.vtu: {hexes[0]['tets'] / tetra / 1e6:.1f} M output tets/s (target 30)")
    vw = med(w for w, _ in vtk)
    ow = med(x["wall"] for x in hexes)
    print(f"hex.vtu whole conversion {ow:.3f} s, VTK pipeline {vw:.3f} s (peak {med(r for _, r in vtk) / 1024:.0f}"
          f" MiB): {vw / ow:.2f}x (target 4x)")
    mw = med(x["wall"] for x in ours["hex.msh"])
    print(f"hex.msh whole conversion {mw:.3f} s (target < 0.8 s), peak"
          f" {med(x['rss'] for x in ours['hex.msh']) / 1024:.0f} MiB (target <= 308 MiB)")


if __name__ == "__main__":
    main()
