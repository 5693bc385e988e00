"""tetpack -> VTK objects (vtkUnstructuredGrid, vtkPolyData), with the vtkmodules of whoever imports
it: Debian's python3-vtk9 under python3, ParaView's own under pvpython (the reader plugin)."""
import numpy as np
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData, vtkUnstructuredGrid

VTK_TETRA = 10


def _points(values):
    points = vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(values, dtype=np.float64), deep=True))
    return points


def _cells(connectivity):
    """A vtkCellArray of equal-sized cells from an int (n, k) array (offsets 0, k, 2k, ...)."""
    n, k = connectivity.shape
    cells = vtkCellArray()
    offsets = numpy_support.numpy_to_vtk(np.arange(0, (n + 1) * k, k, dtype=np.int64), deep=True)
    conn = numpy_support.numpy_to_vtk(np.ascontiguousarray(connectivity, dtype=np.int64).ravel(), deep=True)
    cells.SetData(offsets, conn)
    return cells


def _add(data, name, values):
    array = numpy_support.numpy_to_vtk(np.ascontiguousarray(values), deep=True)
    array.SetName(name)
    data.AddArray(array)


def geometry(f):
    """(vtkPoints, vtkCellArray) of File f: what every time step of a grid shares."""
    return _points(f.points()), _cells(f.tets())


def fill_grid(grid, f, step=None, shared_geometry=None):
    """Fill `grid` (a vtkUnstructuredGrid) from File f; see File.to_vtk for `step`. shared_geometry:
    geometry(f) kept by the caller (the ParaView reader, so that stepping through time recovers the
    tets once)."""
    points, cells = shared_geometry or geometry(f)
    grid.SetPoints(points)
    grid.SetCells(VTK_TETRA, cells)
    if step is None:
        arrays = f._named_arrays()
    else:
        arrays = [(fd.association, fd.name, f.field(fd.name, min(step, fd.steps - 1))) for fd in f.fields]
    for assoc, name, values in arrays:
        _add(grid.GetPointData() if assoc == "point" else grid.GetCellData(), name, values)
    return grid


def unstructured_grid(f, step=None):
    return fill_grid(vtkUnstructuredGrid(), f, step)


def shell_polydata(f):
    """Only the shell's vertices, renumbered in ascending id order (as `tetpack export --shell`)."""
    shell = f.shell()
    tri = np.stack([shell["a"], shell["b"], shell["c"]], axis=1)
    used, local = np.unique(tri, return_inverse=True)
    poly = vtkPolyData()
    poly.SetPoints(_points(f.points()[used]))
    poly.SetPolys(_cells(local.reshape(-1, 3)))
    _add(poly.GetCellData(), "tet", np.array(shell["t"]))
    _add(poly.GetPointData(), "vertex", used.astype(np.int32))
    return poly
