"""f.to_vtk() and f.shell_to_vtk() (Debian's python3-vtk9, or python3-paraview's own VTK) hold what `tetpack export` writes."""
import unittest

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy

import tetpack
from common import Exported, assert_equal, cases, converted, exported_shell, exported_vtu


class ToVtk(unittest.TestCase):
    def assert_same_grid(self, got, want):
        assert_equal(self, got.points, want.points, "points")
        assert_equal(self, got.tets, want.tets, "tets")
        for section in ("point_data", "cell_data"):
            mine, theirs = getattr(got, section), getattr(want, section)
            self.assertEqual(sorted(mine), sorted(theirs), section)
            for name in theirs:
                assert_equal(self, mine[name], theirs[name], name)

    def test_grid_equals_exported_vtu(self):
        for name, codec in cases():
            path = converted(name, codec, 16)
            with self.subTest(mesh=name, codec=codec), tetpack.open(path) as f:
                grid = f.to_vtk()
                self.assertEqual(grid.GetClassName(), "vtkUnstructuredGrid")
                self.assertEqual(grid.GetNumberOfCells(), f.tet_count)
                self.assert_same_grid(Exported(grid=grid), exported_vtu(path)[1])

    def test_one_step(self):
        with tetpack.open(converted("8block", "zstd")) as f:
            grid = Exported(grid=f.to_vtk(step=7))
            self.assertEqual(sorted(grid.point_data), sorted(x.name for x in f.fields))
            for field in f.fields:
                assert_equal(self, grid.point_data[field.name], f.field(field.name, 7), field.name)

    def test_shell_polydata(self):
        for name, codec in cases():
            with self.subTest(mesh=name, codec=codec), tetpack.open(converted(name, codec)) as f:
                poly = f.shell_to_vtk()
                points, tri, tet = exported_shell(converted(name, codec))
                mine = vtk_to_numpy(poly.GetPolys().GetConnectivityArray()).reshape(-1, 3)
                assert_equal(self, vtk_to_numpy(poly.GetPoints().GetData()), points, "shell points")
                assert_equal(self, mine, tri, "shell triangles")
                assert_equal(self, vtk_to_numpy(poly.GetCellData().GetArray("tet")), tet, "shell tets")
                self.assertEqual(np.unique(vtk_to_numpy(poly.GetPointData().GetArray("vertex"))).size,
                                 poly.GetNumberOfPoints())


if __name__ == "__main__":
    unittest.main()
