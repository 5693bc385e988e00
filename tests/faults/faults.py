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
import random
import re
import shutil
import signal
import stat
import struct
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import tpk_bytes  # noqa: E402

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


# ---- mutations of importer inputs (every one seeded) -------------------------------------------------

INT_TOKEN = re.compile(rb"(?<![\w.+\-])[0-9]+(?![\w.])")
FLOAT_TOKEN = re.compile(rb"(?<![\w.])-?[0-9]*\.[0-9]+(?:[eE][-+]?[0-9]+)?")
ABSURD_INTS = (b"2147483647", b"4294967295", b"9223372036854775807", b"99999999999999999999", b"-1",
               b"-2147483648", b"0")
NON_FINITE = (b"nan", b"inf", b"-inf", b"1e999", b"NaN", b"-1e400")


def text_length(data, limit=65536):
    """How many bytes the file starts with that are text: the header of a binary VTK or VTU file, say."""
    for at, b in enumerate(data[:limit]):
        if b < 9 or 13 < b < 32 or b > 126:
            return at
    return min(len(data), limit)


def replace_token(data, rng, pattern, lo, hi, values):
    spans = [m.span() for m in pattern.finditer(data, lo, hi)]
    if not spans:
        return None
    a, b = rng.choice(spans)
    return data[:a] + rng.choice(values) + data[b:]


def overwrite_word(data, rng, lo, hi, values):
    if hi - lo < 8:
        return None
    at = lo + rng.randrange((hi - lo - 8) // 4) * 4
    word = rng.choice(values)
    return data[:at] + word + data[at + len(word):]


BINARY_BOMBS = [struct.pack(f, v) for f in ("<I", ">I") for v in (0x7FFFFFFF, 0xFFFFFFFF, 0x40000000)] + \
               [struct.pack(f, v) for f in ("<Q", ">Q") for v in (1 << 62, (1 << 64) - 1)]
BINARY_NAN = [struct.pack(f, v) for f in ("<d", ">d", "<f", ">f") for v in (float("nan"), float("inf"))]


def mutations(data, seed, first):
    """[(name, bytes)]: seeded byte flips and truncations (the `first` seed also cuts at 0, 1, half and
    all but the last byte), absurd counts near the start (memory bombs), ids out of range further on, and
    non-finite numbers, as text tokens or binary words."""
    rng = random.Random(seed)
    n = len(data)
    head = min(n, max(512, n // 20))
    text_head = min(head, text_length(data))  # where counts are text tokens
    text = text_length(data) == min(n, 65536)
    out = []
    for k in range(6):
        flipped = bytearray(data)
        for _ in range(1 + k % 3):
            flipped[rng.randrange(n)] ^= rng.randrange(1, 256)
        out.append(("flip%d" % k, bytes(flipped)))
    for k, cut in enumerate(([0, 1, n // 2, n - 1] if first else []) + [rng.randrange(n) for _ in range(2)]):
        out.append(("cut%d_at_%d" % (k, cut), data[:cut]))
    for k in range(3):
        bomb = replace_token(data, rng, INT_TOKEN, 0, text_head, ABSURD_INTS)
        out.append(("count%d" % k, bomb or overwrite_word(data, rng, 0, head, BINARY_BOMBS)))
        ids = replace_token(data, rng, INT_TOKEN, n // 2, n, ABSURD_INTS) if text else None
        out.append(("id%d" % k, ids or overwrite_word(data, rng, n // 2, n, BINARY_BOMBS)))
    for k in range(2):
        bad = replace_token(data, rng, FLOAT_TOKEN, head, n, NON_FINITE) if text else None
        out.append(("nonfinite%d" % k, bad or overwrite_word(data, rng, n // 2, n, BINARY_NAN)))
    return [(name, b) for name, b in out if b is not None and b != data]


# ---- the importer inputs: a real file per format where ../shared/data has one, else a generated one ----

def closed_surface(size=3):
    """A cube's surface cut into size x size squares per side, two outward triangles each."""
    points, index, tris = [], {}, []

    def pid(p):
        if p not in index:
            index[p] = len(points)
            points.append(p)
        return index[p]
    for axis in range(3):
        for side in (0, size):
            for i in range(size):
                for j in range(size):
                    quad = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0, 0, 0]
                        p[axis], p[(axis + 1) % 3], p[(axis + 2) % 3] = side, i + di, j + dj
                        quad.append(pid(tuple(p)))
                    if side == 0:
                        quad.reverse()
                    tris += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
    return points, tris


def write_surfaces(folder):
    points, tris = closed_surface()
    files = {}
    path = os.path.join(folder, "cube.stl")
    with open(path, "w") as f:
        f.write("solid cube\n")
        for t in tris:
            f.write(" facet normal 0 0 0\n  outer loop\n")
            for v in t:
                f.write("   vertex %g %g %g\n" % points[v])
            f.write("  endloop\n endfacet\n")
        f.write("endsolid cube\n")
    files["stl"] = [path]
    path = os.path.join(folder, "cube_bin.stl")
    with open(path, "wb") as f:
        f.write(b"binary cube".ljust(80, b" ") + struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<12fH", 0, 0, 0, *[c for v in t for c in points[v]], 0))
    files["stl"].append(path)
    path = os.path.join(folder, "cube.off")
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(points), len(tris)))
        f.writelines("%g %g %g\n" % p for p in points)
        f.writelines("3 %d %d %d\n" % t for t in tris)
    files["off"] = [path]
    path = os.path.join(folder, "cube.ply")
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
                 "property float y\nproperty float z\nelement face %d\nproperty list uchar int "
                 "vertex_indices\nend_header\n" % (len(points), len(tris))).encode())
        for p in points:
            f.write(struct.pack("<3f", *p))
        for t in tris:
            f.write(struct.pack("<B3i", 3, *t))
    files["ply"] = [path]
    rng = random.Random(7)
    path = os.path.join(folder, "cloud.csv")
    with open(path, "w") as f:
        f.write("x,y,z,temperature\n")
        for _ in range(60):
            f.write("%.6f,%.6f,%.6f,%.3f\n" % (rng.random(), rng.random(), rng.random(), rng.random()))
    files["csv"] = [path]
    return files


def write_pvd(tetpack, data, folder):
    """A two-step ParaView series of VTU files written by `tetpack export` from a real mesh."""
    tpk = os.path.join(folder, "cross3d.tpk")
    subprocess.run([tetpack, "convert", os.path.join(data, "sfepy/cross3d.mesh"), tpk, "--quiet"], check=True)
    for step in range(2):
        subprocess.run([tetpack, "export", tpk, "--vtu", os.path.join(folder, "step%d.vtu" % step)],
                       check=True)
    path = os.path.join(folder, "series.pvd")
    with open(path, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n'
                '<DataSet timestep="0" file="step0.vtu"/>\n<DataSet timestep="0.5" file="step1.vtu"/>\n'
                '</Collection>\n</VTKFile>\n')
    return [path, os.path.join(folder, "step0.vtu"), os.path.join(folder, "step1.vtu")]


REAL_INPUTS = {
    "vtk": ["sfepy/cylinder.vtk", "gmsh/t5_small_tet_bin.vtk"],
    "vtu": ["hard/huge_offset_hex.vtu", "hard/nonmanifold_vertex_edge_tets.vtu"],
    "gmsh": ["gmsh/t5_small_tet_ascii22.msh", "gmsh/t3_hex_prism_ascii41.msh"],
    "medit": ["sfepy/cube_medium_hexa.mesh", "sfepy/cross3d.mesh"],
    "meshb": ["nasa_refine/om6_om6-curv-no-geom.meshb"],
    "ugrid": ["nasa_refine/cube_polar1.ugrid"],
    "exodus": ["seacas/cube.g", "seacas/8-block.g"],
    "tetgen": ["tetgen/part1_small.node"],
}


def write_binary_ugrid(ascii_path, folder):
    """The ASCII UGRID file as little-endian binary (.lb8.ugrid: int32 and float64): 7 counts, the node
    coordinates, then every other number an integer."""
    numbers = open(ascii_path).read().split()
    nodes = int(numbers[0])
    path = os.path.join(folder, "cube_polar1.lb8.ugrid")
    with open(path, "wb") as f:
        f.write(struct.pack("<7i", *map(int, numbers[:7])))
        f.write(struct.pack("<%dd" % (3 * nodes), *map(float, numbers[7:7 + 3 * nodes])))
        rest = numbers[7 + 3 * nodes:]
        f.write(struct.pack("<%di" % len(rest), *map(int, rest)))
    return path


def importer_sources(tetpack, data, folder):
    """[(format, [files: the first is what convert is given; any of them may be the one damaged], options)]:
    every format `tetpack formats` lists, from real files where ../shared/data has them."""
    sources = []
    for fmt, paths in REAL_INPUTS.items():
        for p in paths:
            files = [os.path.join(data, p)]
            if fmt == "tetgen":
                files.append(files[0][:-len(".node")] + ".ele")
            sources.append((fmt, files, []))
    sources.append(("ugrid", [write_binary_ugrid(os.path.join(data, REAL_INPUTS["ugrid"][0]), folder)], []))
    sources.append(("pvd", write_pvd(tetpack, data, folder), []))
    surfaces = write_surfaces(folder)
    for fmt, paths in surfaces.items():
        sources += [(fmt, [p], []) for p in paths]
    sources.append(("surface", [surfaces["stl"][1]], ["--format", "surface"]))
    sources.append(("points", [surfaces["ply"][0]], ["--format", "points"]))
    listed = json.loads(subprocess.run([tetpack, "formats", "--json"], check=True, capture_output=True).stdout)
    for fmt in listed["formats"]:
        if fmt["name"] not in {s[0] for s in sources}:
            TALLY.fail("import:" + fmt["name"], "other", "-", "tetpack formats lists it, the fault suite has no input")
    return sources


def import_case(tetpack, work, fmt, files, options, damaged, name, payload, old):
    """Convert a copy of `files` with `damaged` (an index into it) replaced by `payload`."""
    case = "%s/%s/%s" % (fmt, os.path.basename(files[damaged]), name)
    folder = tempfile.mkdtemp(dir=work)
    inputs = os.path.join(folder, "in")
    os.mkdir(inputs)
    for k, f in enumerate(files):
        target = os.path.join(inputs, os.path.basename(f))
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
    rc = judge("import:" + fmt, case, result, [files[damaged], files[0]])
    if rc is not None:
        check_output("import:" + fmt, case, tetpack, out, old, rc, [])
    shutil.rmtree(folder)


def run_import(tetpack, data, work):
    sources = importer_sources(tetpack, data, work)
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
                for name, payload in mutations(data_bytes, hash_seed(f, seed), seed == 0):
                    jobs.append((fmt, files, options, damaged, "%s_s%d" % (name, seed), payload))
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

ABSURD_U64 = (0, 1, 63, 65, 0xFFFFFFFF, 0x7FFFFFFF, 1 << 40, 1 << 63, (1 << 64) - 1)


def tpk_mutations(original, seed):
    """[(name, bytes, must_refuse)]: chunk bytes flipped (plain: in place; zstd: in the frame, or in the
    decoded bytes and compressed again) and header or directory fields set to absurd values, every
    checksum recomputed; bad offsets, memory and zstd bombs, extra zstd frames; plain flips and cuts."""
    rng = random.Random(seed)
    out = []
    base = tpk_bytes.Tpk(original)
    size = len(original)

    def fresh():
        return tpk_bytes.Tpk(original)
    for k in range(6):
        t = fresh()
        e = rng.choice(t.entries)
        for _ in range(1 + k % 3):
            t.data[e["offset"] + rng.randrange(max(1, e["stored_size"]))] ^= rng.randrange(1, 256)
        out.append(("chunk_flip%d_%s" % (k, tag_name(e)), t.seal(), False))
    zstd_entries = [i for i, e in enumerate(base.entries) if e["codec"] == tpk_bytes.CODEC_ZSTD]
    for k in range(4 if zstd_entries else 0):
        t = fresh()
        e = t.entries[rng.choice(zstd_entries)]
        raw = bytearray(t.decoded(e))
        for _ in range(1 + k % 3):
            raw[rng.randrange(len(raw))] ^= rng.randrange(1, 256)
        frame = tpk_bytes.zstd_compress(raw, 3)
        if len(frame) <= e["stored_size"]:
            set_stored(t, e, frame)
            out.append(("zstd_raw_flip%d_%s" % (k, tag_name(e)), t.seal(), False))
    for k in range(8):
        t = fresh()
        field = rng.choice(("vertex_count", "tet_count", "shell_face_count", "chunk_count",
                            "directory_offset", "file_size", "ox", "maxz", "flags", "version_minor"))
        value = rng.choice(ABSURD_U64) if field not in ("ox", "maxz") else rng.choice(
            (float("nan"), float("inf"), -1e308))
        if field == "flags":
            value &= 0xFFFFFFFF
        if field == "version_minor":
            value &= 0xFFFF
        t.header[field] = value
        out.append(("header_%s_%s" % (field, value), t.seal(), False))
    for k in range(12):
        t = fresh()
        e = rng.choice(t.entries)
        field = rng.choice(("elem_count", "offset", "stored_size", "raw_size", "elem_size", "elem_type",
                            "codec", "index", "step", "tag"))
        value = rng.choice(ABSURD_U64)
        e[field] = value & {"elem_type": 0xFF, "codec": 0xFF, "elem_size": 0xFFFFFFFF, "index": 0xFFFFFFFF,
                            "step": 0xFFFFFFFF, "tag": 0xFFFFFFFF}.get(field, (1 << 64) - 1)
        out.append(("entry_%s_%s_%d" % (tag_name(e), field, value), t.seal(), False))
    out += offset_faults(fresh, rng)
    out += bomb_faults(fresh, base, zstd_entries)
    for k in range(3):
        flipped = bytearray(original)
        flipped[rng.randrange(size)] ^= rng.randrange(1, 256)
        out.append(("plain_flip%d" % k, bytes(flipped), False))
    for cut in (0, 100, 191, 192, size // 2, size - 1):
        out.append(("cut_%d" % cut, original[:cut], True))
    return out


def tag_name(e):
    return e["tag"].to_bytes(4, "little").decode("latin-1").strip("\0") or "0"


def set_stored(t, e, stored):
    """Replace an entry's stored bytes in place (they must fit in the old space; the rest is zeroed)."""
    at, room = e["offset"], e["stored_size"]
    t.data[at:at + room] = stored + bytes(room - len(stored))
    e["stored_size"] = len(stored)


def offset_faults(fresh, rng):
    """Offsets a compliant reader must refuse (spec §4): misaligned, past the end, onto another chunk,
    onto the directory, and sizes that run past the end; every checksum recomputed."""
    out = []
    cases = (("misaligned", lambda t, e: e["offset"] + 8), ("past_end", lambda t, e: len(t.data) + 64),
             ("huge", lambda t, e: (1 << 63) - 64), ("onto_other", lambda t, e: t.entries[0]["offset"]
                                                      if e is not t.entries[0] else t.entries[1]["offset"]),
             ("onto_directory", lambda t, e: t.header["directory_offset"]), ("into_header", lambda t, e: 64))
    for name, where in cases:
        t = fresh()
        e = rng.choice(t.entries)
        e["offset"] = where(t, e)
        out.append(("offset_%s_%s" % (name, tag_name(e)), t.seal(), True))
    t = fresh()
    e = t.entries[-1]
    e["stored_size"] = len(t.data)
    out.append(("stored_past_end_%s" % tag_name(e), t.seal(chunk_checksums=False), True))
    return out


def bomb_faults(fresh, base, zstd_entries):
    """Counts that claim gigabytes (consistent with each other, so only a limit or the file size stops
    them) and zstd frames that decode to far more than the entry says, or carry a second frame."""
    out = []
    for i, e in enumerate(base.entries[:4]):
        t = fresh()
        e = t.entries[i]
        e["elem_count"] = (1 << 40) // max(1, e["elem_size"])
        e["raw_size"] = e["elem_count"] * e["elem_size"]
        if e["codec"] == tpk_bytes.CODEC_NONE:
            e["stored_size"] = e["raw_size"]
        out.append(("memory_bomb_%s" % tag_name(e), t.seal(chunk_checksums=False), True))
    t = fresh()
    t.header["vertex_count"] = t.header["tet_count"] = 0x7FFFFFFF
    out.append(("memory_bomb_header_counts", t.seal(), True))
    for i in zstd_entries[:3]:
        e = base.entries[i]
        blocks = (e["stored_size"] - 14) // 4  # magic, header with a content size, 4 bytes a block
        if blocks < 2:
            continue
        for claim in (None, e["raw_size"], 1 << 60):
            t = fresh()
            set_stored(t, t.entries[i], tpk_bytes.rle_bomb(blocks, claim))
            out.append(("zstd_bomb_%s_claims_%s" % (tag_name(e), claim), t.seal(), True))
        raw = base.decoded(e)
        frame = tpk_bytes.zstd_compress(raw, 19)
        extras = (("skippable_after", frame + tpk_bytes.skippable_frame()),
                  ("skippable_before", tpk_bytes.skippable_frame() + frame),
                  ("two_frames", tpk_bytes.zstd_compress(raw[:len(raw) // 2], 19) +
                   tpk_bytes.zstd_compress(raw[len(raw) // 2:], 19)))
        for name, stored in extras:
            if len(stored) <= e["stored_size"]:
                t = fresh()
                set_stored(t, t.entries[i], stored)
                out.append(("zstd_%s_%s" % (name, tag_name(e)), t.seal(), True))
    return out


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
                     for name, payload, refuse in tpk_mutations(original, 1000 * seed + len(kind))]
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
            run_import(tetpack, data, work)
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
