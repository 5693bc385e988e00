#!/usr/bin/python3
"""OpenFOAM's tutorials as their users have them: each case meshed by its own blockMesh (and, where it has
the dictionaries, surfaceFeatureExtract and snappyHexMesh -overwrite), 0.orig copied to 0 as Allrun's
restore0Dir does, then checkMesh (the oracle for the source), `tetpack check` on the case, `tetpack convert`
with every field the case's latest time directory holds, and `tetpack check` on the file.

    tests/openfoam/tutorials.py TETPACK WORKDIR [--budget S] [--table FILE.md] [--json FILE] [TUTORIAL...]

TUTORIAL: a path under the examples folder (incompressible/simpleFoam/pitzDaily), or none for every one
that has system/blockMeshDict. A case whose meshing takes longer than the budget (default 60 s) is
listed as slow and not converted. The verdict per case:
  ok        checkMesh says "Mesh OK", check finds no 3xx/4xx error in the case nor any error in the file,
            the region counts agree and every field the case holds is kept;
  mesh-fail the tutorial does not mesh with these steps alone (it needs m4, topoSet, a mapped case...);
  not-ok    checkMesh fails: its findings are the source's, reported but not held against tetpack;
  overset   an overset case (patches of type overset): its meshes overlap by design, and check says so on
            the case and on the file (406);
  interface an AMI or ACMI case (cyclicAMI/cyclicACMI patches in its boundary or dictionaries): its meshes
            meet on non-matching faces by design (303, 406 on those);
  defect    check finds the boundary crossing itself (406) in the case and the file, and OpenFOAM's own
            surfaceCheck -checkSelfIntersection confirms it on the extracted boundary: a real defect that
            checkMesh does not test;
  FAIL      anything else (exit status 1).
Needs Debian's openfoam and openfoam-examples. Prints a Markdown table; exits 1 on any FAIL."""
import json
import os
import re
import shutil
import subprocess
import sys
import time

EXAMPLES = os.environ.get("EXAMPLES", "/usr/share/doc/openfoam-examples/examples")
FIELD_CLASSES = {"volScalarField": "", "volVectorField": ":mag", "pointScalarField": ""}


def run(cmd, cwd, log, timeout):
    with open(os.path.join(cwd, log), "w") as out:
        try:
            return subprocess.run(cmd, cwd=cwd, stdout=out, stderr=subprocess.STDOUT, timeout=timeout).returncode
        except subprocess.TimeoutExpired:
            return None


def copy_case(tutorial, work):
    dst = os.path.join(work, tutorial.replace("/", "__"))
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(os.path.join(EXAMPLES, tutorial), dst, symlinks=True)
    for root, _, files in os.walk(dst):
        for f in files:
            if f.endswith(".gz"):
                subprocess.run(["gunzip", "-f", os.path.join(root, f)], check=False)
    return dst


def mesh(case, budget):
    """blockMesh, then surfaceFeatureExtract and snappyHexMesh where the case has their dictionaries; 0.orig
    to 0. Returns (seconds, None) or (seconds, why)."""
    start = time.monotonic()
    steps = [["blockMesh"]]
    if os.path.exists(os.path.join(case, "system/snappyHexMeshDict")):
        if os.path.exists(os.path.join(case, "system/surfaceFeatureExtractDict")):
            steps.append(["surfaceFeatureExtract"])
        steps.append(["snappyHexMesh", "-overwrite"])
    for step in steps:
        left = budget - (time.monotonic() - start)
        rc = run(step, case, "log." + step[0], max(left, 1))
        if rc is None:
            return time.monotonic() - start, "slow"
        if rc != 0:
            return time.monotonic() - start, "%s failed" % step[0]
    if not os.path.isdir(os.path.join(case, "0")) and os.path.isdir(os.path.join(case, "0.orig")):
        shutil.copytree(os.path.join(case, "0.orig"), os.path.join(case, "0"))
    return time.monotonic() - start, None


def check_mesh(case):
    run(["checkMesh", "-constant"], case, "log.checkMesh", 600)
    text = open(os.path.join(case, "log.checkMesh"), errors="replace").read()
    cells = re.search(r"^\s*cells:\s+(\d+)", text, re.M)
    regions = re.search(r"Number of regions:\s+(\d+)", text)
    return ("Mesh OK" in text, int(cells.group(1)) if cells else 0, int(regions.group(1)) if regions else 0)


def latest_time(case):
    times = []
    for d in os.listdir(case):
        try:
            times.append((float(d), d))
        except ValueError:
            pass
    return max(times)[1] if times else None


def case_fields(case):
    """The fields tetpack reads from the latest time directory: name -> --field argument."""
    t = latest_time(case)
    if t is None:
        return {}
    fields = {}
    folder = os.path.join(case, t)
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name)
        if os.path.isdir(path):
            continue
        head = open(path, "rb").read(4096).decode("latin-1")
        m = re.search(r"\bclass\s+(\w+)\s*;", head)
        if m and m.group(1) in FIELD_CLASSES:
            base = name[:-3] if name.endswith(".gz") else name
            fields[base] = base + FIELD_CLASSES[m.group(1)]
    return fields


def surface_self_intersections(case):
    """OpenFOAM's surfaceMeshExtract + surfaceCheck -checkSelfIntersection on the case's boundary: the number
    of locations where it crosses itself, 0 when none or when the tools fail."""
    if run(["surfaceMeshExtract", "-constant", "boundary.obj"], case, "log.surfaceMeshExtract", 600) != 0:
        return 0
    obj = [f for f in os.listdir(case) if f.startswith("boundary") and f.endswith(".obj")]
    if not obj:
        return 0
    run(["surfaceCheck", "-checkSelfIntersection", sorted(obj)[0]], case, "log.surfaceCheck", 600)
    m = re.search(r"self-intersecting at (\d+) locations", open(os.path.join(case, "log.surfaceCheck"),
                                                              errors="replace").read())
    return int(m.group(1)) if m else 0


def tetpack_json(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        return p.returncode, json.loads(p.stdout), p.stderr
    except ValueError:
        return p.returncode, None, p.stderr


def errors(report, lo, hi):
    return ["%d %s x%d" % (f["id"], f["name"], f["count"]) for f in report["findings"]
            if lo <= f["id"] < hi and f["severity"] == "error" and f["count"]]


def one_case(tpk, tutorial, work, budget):
    row = {"tutorial": tutorial}
    case = copy_case(tutorial, work)
    row["mesh_seconds"], why = mesh(case, budget)
    if why:
        row["verdict"] = "slow" if why == "slow" else "mesh-fail"
        row["why"] = why
        return row
    mesh_ok, row["cells"], row["regions"] = check_mesh(case)
    row["checkmesh"] = "Mesh OK" if mesh_ok else "failed"
    rc, src, check_err = tetpack_json([tpk, "check", case, "--json", "--no-progress"])
    if src is None:
        row.update(verdict="FAIL", why="check on the case: " + check_err.strip()[-300:])
        return row
    row["check_case"] = errors(src, 300, 500)
    row["components"] = src["components"]["count"]
    fields = case_fields(case)
    read = {f["name"] for f in src.get("fields", [])}
    row["fields"] = "%d/%d" % (len(read & set(fields)), len(fields))
    out = os.path.join(case, "case.tpk")
    args = [tpk, "convert", case, out, "--json"]
    for name in sorted(read & set(fields)):
        args += ["--field", fields[name]]
    start = time.monotonic()
    rc, conv, err = tetpack_json(args)
    row["convert_seconds"] = time.monotonic() - start
    if rc != 0 or conv is None:
        row.update(verdict="FAIL", why="convert: " + err.strip()[-300:])
        return row
    row["tets"] = conv["tets"]
    row["fields_kept"] = conv["fields"]
    row["flat_tets"] = conv.get("flat_tets", 0)
    rc, tpk_report, err = tetpack_json([tpk, "check", out, "--json", "--no-progress"])
    if tpk_report is None:
        row.update(verdict="FAIL", why="check on the file: " + err.strip()[-300:])
        return row
    row["check_file"] = errors(tpk_report, 0, 1000)
    problems = []
    if mesh_ok and row["check_case"]:
        problems.append("check on the case: " + ", ".join(row["check_case"]))
    if mesh_ok and row["components"] != row["regions"]:
        problems.append("%d components, checkMesh %d regions" % (row["components"], row["regions"]))
    # A mesh checkMesh fails may keep its own defects in the file; an error the case does not have is
    # the converter's, whatever checkMesh says.
    ids = lambda found: {e.split()[0] for e in found}
    new_in_file = row["check_file"] if mesh_ok else \
        [e for e in row["check_file"] if e.split()[0] not in ids(errors(src, 0, 1000))]
    if new_in_file:
        problems.append("check on the file: " + ", ".join(new_in_file))
    if len(read & set(fields)) != len(fields) or conv["fields"] != len(fields):
        problems.append("fields: %d of %d read, %d kept; %s" % (len(read & set(fields)), len(fields), conv["fields"],
                                                                 check_err.strip().replace("\n", " ")[-300:]))
    boundary = open(os.path.join(case, "constant/polyMesh/boundary"), errors="replace").read()
    overset = "overset" in boundary
    dicts = boundary + "".join(open(os.path.join(case, "system", f), errors="replace").read()
                               for f in os.listdir(os.path.join(case, "system"))
                               if os.path.isfile(os.path.join(case, "system", f)))
    if problems and re.search(r"cyclicA?AMI|cyclicACMI", dicts) and \
            all(p.startswith("check on the") for p in problems):
        # An AMI or ACMI interface: two meshes meet on faces that do not match by design (OpenFOAM
        # interpolates across them); the 303/406 of those faces are the source's, in the case and the file.
        row["verdict"], row["why"] = "interface", "; ".join(problems)
        return row
    only_406 = problems and all(p.startswith("check on the") for p in problems) and \
        {e.split()[0] for e in row["check_case"] + row["check_file"]} == {"406"} and row["check_case"]
    if only_406 and not overset:
        found = surface_self_intersections(case)
        if found:
            # A second oracle, OpenFOAM's own: its boundary, triangulated, crosses itself too.
            row["verdict"] = "defect"
            row["why"] = "boundary crosses itself (OpenFOAM's surfaceCheck: %d locations; checkMesh does not " \
                "test it); %s" % (found, "; ".join(problems))
            return row
    if problems and overset and not [p for p in problems if not p.startswith("check on the")]:
        # Overset meshes overlap by design (their solver interpolates between them): the overlaps are the
        # source's, found in the case and kept in the file, not a disagreement.
        row["verdict"], row["why"] = "overset", "; ".join(problems)
        return row
    row["verdict"] = "FAIL" if problems else "ok" if mesh_ok else "not-ok"
    if problems:
        row["why"] = "; ".join(problems)
    return row


def table(rows):
    lines = ["| tutorial | cells | checkMesh | check on the case | check on the file | fields kept | tets | "
             "convert s | verdict |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "cells" not in r:
            lines.append("| %s | | | | | | | | %s (%s, %.0f s) |" % (r["tutorial"], r["verdict"], r.get("why", ""),
                                                                     r["mesh_seconds"]))
            continue
        lines.append("| %s | %d | %s | %s | %s | %s | %s | %s | %s%s |" % (
            r["tutorial"], r["cells"], r["checkmesh"], ", ".join(r.get("check_case", [])) or "clean",
            ", ".join(r.get("check_file", [])) or ("clean" if "check_file" in r else ""),
            r.get("fields", ""), r.get("tets", ""), "%.2f" % r["convert_seconds"] if "convert_seconds" in r else "",
            r["verdict"], ": " + r["why"] if r.get("why") and r["verdict"] == "FAIL" else ""))
    return "\n".join(lines)


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    tpk, work = os.path.abspath(argv[1]), argv[2]
    budget, table_file, json_file, tutorials = 60.0, None, None, []
    i = 3
    while i < len(argv):
        if argv[i] in ("--budget", "--table", "--json") and i + 1 < len(argv):
            if argv[i] == "--budget":
                budget = float(argv[i + 1])
            elif argv[i] == "--table":
                table_file = argv[i + 1]
            else:
                json_file = argv[i + 1]
            i += 2
        else:
            tutorials.append(argv[i].strip("/"))
            i += 1
    os.environ.setdefault("WM_PROJECT_DIR", "/usr/share/openfoam")
    if shutil.which("blockMesh") is None or not os.path.isdir(EXAMPLES):
        print("tutorials.py: needs Debian's openfoam and openfoam-examples", file=sys.stderr)
        return 77
    if not tutorials:
        for root, dirs, files in os.walk(EXAMPLES):
            if root.endswith("/system") and "blockMeshDict" in files:
                tutorials.append(os.path.relpath(os.path.dirname(root), EXAMPLES))
        tutorials.sort()
    os.makedirs(work, exist_ok=True)
    rows = []
    for t in tutorials:
        row = one_case(tpk, t, work, budget)
        rows.append(row)
        print("%-70s %s%s" % (t, row["verdict"], " (" + row["why"] + ")" if row.get("why") else ""), flush=True)
        shutil.rmtree(os.path.join(work, t.replace("/", "__")), ignore_errors=True)
    text = table(rows)
    if table_file:
        open(table_file, "w").write(text + "\n")
    if json_file:
        json.dump(rows, open(json_file, "w"), indent=1)
    counts = {}
    for r in rows:
        counts[r["verdict"]] = counts.get(r["verdict"], 0) + 1
    print(", ".join("%d %s" % (n, v) for v, n in sorted(counts.items())))
    return 1 if counts.get("FAIL") else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
