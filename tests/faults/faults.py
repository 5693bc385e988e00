#!/usr/bin/python3
"""The fault suite (ctest label `faults`): feeds the built `tetpack` damaged inputs and hostile output
conditions, every run under a timeout, and asserts what the fault-injection run asked for: no crash (no
signal, no sanitizer report), no hang, no lost or half-written output (the old bytes or a complete valid
file, and no temporary file left beside it), and exit 2 with a message naming the file for every refusal.

usage: faults.py TETPACK DATA_DIR SOURCE_DIR CATEGORY    (CATEGORY: import, tpk or output)
Fixed seeds; TPK_FAULTS_SEEDS=N (default 1) multiplies the random cases for a longer run (./dev faults);
TPK_FAULTS_TIMEOUT (default 60) is the seconds one run of tetpack may take before it counts as a hang;
TPK_FAULTS_VERBOSE=1 lists the accepted cases.
Exit 0 when every case holds, 1 when one does not, 77 (ctest's skip) when a case could not run here
(for example the full filesystem needs root), unless TETPACK_REQUIRE_ALL=1 makes a skip a failure."""
import json
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mutations  # noqa: E402
import tpk_mutations  # noqa: E402

TIMEOUT_S = float(os.environ.get("TPK_FAULTS_TIMEOUT", "60"))
SEEDS = int(os.environ.get("TPK_FAULTS_SEEDS", "1"))
SANITIZER_MARKS = ("Sanitizer", "runtime error:")


class Tally:
    """Counts per category, and every failure with the end of its message."""

    def __init__(self):
        self.counts = {}
        self.failures = []
        self.skips = []
        self.lock = threading.Lock()  # cases run on worker threads
        self.expected = set()
        self.real_failures = 0

    def add(self, category, what, n=1):
        with self.lock:
            row = self.counts.setdefault(category, dict.fromkeys(
                ("cases", "refused", "accepted", "crashes", "hangs", "lost", "other", "tetgen"), 0))
            row[what] += n

    def fail(self, category, what, case, detail):
        self.add(category, what)
        line = "%s/%s: %s: %s" % (category, case, what, detail.strip()[-600:])
        expected = [x for x in EXPECTED_FAILURES if re.match(x[0], "%s/%s" % (category, case))]
        with self.lock:
            if expected:
                self.expected.add(expected[0])
                self.failures.append("XFAIL (%s): %s" % (expected[0][1], line))
            else:
                self.failures.append("FAIL: " + line)
                self.real_failures += 1

    def report(self, category):
        """One row per category: cases run; refused (exit 2 naming the file); accepted (exit 0, or 1 for
        check, with a valid output); crashes; hangs; lost (an output changed by a refusal, half-written, or
        files left beside it); other (a wrong exit code or message, or a file the spec says to refuse that
        was accepted: such a case counts as accepted too); tetgen (TetGen crashes contained in its child
        process and refused by name, counted among the refused too)."""
        names = ("cases", "refused", "accepted", "crashes", "hangs", "lost", "other", "tetgen")
        print("%-16s" % "category" + "".join("%9s" % n[:8] for n in names))
        for category, row in sorted(self.counts.items()):
            print("%-16s" % category + "".join("%9d" % row[n] for n in names))
        for s in self.skips:
            print("SKIPPED: " + s)
        for f in self.failures:
            print(f)
        for pattern, why in EXPECTED_FAILURES:
            if pattern.startswith(category) and (pattern, why) not in self.expected:
                print("XPASS: %s no longer fails (%s): remove it from EXPECTED_FAILURES" % (pattern, why))


# Cases that fail because their fix lives on a branch not merged yet: (regex on "category/case", why).
# They are reported as XFAIL and do not fail the run; one that passes is reported as XPASS.
EXPECTED_FAILURES = []
TALLY = Tally()


def run(cmd, cwd=None):
    """(exit code, stderr, hung): a negative code is the signal that ended it."""
    p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         start_new_session=True)
    try:
        _, err = p.communicate(timeout=TIMEOUT_S)
        return p.returncode, err.decode("utf-8", "replace"), False
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        _, err = p.communicate()
        return p.returncode, err.decode("utf-8", "replace"), True


def judge(category, case, result, names, allowed=(0, 2)):
    """Count one run: refused (2, naming one of `names`), accepted (0, or 1 where allowed), or a failure.
    Returns the exit code, or None for a run that crashed or hung."""
    rc, err, hung = result
    TALLY.add(category, "cases")
    # TetGen runs in a child process so that its crashes cannot take tetpack down (mesher/tetgen_child.c):
    # a crash there, sanitizer report included, that tetpack turned into a refusal is contained. It is
    # counted apart, as a third-party crash, not as a crash of tetpack.
    contained = rc == 2 and "TetGen crashed" in err
    if contained:
        TALLY.add(category, "tetgen")
    if hung:
        TALLY.fail(category, "hangs", case, "no exit after %gs" % TIMEOUT_S)
    elif rc < 0 or (not contained and any(m in err for m in SANITIZER_MARKS)):
        TALLY.fail(category, "crashes", case, "exit %d: %s" % (rc, err))
    elif rc == 2 and any(os.path.basename(n) in err for n in names):
        TALLY.add(category, "refused")
        return rc
    elif rc in allowed and rc != 2:
        TALLY.add(category, "accepted")
        if os.environ.get("TPK_FAULTS_VERBOSE"):
            print("accepted: %s/%s" % (category, case))
        return rc
    else:
        TALLY.fail(category, "other", case, "exit %d, wanted one of %s (exit 2 naming %s): %s" %
                   (rc, allowed, [os.path.basename(n) for n in names], err))
    return None


def tpk_is_valid(tetpack, path):
    """A complete valid .tpk: info opens it and verifies every chunk, and check finds no error among the
    format's MUSTs and mesh invariants (ids 6xx)."""
    if run([tetpack, "info", path])[0] != 0:
        return False
    p = subprocess.run([tetpack, "check", path, "--json", "--no-self-intersections", "--threads", "1"],
                       capture_output=True, timeout=TIMEOUT_S)
    if p.returncode not in (0, 1):
        return False
    findings = json.loads(p.stdout)["findings"]
    return not any(600 <= f["id"] < 700 and f["severity"] == "error" and f["count"] > 0 for f in findings)


def check_output(category, case, tetpack, out, old, rc, keep):
    """The output is the old bytes or (after exit 0) a complete valid file; nothing else lies in its
    directory but `keep`. A refusal must leave the old bytes (or nothing, where there were none)."""
    folder = os.path.dirname(out)
    stray = sorted(set(os.listdir(folder)) - set(keep) - {os.path.basename(out)})
    if stray:
        TALLY.fail(category, "lost", case, "files left beside the output: %s" % stray)
        return
    now = open(out, "rb").read() if os.path.lexists(out) else None
    if now == old:
        return
    if rc != 0:
        TALLY.fail(category, "lost", case, "exit %s, yet %s changed" % (rc, os.path.basename(out)))
    elif now is None or (out.endswith(".tpk") and not tpk_is_valid(tetpack, out)):
        TALLY.fail(category, "lost", case, "exit 0, yet %s is missing or not a valid file" % out)


# ---- importers: every format's inputs, damaged ------------------------------------------------------

# Real files per format from ../shared/data, small ones (every case converts one); the formats it has no
# file of are generated by mutations.py.
REAL_INPUTS = {
    "vtk": ["sfepy/cylinder.vtk", "gmsh/t5_small_tet_bin.vtk"],
    "vtu": ["hard/huge_offset_hex.vtu", "hard/nonmanifold_vertex_edge_tets.vtu"],
    "gmsh": ["gmsh/t5_small_tet_ascii22.msh", "gmsh/t3_hex_prism_ascii41.msh"],
    "medit": ["sfepy/cube_medium_hexa.mesh", "sfepy/cross3d.mesh"],
    "meshb": ["nasa_refine/om6_om6-curv-no-geom.meshb"],
    "ugrid": ["nasa_refine/cube_polar1.ugrid"],
    "exodus": ["seacas/cube.g", "seacas/8-block.g"],
    "cgns": ["seacas/generated.cgns"],
    "tetgen": ["tetgen/part1_small.node"],
}


def importer_sources(tetpack, data, source_dir, folder):
    """[(format, [files: the first is what convert is given; any of them may be the one damaged], options)]:
    every format `tetpack formats` lists, from real files where ../shared/data has them."""
    sources = []
    for fmt, paths in REAL_INPUTS.items():
        for p in paths:
            files = [os.path.join(data, p)]
            if fmt == "tetgen":
                files.append(files[0][:-len(".node")] + ".ele")
            sources.append((fmt, files, []))
    sources.append(("ugrid", [mutations.write_binary_ugrid(os.path.join(data, REAL_INPUTS["ugrid"][0]), folder)], []))
    sources.append(("pvd", mutations.write_pvd(tetpack, data, folder), []))
    if any(f["name"] == "vtkhdf" for f in json.loads(subprocess.run(
            [tetpack, "formats", "--json"], check=True, capture_output=True).stdout)["formats"]):
        sources.append(("vtkhdf", [mutations.write_vtkhdf(tetpack, data, folder)], []))
    surfaces = mutations.write_surfaces(folder)
    for fmt, paths in surfaces.items():
        sources += [(fmt, [p], []) for p in paths]
    made = mutations.write_meshio_files(os.path.join(source_dir, "samples/cylinder.vtk"), folder)
    if made is None:
        TALLY.skips.append("import: python3 without meshio: no binary Gmsh, zlib VTU, inp, XDMF or DOLFIN cases")
    for fmt, paths in (made or {}).items():
        sources += [(fmt, [p], []) for p in paths]
    # An OpenFOAM case is a directory: convert is given its CASE.foam; each mesh and field file is damaged.
    case = os.path.join(source_dir, "tests/data/openfoam/cases/cavity_binary")
    sources.append(("openfoam", [os.path.join(case, "cavity.foam")] +
                    [os.path.join(case, "constant/polyMesh", n) for n in ("points", "faces", "owner", "neighbour")] +
                    [os.path.join(case, "0.5", n) for n in ("p", "pp")], []))
    sources.append(("surface", [surfaces["stl"][1]], ["--format", "surface"]))
    sources.append(("points", [surfaces["ply"][0]], ["--format", "points"]))
    listed = json.loads(subprocess.run([tetpack, "formats", "--json"], check=True, capture_output=True).stdout)
    for fmt in listed["formats"]:
        if fmt["name"] not in {s[0] for s in sources}:
            TALLY.fail("import:" + fmt["name"], "other", "-", "tetpack formats lists it, the fault suite has no input")
    return sources


def import_case(tetpack, work, fmt, files, options, damaged, name, payload, allowed, old):
    """Convert a copy of `files` with `damaged` (an index into it) replaced by `payload`; `allowed` is
    (2,) for an input that must be refused, else (0, 2)."""
    case = "%s/%s/%s" % (fmt, os.path.basename(files[damaged]), name)
    folder = tempfile.mkdtemp(dir=work)
    inputs = os.path.join(folder, "in")
    os.mkdir(inputs)
    for k, f in enumerate(files):
        # Kept where they lie relative to the first file (an OpenFOAM case's folders).
        target = os.path.join(inputs, os.path.relpath(f, os.path.dirname(files[0])))
        os.makedirs(os.path.dirname(target), exist_ok=True)
        if k == damaged:
            with open(target, "wb") as out:
                out.write(payload)
        else:
            shutil.copyfile(f, target)
    out_dir = os.path.join(folder, "out")
    os.mkdir(out_dir)
    out = os.path.join(out_dir, "out.tpk")
    with open(out, "wb") as f:
        f.write(old)
    first = os.path.join(inputs, os.path.basename(files[0]))
    result = run([tetpack, "convert", first, out, "--quiet"] + options)
    rc = judge("import:" + fmt, case, result, [files[damaged], files[0]], allowed)
    if rc is not None:
        check_output("import:" + fmt, case, tetpack, out, old, rc, [])
    shutil.rmtree(folder)


def run_import(tetpack, data, work, source_dir):
    sources = importer_sources(tetpack, data, source_dir, work)
    old = make_tpk(tetpack, os.path.join(data, "sfepy/cross3d.mesh"), work, "old.tpk")
    jobs = []
    for fmt, files, options in sources:
        # The untouched input converts: the cases below start from a file the converter accepts.
        ok = run([tetpack, "convert", files[0], os.path.join(work, "clean.tpk"), "--quiet"] + options)
        if ok[0] != 0 and "without TetGen" in ok[1]:
            TALLY.skips.append("import:%s: built without TetGen" % fmt)
            continue
        if ok[0] != 0:
            TALLY.fail("import:" + fmt, "other", os.path.basename(files[0]), "the clean input fails: " + ok[1])
            continue
        for seed in range(SEEDS):
            for damaged, f in enumerate(files):
                data_bytes = open(f, "rb").read()
                if not data_bytes:  # nothing to damage (ParaView's empty CASE.foam)
                    continue
                for name, payload in mutations.mutations(data_bytes, hash_seed(f, seed), seed == 0):
                    jobs.append((fmt, files, options, damaged, "%s_s%d" % (name, seed), payload, (0, 2)))
    for name, path in mutations.write_vtu_zlib_bombs(work):
        # Decompression bombs, and the same file without a bomb, which must convert: the others are then
        # refused for their bomb alone.
        payload = open(path, "rb").read()
        jobs.append(("vtu", [path], [], 0, "zlib_" + name, payload, (0,) if name == "clean" else (2,)))
    with ThreadPoolExecutor(max_workers=workers()) as pool:
        list(pool.map(lambda j: import_case(tetpack, work, *j, old), jobs))


def hash_seed(path, seed):
    """A seed fixed by the file's name and the run's seed number (not by Python's salted hash)."""
    return sum(os.path.basename(path).encode()) * 7919 + seed


def workers():
    return max(1, min(2, os.cpu_count() or 1))


def make_tpk(tetpack, source, folder, name, *options):
    path = os.path.join(folder, name)
    subprocess.run([tetpack, "convert", source, path, "--quiet", *options], check=True)
    return open(path, "rb").read()


# ---- .tpk corruption behind valid checksums -----------------------------------------------------------

# (name, argv, output suffix, allowed exit codes, reads every chunk). render reads only the layout and
# field it draws, so a damaged chunk it does not read need not stop it.
TPK_COMMANDS = (("info", lambda f, o: ["info", f], None, (0, 2), True),
                ("check", lambda f, o: ["check", f, "--no-self-intersections"], None, (0, 1, 2), True),
                ("export", lambda f, o: ["export", f, "--vtu", o + ".vtu"], ".vtu", (0, 2), True),
                ("render", lambda f, o: ["render", f, "-o", o + ".png", "--size", "24x16"], ".png", (0, 2),
                 False))


def tpk_case(tetpack, work, kind, name, payload, must_refuse):
    folder = tempfile.mkdtemp(dir=work)
    path = os.path.join(folder, "damaged.tpk")
    with open(path, "wb") as f:
        f.write(payload)
    case = "%s/%s" % (kind, name)
    for command, argv, suffix, allowed, reads_all in TPK_COMMANDS:
        out = os.path.join(folder, "out")
        rc = judge("tpk:" + command, case, run([tetpack] + argv(path, out)), [path], allowed)
        if rc is None:
            continue
        if must_refuse and reads_all and rc == 0:
            TALLY.fail("tpk:" + command, "other", case, "accepted a file the spec says to refuse")
        if suffix:
            written = os.path.exists(out + suffix)
            if written != (rc == 0):
                TALLY.fail("tpk:" + command, "lost", case, "exit %d, output %s" %
                           (rc, "written" if written else "missing"))
            if written:
                os.unlink(out + suffix)
        stray = sorted(set(os.listdir(folder)) - {"damaged.tpk"})
        if stray:
            TALLY.fail("tpk:" + command, "lost", case, "files left: %s" % stray)
    shutil.rmtree(folder)


def run_tpk(tetpack, data, work, source_dir):
    source = os.path.join(source_dir, "samples/cylinder.vtk")
    layouts = ["--layout", "tet16", "--layout", "tet20", "--layout", "tet32"]
    bases = (("plain", make_tpk(tetpack, source, work, "plain.tpk", *layouts)),
             ("zstd", make_tpk(tetpack, source, work, "zstd.tpk", "--zstd", "3", *layouts)))
    jobs = []
    for kind, original in bases:
        for command, argv, _, _, _ in TPK_COMMANDS[:1]:
            # The undamaged file passes: the cases below start from a file the reader accepts.
            if run([tetpack] + argv(os.path.join(work, kind + ".tpk"), ""))[0] != 0:
                TALLY.fail("tpk:" + command, "other", kind, "the undamaged file is refused")
        for seed in range(SEEDS):
            jobs += [(kind, name, payload, refuse)
                     for name, payload, refuse in tpk_mutations.tpk_mutations(original, 1000 * seed + len(kind))]
    with ThreadPoolExecutor(max_workers=workers()) as pool:
        list(pool.map(lambda j: tpk_case(tetpack, work, *j), jobs))


# ---- output faults: read-only and full filesystems, kills while writing, outputs that are inputs ------

def output_commands(tetpack, inputs, folder):
    """[(name, argv, output)]: every command that writes a file, writing into `folder`."""
    return [("convert", [tetpack, "convert", inputs["mesh"], os.path.join(folder, "out.tpk"), "--quiet"],
             os.path.join(folder, "out.tpk")),
            ("export_vtu", [tetpack, "export", inputs["tpk"], "--vtu", os.path.join(folder, "out.vtu")],
             os.path.join(folder, "out.vtu")),
            ("export_ply", [tetpack, "export", inputs["tpk"], "--shell", os.path.join(folder, "out.ply")],
             os.path.join(folder, "out.ply")),
            ("render", [tetpack, "render", inputs["tpk"], "-o", os.path.join(folder, "out.png"), "--size",
                        "320x240"], os.path.join(folder, "out.png"))]


def seeded_folder(work, name, old):
    folder = os.path.join(work, name)
    os.mkdir(folder)
    for out in ("out.tpk", "out.vtu", "out.ply", "out.png"):
        with open(os.path.join(folder, out), "wb") as f:
            f.write(old)
    return folder


def refused_intact(category, case, tetpack, result, out, old):
    """A write that cannot succeed: exit 2 naming the output, the old bytes kept, nothing left beside."""
    rc = judge(category, case, result, [out], allowed=(2,))
    if rc is not None:
        check_output(category, case, tetpack, out, old, rc, ["out.tpk", "out.vtu", "out.ply", "out.png"])


def can_mount(work):
    """Root with mount namespaces (a container may lack CAP_SYS_ADMIN): a tmpfs can be mounted privately."""
    if os.getuid() != 0 or shutil.which("unshare") is None:
        return False
    probe = tempfile.mkdtemp(dir=work)
    return run(["unshare", "-m", "--propagation", "private", "sh", "-c", 'mount -t tmpfs -o size=64k tpkprobe "$0"',
                probe])[0] == 0


def read_only_faults(tetpack, inputs, work, old):
    folder = seeded_folder(work, "read_only", old)
    if os.getuid() == 0:
        # root writes through file modes: a read-only bind mount in a private mount namespace.
        if not can_mount(work):
            TALLY.skips.append("output:read_only: root without mount namespaces cannot make a folder read-only")
            return
        for name, argv, out in output_commands(tetpack, inputs, folder):
            script = 'mount --bind "$0" "$0" && mount -o remount,bind,ro "$0" && exec "$@"'
            result = run(["unshare", "-m", "--propagation", "private", "sh", "-c", script, folder] + argv)
            refused_intact("output:read_only", name, tetpack, result, out, old)
        return
    os.chmod(folder, 0o555)
    try:
        for name, argv, out in output_commands(tetpack, inputs, folder):
            refused_intact("output:read_only", name, tetpack, run(argv), out, old)
    finally:
        os.chmod(folder, 0o755)


def full_fs_faults(tetpack, inputs, work, old):
    """A 64 KiB tmpfs holding the old outputs, then filled up (root only, in a private mount namespace;
    its files are copied out for the checks before it goes away)."""
    if not can_mount(work):
        TALLY.skips.append("output:full_fs: mounting a small tmpfs needs root, unshare and mount namespaces")
        return
    mount_point = os.path.join(work, "full")
    os.mkdir(mount_point)
    for name, argv, out in output_commands(tetpack, inputs, mount_point):
        snapshot = seeded_folder(work, "full_" + name, old)
        script = ('m=$1; shift; mount -t tmpfs -o size=64k tpkfull "$m" && cp "$0"/* "$m"/ && '
                  '{ cat /dev/zero > "$m"/filler 2>/dev/null; "$@"; }; rc=$?; rm -f "$0"/*; cp -a "$m"/. "$0"/; '
                  'exit $rc')
        result = run(["unshare", "-m", "--propagation", "private", "sh", "-c", script, snapshot,
                      mount_point] + argv)
        rc = judge("output:full_fs", name, result, [out], allowed=(2,))
        if rc is not None:
            check_output("output:full_fs", name, tetpack, os.path.join(snapshot, os.path.basename(out)), old,
                         rc, ["out.tpk", "out.vtu", "out.ply", "out.png", "filler"])


def kill_faults(tetpack, data, work, old):
    """SIGKILL (and SIGTERM, SIGINT) at spread moments of a convert that replaces an older output: the
    output is then the old bytes or a complete valid file, and no temporary file is left. In the counts,
    refused means killed before it finished, accepted that it finished first."""
    source = os.path.join(data, "sfepy/cube_big_tetra.mesh")
    folder = os.path.join(work, "kill")
    os.mkdir(folder)
    out = os.path.join(folder, "out.tpk")
    argv = [tetpack, "convert", source, out, "--quiet", "--layout", "tet16", "--layout", "tet20", "--layout",
            "tet32", "--threads", "1"]
    start = time.monotonic()
    subprocess.run(argv, check=True)
    duration = time.monotonic() - start
    # Spread over the run, and one after it (that run completes: its output must be the new file).
    moments = [duration * k / (12 * SEEDS + 1) for k in range(1, 12 * SEEDS + 1)] + [duration * 2]
    for sig in (signal.SIGKILL, signal.SIGTERM, signal.SIGINT):
        for at in moments if sig == signal.SIGKILL else moments[::3]:
            with open(out, "wb") as f:
                f.write(old)
            p = subprocess.Popen(argv, stderr=subprocess.DEVNULL, start_new_session=True)
            time.sleep(at)
            p.send_signal(sig)
            p.wait()
            TALLY.add("output:kill", "cases")
            case = "%s_at_%.3fs" % (sig.name, at)
            before = TALLY.counts["output:kill"]["lost"]
            check_output("output:kill", case, tetpack, out, old, 0, [])
            if TALLY.counts["output:kill"]["lost"] == before:
                TALLY.add("output:kill", "refused" if p.returncode != 0 else "accepted")
            for f in os.listdir(folder):
                if f != "out.tpk":
                    os.unlink(os.path.join(folder, f))


def self_overwrite_faults(tetpack, inputs, work):
    """Outputs that are the input, or not regular files: refused by name, the input and the FIFO kept."""
    folder = os.path.join(work, "self")
    os.mkdir(folder)
    mesh = os.path.join(folder, "in.vtk")
    shutil.copyfile(inputs["mesh"], mesh)
    tpk = os.path.join(folder, "in.tpk")
    shutil.copyfile(inputs["tpk"], tpk)
    fifo = os.path.join(folder, "fifo.tpk")
    os.mkfifo(fifo)
    cases = (("convert_onto_input", [tetpack, "convert", mesh, mesh, "--quiet"], mesh),
             ("export_onto_input", [tetpack, "export", tpk, "--vtu", tpk], tpk),
             ("render_onto_input", [tetpack, "render", tpk, "-o", tpk], tpk),
             ("convert_onto_fifo", [tetpack, "convert", mesh, fifo, "--quiet"], fifo),
             ("convert_onto_directory", [tetpack, "convert", mesh, folder, "--quiet"], folder))
    originals = {p: open(p, "rb").read() for p in (mesh, tpk)}
    for name, argv, target in cases:
        judge("output:self", name, run(argv), [target], allowed=(2,))
        intact = all(open(p, "rb").read() == b for p, b in originals.items()) and \
            stat.S_ISFIFO(os.lstat(fifo).st_mode)
        stray = sorted(set(os.listdir(folder)) - {"in.vtk", "in.tpk", "fifo.tpk"})
        if not intact or stray:
            TALLY.fail("output:self", "lost", name, "input or FIFO changed, or files left: %s" % stray)
        for p, b in originals.items():  # the next case starts from the untouched inputs
            with open(p, "wb") as f:
                f.write(b)
        if not stat.S_ISFIFO(os.lstat(fifo).st_mode):
            os.unlink(fifo)
            os.mkfifo(fifo)


def run_output(tetpack, data, work, source_dir):
    mesh = os.path.join(source_dir, "samples/cylinder.vtk")
    inputs = {"mesh": mesh}
    layouts = ["--layout", "tet16", "--layout", "tet20", "--layout", "tet32"]
    make_tpk(tetpack, mesh, work, "in.tpk", *layouts)
    inputs["tpk"] = os.path.join(work, "in.tpk")
    old = make_tpk(tetpack, os.path.join(data, "sfepy/cross3d.mesh"), work, "old.tpk")
    read_only_faults(tetpack, inputs, work, old)
    full_fs_faults(tetpack, inputs, work, old)
    kill_faults(tetpack, data, work, old)
    self_overwrite_faults(tetpack, inputs, work)


def main():
    if len(sys.argv) != 5 or sys.argv[4] not in ("import", "tpk", "output"):
        print(__doc__, file=sys.stderr)
        return 2
    tetpack, data, source_dir, category = sys.argv[1:]
    tetpack = os.path.abspath(tetpack)
    work = tempfile.mkdtemp(prefix="tpk_faults_")
    started = time.monotonic()
    try:
        if category == "import":
            run_import(tetpack, data, work, source_dir)
        elif category == "tpk":
            run_tpk(tetpack, data, work, source_dir)
        else:
            run_output(tetpack, data, work, source_dir)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    TALLY.report(category)
    print("%s: %.1f s, %d seed(s)" % (category, time.monotonic() - started, SEEDS))
    if TALLY.real_failures:
        return 1
    if TALLY.skips:
        return 1 if os.environ.get("TETPACK_REQUIRE_ALL") == "1" else 77
    return 0


if __name__ == "__main__":
    sys.exit(main())
