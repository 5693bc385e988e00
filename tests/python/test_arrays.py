"""Every array the module gives equals what `tetpack export --vtu` (and --shell) writes, for every layout,
plain and zstd, on real meshes; uncompressed chunks are views into the mapping, zstd ones copies."""
import itertools
import os
import unittest

import numpy as np

import tetpack
from common import DATA, MESHES, address, assert_equal, cases, converted, exported_shell, exported_vtu


class ArraysEqualExport(unittest.TestCase):
    def test_positions_tets_fields_maps(self):
        for (name, codec), layout in itertools.product(cases(), (32, 20, 16)):
            path = converted(name, codec, layout)
            with self.subTest(mesh=name, codec=codec, layout=layout), tetpack.open(path) as f:
                _, vtu = exported_vtu(path)
                self.assertEqual(f.layouts, [layout])
                assert_equal(self, f.points(), vtu.points, "world points")
                self.assertEqual(f.positions().dtype, np.float32)
                assert_equal(self, f.tets(), vtu.tets, "tets from Tet%d" % layout)
                names = set()
                for assoc, label, values in f._named_arrays():
                    want = (vtu.point_data if assoc == "point" else vtu.cell_data)[label]
                    assert_equal(self, values, want, label)
                    names.add(label)
                self.assertEqual(names, set(vtu.point_data) | set(vtu.cell_data))
                self.assertIn("source_cell", names)

    def test_every_layout_gives_the_same_positive_tets(self):
        """Tet20/Tet16 recovery may start a tet at another vertex: the same vertex sets, and every
        quadruple positively oriented (det > 0 on the stored positions, as spec §3 requires)."""
        for name, codec in cases():
            with self.subTest(mesh=name, codec=codec), tetpack.open(converted(name, codec)) as f:
                reference = np.sort(f.tets(32), axis=1)
                p = f.positions().astype(np.float64)
                for layout in (32, 20, 16):
                    tets = f.tets(layout)
                    assert_equal(self, np.sort(tets, axis=1), reference, "vertex sets from Tet%d" % layout)
                    a, b, c, d = (p[tets[:, k]] for k in range(4))
                    det = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
                    self.assertTrue((det > 0).all(), "Tet%d: %d tets not positive" % (layout, (det <= 0).sum()))

    def test_records_agree_between_layouts_and_codecs(self):
        """Tet32's stored vertices and vx are those of the recovered tets; Tet20/Tet16 hold the same
        vx and neighbours (spec §3: nx[r] = n[r] ^ n[3]); plain and zstd files hold identical records."""
        for name in ("acoustic_wg", "t3_prisms"):
            with self.subTest(mesh=name), tetpack.open(converted(name, "plain")) as f, \
                    tetpack.open(converted(name, "zstd")) as z:
                t32, t20, t16 = f.tet32(), f.tet20(), f.tet16()
                tets = f.tets(32)
                assert_equal(self, t32["v"], tets[:, :3], "Tet32 v")
                assert_equal(self, t32["vx"], np.bitwise_xor.reduce(tets, axis=1), "Tet32 vx")
                assert_equal(self, t20["vx"], t32["vx"], "Tet20 vx")
                assert_equal(self, t16["vx"], t32["vx"], "Tet16 vx")
                assert_equal(self, t16["nx"], t20["n"][:, :3] ^ t20["n"][:, 3:], "Tet16 nx")
                for get in ("tet32", "tet20", "tet16", "shell", "positions", "tmap", "vmap"):
                    assert_equal(self, getattr(z, get)(), getattr(f, get)(), "%s plain vs zstd" % get)

    def test_shell_equals_exported_ply(self):
        for name, codec in cases():
            with self.subTest(mesh=name, codec=codec), tetpack.open(converted(name, codec)) as f:
                points, tri, tet = exported_shell(converted(name, codec))
                shell = f.shell()
                self.assertEqual(len(shell), f.shell_face_count)
                mine = np.stack([shell["a"], shell["b"], shell["c"]], axis=1)
                assert_equal(self, f.points()[mine], points[tri], "shell triangles")
                assert_equal(self, shell["t"], tet, "shell tets")

    def test_uncompressed_chunks_are_views_into_one_mapping(self):
        """A copy would land at a fresh address each call; views sit at mapping + chunk offset, so
        address - offset is one constant for every chunk of the file."""
        with tetpack.open(converted("8block", "plain")) as f:
            bases = set()
            for i, entry in enumerate(f.chunks()):
                data, zero_copy = f.chunk_bytes(i)
                self.assertTrue(zero_copy)
                self.assertFalse(data.flags.writeable, "a view into a read-only mapping must be read-only")
                bases.add(address(data) - entry["offset"])
            self.assertEqual(len(bases), 1)
            self.assertEqual(address(f.positions()), address(f.positions()))
            self.assertEqual(address(f.field("disp_Z", 3)), bases.pop() + f.chunks()[f.find_chunk(
                tetpack._tag("FDAT"), [x.name for x in f.fields].index("disp_Z"), 3)]["offset"])

    def test_zstd_chunks_are_decoded_copies(self):
        with tetpack.open(converted("8block", "zstd")) as f:
            i = f.find_chunk(tetpack._tag("POS3"))
            self.assertEqual(f.chunks()[i]["codec"], 1)
            first, zero_copy = f.chunk_bytes(i)
            self.assertFalse(zero_copy)
            self.assertNotEqual(address(first), address(f.chunk_bytes(i)[0]))


class Metadata(unittest.TestCase):
    def test_header_fields_times_meta_match_tetpack_info(self):
        for name, codec in cases():
            with self.subTest(mesh=name, codec=codec), tetpack.open(converted(name, codec)) as f:
                info = tetpack.info(converted(name, codec))
                self.assertEqual((f.vertex_count, f.tet_count, f.shell_face_count),
                                 (info["vertices"], info["tets"], info["shell_faces"]))
                assert_equal(self, f.origin, info["origin"], "origin")
                assert_equal(self, f.bounds[0], info["bounds"]["min"], "bounds min")
                assert_equal(self, f.bounds[1], info["bounds"]["max"], "bounds max")
                self.assertEqual(len(f.chunks()), len(info["chunks"]))
                self.assertEqual([c["tag"] for c in f.chunks()], [c["tag"] for c in info["chunks"]])
                self.assertEqual([x.name for x in f.fields], [x["name"] for x in info["fields"]])
                for mine, theirs in zip(f.fields, info["fields"]):
                    values = np.concatenate([f.field(mine.name, s).ravel() for s in range(mine.steps)])
                    self.assertEqual((mine.min, mine.max), (float(np.nanmin(values)), float(np.nanmax(values))))
                self.assertTrue(f.meta["source"]["path"].endswith(MESHES[name][0]), f.meta["source"])
                self.assertEqual(f.meta["converter"]["name"], "tetpack")
                f.verify()

    def test_time_steps(self):
        with tetpack.open(converted("8block", "plain")) as f:
            self.assertEqual(len(f.fields), 12)
            self.assertEqual({x.steps for x in f.fields}, {11})
            self.assertEqual(len(f.times), 11)
            self.assertTrue(all(b > a for a, b in zip(f.times, f.times[1:])), f.times)
            self.assertFalse(np.array_equal(f.field("disp_Z", 0), f.field("disp_Z", 10)))
            with self.assertRaises(tetpack.Error) as caught:
                f.field("disp_Z", 11)
            self.assertEqual(caught.exception.code, 16)
        with tetpack.open(converted("huge_offset", "plain")) as f:
            self.assertGreater(f.origin[0], 1e6)  # positions are relative to a far origin
            self.assertLess(np.abs(f.positions()).max(), 1e4)


class CommandLine(unittest.TestCase):
    def test_convert_and_check_return_reports(self):
        out = converted("acoustic_wg", "plain")[:-4] + "_api.tpk"
        summary = tetpack.convert(os.path.join(DATA, "sfepy/cylinder.vtk"), out, layouts=(20,), zstd=5)
        self.assertEqual(summary["tets"], 1348)
        with tetpack.open(out) as f:
            self.assertEqual(f.layouts, [20])
            self.assertEqual({c["codec"] for c in f.chunks()}, {1})
        report = tetpack.check(out)
        self.assertEqual(report["schema"], "tetpack-check/1")
        self.assertEqual((report["format"], report["tets"], report["problems"]), ("tpk", 1348, False))
        with self.assertRaises(tetpack.CommandError) as caught:
            tetpack.convert(out + ".missing.vtk", out + ".never.tpk")
        self.assertNotEqual(caught.exception.returncode, 0)


if __name__ == "__main__":
    unittest.main()
