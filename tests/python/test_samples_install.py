"""The Python samples run as written, and the module works after `cmake --install` with Debian's python3
(no build tree on its path: the installed tetpack command and ParaView plugin are the ones it finds)."""
import glob
import os
import subprocess
import sys
import unittest

from common import SAMPLES, WORK


def python(args, env=None, cwd=None):
    proc = subprocess.run([sys.executable] + args, capture_output=True, text=True, env=env, cwd=cwd)
    if proc.returncode != 0:
        raise AssertionError("%s failed (%d):\n%s%s" % (args, proc.returncode, proc.stdout, proc.stderr))
    return proc.stdout


class Samples(unittest.TestCase):
    def test_quickstart(self):
        out = os.path.join(WORK, "quickstart")
        text = python([os.path.join(SAMPLES, "python_quickstart.py"), out])
        self.assertIn("converted: 1348 tets, 354 vertices", text)
        self.assertIn("all positive: True", text)

    def test_walkthrough(self):
        out = os.path.join(WORK, "walkthrough")
        text = python([os.path.join(SAMPLES, "python_walkthrough.py"), out])
        self.assertIn("Tet32 and zstd Tet16 give the same tets: True", text)
        self.assertIn("tetpack.Error 18", text)
        for name in ("walk_meshio.vtu", "walk_vtk.vtu", "walk_shell.vtp"):
            self.assertGreater(os.path.getsize(os.path.join(out, name)), 1000, name)


class Install(unittest.TestCase):
    def test_installed_module(self):
        prefix = os.path.join(WORK, "prefix")
        subprocess.run([os.environ["CMAKE_COMMAND"], "--install", os.environ["TETPACK_BUILD_DIR"], "--prefix", prefix],
                       check=True, capture_output=True)
        # Where the build put it (python/CMakeLists.txt: from python3's sysconfig for the prefix).
        inits = glob.glob(os.path.join(prefix, "**", "tetpack", "__init__.py"), recursive=True)
        self.assertEqual(len(inits), 1, inits)
        site = os.path.dirname(os.path.dirname(inits[0]))
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "TETPACK_EXE")}
        env["PYTHONPATH"] = site
        script = """
import os, sys, tetpack
assert tetpack.__file__.startswith(%r), tetpack.__file__
assert tetpack.executable() == %r, tetpack.executable()
assert os.path.isfile(tetpack.paraview_plugin_path()), tetpack.paraview_plugin_path()
tetpack.convert(%r, %r, layouts=(20,))
with tetpack.open(%r) as f:
    print(f.tet_count, f.tets().shape, f.layouts)
""" % (site, os.path.join(prefix, "bin", "tetpack"), os.path.join(SAMPLES, "cylinder.vtk"),
       os.path.join(WORK, "installed.tpk"), os.path.join(WORK, "installed.tpk"))
        self.assertEqual(python(["-c", script], env=env, cwd=WORK).strip(), "1348 (1348, 4) [20]")


if __name__ == "__main__":
    unittest.main()
