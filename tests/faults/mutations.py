"""Damaged importer inputs for the fault suite (faults.py): seeded mutations of a file's bytes, and the
inputs generated where ../shared/data has no real file of a format."""
import contextlib
import os
import random
import re
import struct
import subprocess
import zlib

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


# ---- inputs made here: surfaces and point clouds (TetGen's formats), a .pvd series, binary UGRID ----

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


def write_vtkhdf(tetpack, data, folder):
    """A VTKHDF file (HDF5) written by `tetpack export --vtkhdf` from a real mesh with a point field."""
    tpk = os.path.join(folder, "cylinder_vtkhdf.tpk")
    subprocess.run([tetpack, "convert", os.path.join(data, "sfepy/cylinder.vtk"), tpk, "--quiet"], check=True)
    path = os.path.join(folder, "cylinder.vtkhdf")
    subprocess.run([tetpack, "export", tpk, "--vtkhdf", path], check=True)
    return path


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


def write_meshio_files(source, folder):
    """Binary Gmsh 4.1 and 2.2, a zlib-compressed VTU (zlib blocks are where inflate bombs hide), Abaqus
    .inp, XDMF with inline XML data and DOLFIN XML of `source`, written by meshio (an independent writer):
    {format: [paths]}, or None without meshio."""
    try:
        import meshio
    except ImportError:
        return None
    mesh = meshio.read(source)
    paths = {"gmsh": [os.path.join(folder, "bin41.msh"), os.path.join(folder, "bin22.msh")],
             "vtu": [os.path.join(folder, "zlib.vtu")], "inp": [os.path.join(folder, "meshio.inp")],
             "xdmf": [os.path.join(folder, "inline.xdmf")], "dolfin": [os.path.join(folder, "dolfin.xml")]}
    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
        meshio.write(paths["gmsh"][0], mesh, file_format="gmsh", binary=True)
        meshio.write(paths["gmsh"][1], mesh, file_format="gmsh22", binary=True)
        meshio.write(paths["vtu"][0], mesh, binary=True, compression="zlib")
        meshio.write(paths["inp"][0], mesh, file_format="abaqus")
        meshio.write(paths["xdmf"][0], mesh, file_format="xdmf", data_format="XML")
        meshio.write(paths["dolfin"][0], meshio.Mesh(mesh.points, mesh.cells), file_format="dolfin-xml")
    return paths


def _zlib_array(raw, claimed_block=None, claimed_blocks=1, inflated=None):
    """An appended zlib DataArray (UInt64 header: blocks, block size, last block size, compressed sizes):
    `raw` compressed, or `inflated` bytes compressed while the header claims `raw`'s size."""
    stream = zlib.compress(inflated if inflated is not None else raw, 9)
    block = len(raw) if claimed_block is None else claimed_block
    return struct.pack("<4Q", claimed_blocks, block, 0, len(stream)) + stream


def write_vtu_zlib_bombs(folder):
    """[(name, path)]: a one-tet zlib VTU whose points block inflates to 64 MiB while its header says 96
    bytes, or whose header claims a 2^40-byte block or 2^40 blocks; and the clean file first ("clean")."""
    points = struct.pack("<12d", 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1)
    arrays = [struct.pack("<4q", 0, 1, 2, 3), struct.pack("<q", 4), bytes([10])]
    variants = (("clean", {}), ("inflates_to_64MiB", {"inflated": bytes(64 << 20)}),
                ("claims_2^40_byte_block", {"claimed_block": 1 << 40}),
                ("claims_2^40_blocks", {"claimed_blocks": 1 << 40}))
    out = []
    for name, bomb in variants:
        blobs = [_zlib_array(points, **bomb)] + [_zlib_array(a) for a in arrays]
        offsets = [sum(len(b) for b in blobs[:k]) for k in range(4)]
        xml = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
               'header_type="UInt64" compressor="vtkZLibDataCompressor">\n<UnstructuredGrid>\n'
               '<Piece NumberOfPoints="4" NumberOfCells="1">\n<Points>\n<DataArray type="Float64" '
               'NumberOfComponents="3" format="appended" offset="%d"/>\n</Points>\n<Cells>\n'
               '<DataArray type="Int64" Name="connectivity" format="appended" offset="%d"/>\n'
               '<DataArray type="Int64" Name="offsets" format="appended" offset="%d"/>\n'
               '<DataArray type="UInt8" Name="types" format="appended" offset="%d"/>\n</Cells>\n</Piece>\n'
               '</UnstructuredGrid>\n<AppendedData encoding="raw">\n_' % tuple(offsets))
        path = os.path.join(folder, "zlib_%s.vtu" % name)
        with open(path, "wb") as f:
            f.write(xml.encode() + b"".join(blobs) + b"\n</AppendedData>\n</VTKFile>\n")
        out.append((name, path))
    return out
