"""Shared by the Python tests: real meshes from the data corpus converted once per process with every
layout, plain and zstd, and what `tetpack export` writes for them (the reference the module must equal).
Run by ctest with PYTHONPATH=<build>/python, TETPACK_EXE and TETPACK_DATA_DIR set (tests/CMakeLists.txt)."""
import atexit
import functools
import os
import shutil
import subprocess
import tempfile

import numpy as np

import tetpack

DATA = os.environ.get("TETPACK_DATA_DIR", os.path.join(os.path.dirname(__file__), "../../../shared/data"))
SAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "samples")
WORK = tempfile.mkdtemp(prefix="tetpack-pytest-")
atexit.register(shutil.rmtree, WORK, True)
ALL_LAYOUTS = ("--layout", "tet32", "--layout", "tet20", "--layout", "tet16")

# name: (input under DATA, extra convert options). Together they cover tet and point fields, 11 time
# steps with times, a far-away origin, hexes and wedges split into tets.
MESHES = {
    "acoustic_wg": ("sfepy/acoustic_wg.vtk", ("--field", "mat_id", "--field", "node_groups")),
    "8block": ("seacas/8-block.g", ()),
    "huge_offset": ("hard/huge_offset_hex.vtu", ()),
    "t3_prisms": ("gmsh/t3_hex_prism_ascii41.msh", ()),
}
CODECS = {"plain": (), "zstd": ("--zstd", "3")}


def run(*args):
    return subprocess.run([tetpack.executable()] + [str(a) for a in args], check=True, capture_output=True,
                          text=True).stdout


@functools.lru_cache(maxsize=None)
def converted(name, codec, layout=None):
    """Path of MESHES[name] converted with one layout (32, 20, 16) or all three (None), plain or zstd."""
    source, options = MESHES[name]
    out = os.path.join(WORK, "%s_%s_%s.tpk" % (name, codec, layout or "all"))
    layouts = ("--layout", "tet%d" % layout) if layout else ALL_LAYOUTS
    run("convert", os.path.join(DATA, source), out, *layouts, *options, *CODECS[codec])
    return out


class Exported:
    """What `tetpack export --vtu` wrote, read by VTK's own XML reader (ParaView's): points, tets,
    point_data and cell_data as NumPy arrays. Not meshio 5: it misreads two of the 134 appended arrays
    of 8-block.g's export (accel_z_t9, force_z_t10), which VTK and this module read alike."""

    def __init__(self, vtu=None, grid=None):
        from vtkmodules.util.numpy_support import vtk_to_numpy
        from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
        if grid is None:
            reader = vtkXMLUnstructuredGridReader()
            reader.SetFileName(vtu)
            reader.Update()
            grid = reader.GetOutput()
        self.points = vtk_to_numpy(grid.GetPoints().GetData())
        assert (vtk_to_numpy(grid.GetCellTypesArray()) == tetpack.VTK_TETRA).all()
        self.tets = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
        self.point_data, self.cell_data = ({data.GetArrayName(i): vtk_to_numpy(data.GetArray(i))
                                            for i in range(data.GetNumberOfArrays())}
                                           for data in (grid.GetPointData(), grid.GetCellData()))


@functools.lru_cache(maxsize=None)
def exported_vtu(path):
    """`tetpack export --vtu` of a .tpk, read back: (vtu path, Exported)."""
    out = path[:-4] + ".vtu"
    run("export", path, "--vtu", out)
    return out, Exported(out)


def exported_shell(path):
    """`tetpack export --shell x.ply` read back: (float64 points, int32 triangles, int32 tet per face).
    The PLY is ours (binary little-endian, a face list with uchar counts then an int tet), which
    meshio 5 does not read, hence this reader."""
    out = path[:-4] + "_shell.ply"
    run("export", path, "--shell", out)
    with open(out, "rb") as ply:
        header = b""
        while not header.endswith(b"end_header\n"):
            header += ply.readline()
        body = ply.read()
    counts = dict(line.split()[1:3] for line in header.decode().splitlines() if line.startswith("element"))
    vertices, faces = int(counts["vertex"]), int(counts["face"])
    points = np.frombuffer(body, "<f8", 3 * vertices).reshape(-1, 3)
    face = np.frombuffer(body, np.dtype([("n", "u1"), ("v", "<i4", (3,)), ("t", "<i4")]), faces, 24 * vertices)
    assert (face["n"] == 3).all()
    return points, face["v"], face["t"]


def cases():
    return [(name, codec) for name in MESHES for codec in CODECS]


def address(array):
    return array.__array_interface__["data"][0]


def assert_equal(test, got, want, what):
    got, want = np.asarray(got), np.asarray(want)
    test.assertEqual(got.shape, want.shape, what)
    # NaN is a value fields carry (an Exodus variable undefined at a step): equal to itself here
    nan_ok = got.dtype.kind == "f" and want.dtype.kind == "f"
    test.assertTrue(np.array_equal(got, want, equal_nan=nan_ok), "%s differs" % what)
