"""Unstructured grids written by VTK itself (python3-paraview's VTK), for the CLI tests of higher-order
cells (lagrange_hex.sh, lagrange_tet_wedge.sh, vtk_hex24_pyramid19.sh): one VTK point per key, so the
points that cells share are written once, each with a value of the point field "f"; ASCII .vtu.
usage, in a test's Python (common.sh's cli_py puts this folder on its path):
    g = vtk_write.Grid(2, value)        # 2 cells to come; value(x): f at a point placed at x
    g.cell(VTK_LAGRANGE_WEDGE, [g.point(key, x) for ...])
    grid = g.write(path)                # the vtkUnstructuredGrid, written"""
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkPoints
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter


class Grid:
    def __init__(self, cells, value):
        self.grid, self.points, self.field, self.ids = vtkUnstructuredGrid(), vtkPoints(), vtkDoubleArray(), {}
        self.field.SetName("f")
        self.value = value
        self.grid.Allocate(cells)

    def point(self, key, x):
        """The id of key's point, placed at x with f = value(x) the first time key is seen."""
        if key not in self.ids:
            self.ids[key] = self.points.InsertNextPoint(*x)
            self.field.InsertNextValue(self.value(x))
        return self.ids[key]

    def cell(self, vtk_type, conn):
        self.grid.InsertNextCell(vtk_type, len(conn), conn)

    def write(self, path):
        self.grid.SetPoints(self.points)
        self.grid.GetPointData().AddArray(self.field)
        w = vtkXMLUnstructuredGridWriter()
        w.SetFileName(path)
        w.SetInputData(self.grid)
        w.SetDataModeToAscii()
        assert w.Write() == 1, path
        return self.grid
