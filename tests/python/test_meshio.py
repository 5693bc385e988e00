"""meshio.read("x.tpk") and meshio.write("x.tpk", mesh) work once tetpack is imported."""
import os
import unittest

import meshio
import numpy as np

import tetpack
from common import DATA, WORK, assert_equal, cases, converted, exported_vtu


class Meshio(unittest.TestCase):
    def test_registered(self):
        self.assertTrue(tetpack.meshio_plugin.registered)
        self.assertIn("tetpack", meshio._helpers.extension_to_filetypes[".tpk"])

    def test_read_equals_export(self):
        for name, codec in cases():
            path = converted(name, codec, 20)
            with self.subTest(mesh=name, codec=codec):
                mesh = meshio.read(path)
                want = exported_vtu(path)[1]
                assert_equal(self, mesh.points, want.points, "points")
                assert_equal(self, mesh.cells_dict["tetra"], want.tets, "tets")
                self.assertEqual(sorted(mesh.point_data), sorted(want.point_data))
                self.assertEqual(sorted(mesh.cell_data), sorted(want.cell_data))
                for label, values in mesh.point_data.items():
                    assert_equal(self, values, want.point_data[label], label)
                for label, values in mesh.cell_data.items():
                    assert_equal(self, values[0], want.cell_data[label], label)

    def test_write_goes_through_convert(self):
        """A meshio mesh of hexes written as .tpk comes back as tets over the same points (VMAP)
        covering the same cells (TMAP), with its point field."""
        source = meshio.read(os.path.join(DATA, "sfepy/cube_medium_hexa.mesh"))
        source.point_data = {"height": source.points[:, 2].copy()}
        out = os.path.join(WORK, "written_by_meshio.tpk")
        meshio.write(out, source)
        with tetpack.open(out) as f:
            vmap, tmap = f.vmap(), f.tmap()
            assert_equal(self, f.points(), source.points[vmap].astype(np.float32).astype(np.float64), "points")
            assert_equal(self, f.field("height"), source.point_data["height"][vmap].astype(np.float32), "height")
            hexes = source.cells_dict["hexahedron"]
            per_hex = np.bincount(tmap, minlength=len(hexes))
            self.assertTrue(set(per_hex.tolist()) <= {5, 6}, "a hex splits into 5 or 6 tets")
            corners = vmap[f.tets()]
            for t in range(0, f.tet_count, 97):
                self.assertTrue(set(corners[t]) <= set(hexes[tmap[t]]), "tet %d outside its hex" % t)
        self.assertFalse(tetpack.check(out)["problems"])


if __name__ == "__main__":
    unittest.main()
