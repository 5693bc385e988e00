"""Closing, lifetimes and errors: arrays keep the mapping alive past close(), the file is unmapped when
the last one dies, a closed File refuses calls, and the library's result codes reach Python."""
import gc
import os
import shutil
import unittest

import numpy as np

import tetpack
from common import SAMPLES, WORK, converted


def mapped(path):
    """Whether this process maps `path` (read from /proc/self/maps)."""
    real = os.path.realpath(path)
    with open("/proc/self/maps") as maps:
        return any(line.rstrip("\n").endswith(" " + real) for line in maps)


class Lifetime(unittest.TestCase):
    def setUp(self):
        # a copy of its own, so no other open handle in this process maps the same path
        self.path = os.path.join(WORK, "lifetime_%s.tpk" % self._testMethodName)
        shutil.copyfile(converted("acoustic_wg", "plain"), self.path)

    def test_arrays_outlive_close_and_the_last_one_unmaps(self):
        f = tetpack.open(self.path)
        positions, tets32, field = f.positions(), f.tet32(), f.field("node_groups")
        expected = float(positions.astype(np.float64).sum())
        self.assertTrue(mapped(self.path))
        f.close()
        self.assertTrue(f.closed)
        self.assertTrue(mapped(self.path), "close() must not unmap under live arrays")
        self.assertEqual(float(positions.astype(np.float64).sum()), expected)
        self.assertEqual(len(tets32), f.tet_count)
        del positions, tets32
        gc.collect()
        self.assertTrue(mapped(self.path), "one array is still alive")
        del field
        gc.collect()
        self.assertFalse(mapped(self.path), "the last array gone, the file must be unmapped")

    def test_close_without_arrays_unmaps_at_once(self):
        with tetpack.open(self.path) as f:
            f.tets()  # decoded into a new array: holds no mapping
            self.assertTrue(mapped(self.path))
        self.assertFalse(mapped(self.path))

    def test_closed_file_refuses_every_call(self):
        f = tetpack.open(self.path)
        f.close()
        f.close()  # a second close is harmless, as for Python files
        for call in (f.positions, f.tets, f.verify, f.chunks, f.info, lambda: f.field("mat_id"),
                     lambda: f.time(0), lambda: f.chunk_bytes(0), lambda: f.meta):
            with self.assertRaises(tetpack.Error) as caught:
                call()
            self.assertEqual(caught.exception.code, 18)
            self.assertIn("closed", str(caught.exception))

    def test_views_are_read_only(self):
        with tetpack.open(self.path) as f:
            with self.assertRaises(ValueError):
                f.positions()[0, 0] = 1.0


class Errors(unittest.TestCase):
    """Golden broken files (samples/vectors, spec §10): the library's code and message come through."""

    def vector(self, name):
        return os.path.join(SAMPLES, "vectors", name)

    def test_open_errors(self):
        for name, code in (("bad_magic.tpk", 4), ("truncated.tpk", 5), ("newer_major.tpk", 6),
                           ("overlap.tpk", 12), ("unknown_required_chunk.tpk", 10)):
            with self.subTest(vector=name):
                with self.assertRaises(tetpack.Error) as caught:
                    tetpack.open(self.vector(name))
                err = caught.exception
                self.assertEqual(err.code, code, err)
                self.assertEqual(err.code_name, tetpack._tetpack.result_string(code))
                self.assertTrue(err.message)

    def test_checksum_errors_on_read_and_verify(self):
        for name in ("chunk_checksum.tpk", "zstd_chunk_checksum.tpk"):
            with self.subTest(vector=name):
                with tetpack.open(self.vector(name)) as f:
                    with self.assertRaises(tetpack.Error) as caught:
                        f.verify()
                    self.assertEqual(caught.exception.code, 9)
                with self.assertRaises(tetpack.Error) as caught:
                    tetpack.open(self.vector(name), verify_all=True)
                self.assertEqual(caught.exception.code, 9)

    def test_missing_file_and_missing_things(self):
        with self.assertRaises(tetpack.Error) as caught:
            tetpack.open(os.path.join(WORK, "no such file.tpk"))
        self.assertEqual(caught.exception.code, 2)
        with tetpack.open(self.vector("one_tet.tpk")) as f:
            self.assertEqual((f.vertex_count, f.tet_count), (4, 1))
            self.assertIsNone(f.tmap())
            for call in (lambda: f.field("nope"), lambda: f.chunk("TIME")):
                with self.assertRaises(tetpack.Error) as caught:
                    call()
                self.assertEqual(caught.exception.code, 16)


if __name__ == "__main__":
    unittest.main()
