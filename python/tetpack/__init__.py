"""tetpack: read .tpk files from Python with NumPy (libtetpack underneath), and hand them to meshio,
VTK and ParaView.

    import tetpack
    with tetpack.open("mesh.tpk") as f:
        f.positions()          # float32 (N, 3) relative to f.origin: a view into the mapped file
        f.tets()               # int32 (T, 4), positively oriented, from any layout
        f.field("pressure", step=2)

Uncompressed chunks come back as read-only NumPy views into the file's mapping (no copy); zstd chunks
are decoded into new arrays. Arrays keep the mapping alive: close() makes the File refuse further calls
(tetpack.Error) and the file is unmapped once no array points into it.
"""
import json
import os
import shutil
import subprocess

import numpy as np

from . import _tetpack
from ._tetpack import Error, LIBRARY_VERSION

__all__ = ["open", "File", "Error", "convert", "check", "info", "Field", "TET32", "TET20", "TET16",
           "SHELL_FACE", "LIBRARY_VERSION"]

# Record layouts of spec §3 (format/tetpack_format.h), little-endian as on disk.
TET32 = np.dtype([("v", "<i4", (3,)), ("vx", "<i4"), ("n", "<i4", (4,))])
TET20 = np.dtype([("vx", "<i4"), ("n", "<i4", (4,))])
TET16 = np.dtype([("vx", "<i4"), ("nx", "<i4", (3,))])
SHELL_FACE = np.dtype([("a", "<i4"), ("b", "<i4"), ("c", "<i4"), ("t", "<i4")])
_LAYOUTS = {32: ("TT32", TET32), 20: ("TT20", TET20), 16: ("TT16", TET16)}
VTK_TETRA = 10


def _tag(name):
    """FourCC value of a tag name, first character in the lowest byte (spec §2)."""
    return int.from_bytes(name.encode("ascii"), "little")


class Field:
    """One field: name, units, association ("point" or "tet"), steps, components, min, max, times
    (one float per step, or None when the file stores no TIME chunk)."""

    def __init__(self, desc, times):
        self.__dict__.update(desc)
        self.times = times

    def __repr__(self):
        return "Field(%r, %s, %d step(s), %d component(s))" % (self.name, self.association, self.steps,
                                                                self.components)


class File(_tetpack.File):
    """An open .tpk. Use tetpack.open(path); a context manager closes it."""

    def __init__(self, path, verify_all=False):
        super().__init__(os.fspath(path), verify_all)
        self.path = os.fspath(path)
        head = self.info()
        self.version = head["version"]
        self.file_size = head["file_size"]
        self.vertex_count = head["vertex_count"]
        self.tet_count = head["tet_count"]
        self.shell_face_count = head["shell_face_count"]
        self.origin = np.array(head["origin"], dtype=np.float64)
        self.bounds = (np.array(head["bounds_min"]), np.array(head["bounds_max"]))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self):
        state = "closed" if self.closed else "%d vertices, %d tets" % (self.vertex_count, self.tet_count)
        return "<tetpack.File %r: %s>" % (self.path, state)

    # ---- what the file holds ------------------------------------------------------------------

    @property
    def fields(self):
        """The fields (FDSC), each with its steps and their times."""
        times = self.times
        return [Field(d, times[:d["steps"]] if times is not None else None) for d in self.field_descs()]

    @property
    def times(self):
        """Time value per step (TIME chunk) as a list, or None when the file stores none."""
        i = self.find_chunk(_tag("TIME"))
        if i is None:
            return None
        return [float(t) for t in self._chunk(i).view("<f8")]

    @property
    def layouts(self):
        """The tet layouts the file stores, among 32, 20, 16."""
        return [k for k, (tag, _) in _LAYOUTS.items() if self.find_chunk(_tag(tag)) is not None]

    @property
    def meta(self):
        """META as a dict ({} when absent). META is informative (spec §8): text that is not JSON
        raises ValueError here and is available raw from chunk("META")."""
        i = self.find_chunk(_tag("META"))
        if i is None:
            return {}
        return json.loads(self._chunk(i).tobytes().decode("utf-8"))

    # ---- arrays ----------------------------------------------------------------------------------

    def _chunk(self, i):
        return self.chunk_bytes(i)[0]

    def chunk(self, tag, index=0, step=0):
        """The raw bytes of a chunk as a uint8 array (a view when uncompressed); Error NOT_FOUND if
        the file has no such chunk."""
        i = self.find_chunk(_tag(tag), index, step)
        if i is None:
            raise _not_found("no %s chunk with index %d, step %d" % (tag, index, step))
        return self._chunk(i)

    def _typed(self, tag, dtype, count, index=0, step=0, components=1):
        data = self.chunk(tag, index, step).view(dtype)
        if data.shape[0] != count * components:
            raise Error("%s chunk holds %d values, the header says %d" % (tag, data.shape[0], count * components))
        return data.reshape(count, components) if components != 1 else data

    def positions(self):
        """float32 (vertex_count, 3), relative to self.origin (spec §6.8)."""
        return self._typed("POS3", "<f4", self.vertex_count, components=3)

    def points(self):
        """World coordinates: origin + positions, as float64 (a new array)."""
        return self.origin + self.positions().astype(np.float64)

    def layout(self, layout):
        """The tet records of one layout (32, 20 or 16) as a structured array (TET32/TET20/TET16)."""
        tag, dtype = _LAYOUTS[layout]
        return self._typed(tag, dtype, self.tet_count)

    def tet32(self):
        return self.layout(32)

    def tet20(self):
        return self.layout(20)

    def tet16(self):
        return self.layout(16)

    def shell(self):
        """Boundary faces (a, b, c, t) as a SHELL_FACE structured array; (b-a)x(c-a) points out."""
        return self._typed("SHEL", SHELL_FACE, self.shell_face_count)

    def tmap(self):
        """int32 source cell per tet (TMAP), or None when absent."""
        return self._optional("TMAP", self.tet_count)

    def vmap(self):
        """int32 source vertex per vertex (VMAP), or None when absent."""
        return self._optional("VMAP", self.vertex_count)

    def _optional(self, tag, count):
        if self.find_chunk(_tag(tag)) is None:
            return None
        return self._typed(tag, "<i4", count)

    def field(self, name, step=0):
        """float32 values of a field at a step: (n,) or (n, components), n = vertices or tets."""
        for index, f in enumerate(self.fields):
            if f.name == name:
                if not 0 <= step < f.steps:
                    raise _not_found("field %r has %d step(s), not step %d" % (name, f.steps, step))
                count = self.tet_count if f.association == "tet" else self.vertex_count
                return self._typed("FDAT", "<f4", count, index, step, f.components)
        raise _not_found("no field named %r" % name)

    def tets(self, layout=None):
        """int32 (tet_count, 4) vertex quadruples, positively oriented, recovered by libtetpack from
        `layout` (default: the first of 32, 20, 16 the file has)."""
        if layout is None:
            present = self.layouts
            if not present:
                raise _not_found("the file has no tet layout")
            layout = present[0]
        return self.recover_tets(layout)

    # ---- other libraries ---------------------------------------------------------------------------

    def _named_arrays(self):
        """(association, name, values) for every field at every step, named as `tetpack export --vtu`
        names them (NAME, or NAME_t0, NAME_t1, ... for several steps), then source_point/source_cell."""
        for f in self.fields:
            for s in range(f.steps):
                name = f.name if f.steps == 1 else "%s_t%d" % (f.name, s)
                yield f.association, name, self.field(f.name, s)
        for assoc, name, values in (("point", "source_point", self.vmap()), ("tet", "source_cell", self.tmap())):
            if values is not None:
                yield assoc, name, values

    def to_meshio(self):
        """A meshio.Mesh: float64 world points, one "tetra" block, every field at every step."""
        import meshio
        point_data, cell_data = {}, {}
        for assoc, name, values in self._named_arrays():
            if assoc == "point":
                point_data[name] = np.array(values)
            else:
                cell_data[name] = [np.array(values)]
        return meshio.Mesh(self.points(), [("tetra", self.tets().astype(np.int64))], point_data=point_data,
                           cell_data=cell_data)

    def to_vtk(self, step=None):
        """A vtkUnstructuredGrid of the tets with float64 world points. step None: every field at
        every step, named as in to_meshio; step k: each field at step k (its last step if it has
        fewer) under its own name."""
        from . import vtk_support
        return vtk_support.unstructured_grid(self, step)

    def shell_to_vtk(self):
        """The shell as a vtkPolyData of outward triangles, with cell data "tet"."""
        from . import vtk_support
        return vtk_support.shell_polydata(self)


def _not_found(message):
    err = Error(message)
    err.code, err.code_name, err.message = 16, _tetpack.result_string(16), message
    return err


def open(path, verify_all=False):  # noqa: A001 (tetpack.open, as in the issue)
    """Open and map a .tpk. verify_all: check every chunk's checksum now rather than on first use."""
    return File(path, verify_all)


# ---- the tetpack command -----------------------------------------------------------------------------

def executable():
    """The tetpack command: $TETPACK_EXE, else the one this package was built or installed with, else PATH."""
    candidates = [os.environ.get("TETPACK_EXE")]
    try:
        from ._paths import TETPACK_EXE
        candidates.append(TETPACK_EXE)
    except ImportError:
        pass
    candidates.append(shutil.which("tetpack"))
    for exe in candidates:
        if exe and os.access(exe, os.X_OK):
            return exe
    raise FileNotFoundError("the tetpack command was not found (set TETPACK_EXE or put it on PATH)")


class CommandError(Error):
    """The tetpack command failed: .returncode, .stderr, and .report (its JSON, when it printed one)."""


def _run_json(args, ok_codes=(0,)):
    proc = subprocess.run([executable()] + [os.fspath(a) for a in args], capture_output=True, text=True)
    report = None
    if proc.stdout.strip():
        try:
            report = json.loads(proc.stdout)
        except ValueError:
            report = None
    if proc.returncode not in ok_codes or report is None:
        err = CommandError("tetpack %s failed (exit %d): %s" % (args[0], proc.returncode, proc.stderr.strip()))
        err.returncode, err.stderr, err.report = proc.returncode, proc.stderr, report
        raise err
    return report


def convert(source, output, layouts=None, zstd=None, fields=None, options=()):
    """Run `tetpack convert source output --json` and return its JSON summary as a dict.
    layouts: any of 32, 20, 16 (default: the tool's, tet16); zstd: a level 1-22 to compress chunks
    (default: uncompressed, zero-copy); fields: names to keep (default: the tool's); options: further
    command-line options."""
    args = ["convert", source, output, "--json"]
    for layout in layouts or ():
        args += ["--layout", "tet%d" % layout]
    if zstd:
        args += ["--zstd", str(int(zstd))]
    for name in fields or ():
        args += ["--field", name]
    return _run_json(args + list(options))


def check(path, options=()):
    """Run `tetpack check path --json` and return the report as a dict. Findings are in the report
    (exit 1 is a report, not an exception); a file the tool cannot read at all raises CommandError."""
    return _run_json(["check", path, "--json"] + list(options), ok_codes=(0, 1))


def info(path):
    """`tetpack info path --json` as a dict (what the command line reports, for comparisons)."""
    return _run_json(["info", path, "--json"])


def paraview_plugin_path():
    """Path of the ParaView reader plugin (tetpack_reader.py) of this build tree or installation."""
    from ._paths import PARAVIEW_PLUGIN
    return PARAVIEW_PLUGIN


def load_paraview_plugin(ns):
    """In pvpython: load the reader plugin into namespace `ns` (pass globals()), defining TetpackReader."""
    import inspect
    if not hasattr(inspect, "getargspec"):
        # ParaView 5.11's paraview.detail.pythonalgorithm imports inspect.getargspec, which Python 3.11
        # removed (Debian 12 ships exactly this pair); it reads only .args, which getfullargspec has too.
        inspect.getargspec = inspect.getfullargspec
    from paraview.simple import LoadPlugin
    LoadPlugin(paraview_plugin_path(), ns=ns)


from . import meshio_plugin  # noqa: E402  (registers .tpk with meshio when meshio is installed)
