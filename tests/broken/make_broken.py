#!/usr/bin/python3
"""Generate the corpus of broken meshes for `tetpack check` and the expected findings.

Each module broken_<group>.py next to this file defines `cases()`, a list of dicts:
    {"name": "inverted_hex",            # file stem, unique over the corpus
     "text": "...",                     # file content (str: written as text; bytes: as is)
     "ext": ".vtk",                     # file extension
     "expect": {"inverted_cell": 1},    # check name -> exact count (or ">0")
     "absent": ["zero_volume_cell"],    # check names that must NOT be reported (near misses)
     "exit": 1}                         # expected exit status of `tetpack check` (0, 1 or 2)
Usage: make_broken.py OUTDIR  -> writes OUTDIR/<name><ext> and OUTDIR/expected.json
"""
import glob
import importlib.util
import json
import os
import sys


def load_cases():
    here = os.path.dirname(os.path.abspath(__file__))
    cases = []
    for path in sorted(glob.glob(os.path.join(here, "broken_*.py"))):
        spec = importlib.util.spec_from_file_location(os.path.basename(path)[:-3], path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        for case in module.cases():
            case.setdefault("absent", [])
            case.setdefault("exit", 1 if case.get("expect") else 0)
            case["module"] = os.path.basename(path)
            cases.append(case)
    names = [c["name"] for c in cases]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        sys.exit("make_broken.py: duplicate case names: %s" % ", ".join(sorted(dup)))
    return cases


def vtk_legacy(points, cells, title="tetpack check corpus", point_data=None, cell_data=None):
    """VTK legacy ASCII UNSTRUCTURED_GRID text. cells: list of (vtk_type, [ids...]).
    point_data/cell_data: dict name -> list of floats (scalars)."""
    out = ["# vtk DataFile Version 3.0", title, "ASCII", "DATASET UNSTRUCTURED_GRID",
           "POINTS %d double" % len(points)]
    out += ["%r %r %r" % tuple(float(c) for c in p) for p in points]
    size = sum(1 + len(ids) for _, ids in cells)
    out.append("CELLS %d %d" % (len(cells), size))
    out += [" ".join(str(v) for v in [len(ids)] + list(ids)) for _, ids in cells]
    out.append("CELL_TYPES %d" % len(cells))
    out += [str(t) for t, _ in cells]
    for section, data, n in (("POINT_DATA", point_data, len(points)), ("CELL_DATA", cell_data, len(cells))):
        if data:
            out.append("%s %d" % (section, n))
            for name, values in data.items():
                out.append("SCALARS %s double 1" % name)
                out.append("LOOKUP_TABLE default")
                out += [repr(float(v)) for v in values]
    return "\n".join(out) + "\n"


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: make_broken.py OUTDIR")
    outdir = sys.argv[1]
    os.makedirs(outdir, exist_ok=True)
    expected = []
    for case in load_cases():
        path = os.path.join(outdir, case["name"] + case.get("ext", ".vtk"))
        data = case["text"]
        with open(path, "wb") as f:
            f.write(data if isinstance(data, bytes) else data.encode())
        expected.append({k: case[k] for k in ("name", "expect", "absent", "exit", "module")} |
                        {"file": os.path.basename(path), "args": case.get("args", [])})
    with open(os.path.join(outdir, "expected.json"), "w") as f:
        json.dump(expected, f, indent=1)
    print("make_broken.py: %d cases in %s" % (len(expected), outdir))


if __name__ == "__main__":
    main()
