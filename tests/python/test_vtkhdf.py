"""VTKHDF in and out. Files written by an independent writer (h5py, following VTK's published VTKHDF
layout) from real meshes of ../shared/data, split into partitions that repeat their shared points as a
distributed VTK writer does, must convert to what the same mesh converts to from VTU (or a .pvd series
for time steps): same tets, fields and steps, compared through `tetpack info --json` and the arrays of
`tetpack export --vtu` (read by VTK, points in a canonical order, since partitions number points their
own way). `export --vtkhdf` must be read back by VTK's vtkHDFReader with the same counts and values.
Bad inputs must fail with messages naming the file and the dataset or attribute."""
import json
import os
import shutil
import subprocess
import tempfile
import unittest

import h5py
import meshio
import numpy as np
import vtk
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

EXE = os.environ.get("TETPACK_EXE", "tetpack")
DATA = os.environ.get("TETPACK_DATA_DIR", os.path.join(os.path.dirname(__file__), "../../../shared/data"))
VTK_TYPES = {"tetra": 10, "hexahedron": 12, "wedge": 13, "pyramid": 14}


def tetpack(*args, ok=True):
    p = subprocess.run([EXE] + [str(a) for a in args], capture_output=True, text=True)
    if ok and p.returncode != 0:
        raise AssertionError("tetpack %s failed: %s" % (" ".join(map(str, args)), p.stderr))
    return p


# ---- the independent writer: VTK's VTKHDF UnstructuredGrid layout, with h5py ---------------------------
def partition(points, cells, types, parts):
    """Cells split into `parts` consecutive runs; each partition holds only the points its cells use,
    renumbered from 0 (shared points repeated). cells: list of id arrays (polyhedra: list of faces)."""
    bounds = np.linspace(0, len(cells), parts + 1).astype(int)
    out = []
    for p in range(parts):
        sel = range(bounds[p], bounds[p + 1])
        used = sorted({int(i) for c in sel for i in np.concatenate([np.ravel(f) for f in cells[c]] if types[c] == 42 else [cells[c]])})
        local = {g: k for k, g in enumerate(used)}
        out.append((np.array(used, dtype=np.int64), [c for c in sel], local))
    return out


def write_vtkhdf(path, points, cells, types, point_data, cell_data, parts=1, times=None, version=(2, 0)):
    """point_data/cell_data: name -> array (steps, n[, comps]) when times is given, else (n[, comps])."""
    steps = len(times) if times is not None else 1
    pieces = partition(points, cells, types, parts)
    with h5py.File(path, "w") as f:
        g = f.create_group("VTKHDF", track_order=True)
        g.attrs.create("Version", np.array(version, dtype="<i8"))
        g.attrs.create("Type", np.bytes_("UnstructuredGrid"), dtype=h5py.string_dtype("ascii", 16))
        npts, ncells, nconn, pts, conn, offs, typ = [], [], [], [], [], [], []
        nfaces, nfconn, np2f, fconn, foffs, p2f, poffs = [], [], [], [], [], [], []
        for used, sel, local in pieces:
            npts.append(len(used))
            ncells.append(len(sel))
            pts.append(points[used])
            o, fo, po, c_conn, c_fconn, c_p2f = [0], [0], [0], [], [], []
            for c in sel:
                if types[c] == 42:
                    ids = sorted({local[int(i)] for face in cells[c] for i in face})
                    for face in cells[c]:
                        c_p2f.append(len(fo) - 1)
                        c_fconn.extend(local[int(i)] for i in face)
                        fo.append(len(c_fconn))
                else:
                    ids = [local[int(i)] for i in cells[c]]
                c_conn.extend(ids)
                o.append(len(c_conn))
                po.append(len(c_p2f))
                typ.append(types[c])
            nconn.append(len(c_conn))
            conn.append(c_conn), offs.append(o)
            nfaces.append(len(fo) - 1), nfconn.append(len(c_fconn)), np2f.append(len(c_p2f))
            fconn.append(c_fconn), foffs.append(fo), p2f.append(c_p2f), poffs.append(po)
        i64 = lambda parts_: np.array([x for q in parts_ for x in q], dtype=np.int64)
        g["NumberOfPoints"], g["NumberOfCells"] = np.array(npts, "<i8"), np.array(ncells, "<i8")
        g["NumberOfConnectivityIds"] = np.array(nconn, "<i8")
        g["Points"] = np.concatenate(pts)
        g.create_dataset("Connectivity", data=i64(conn), compression="gzip", chunks=True)
        g["Offsets"], g["Types"] = i64(offs), np.array(typ, np.uint8)
        if 42 in types:
            g["NumberOfFaces"], g["NumberOfFaceConnectivityIds"] = np.array(nfaces, "<i8"), np.array(nfconn, "<i8")
            g["NumberOfPolyhedronToFaceIds"] = np.array(np2f, "<i8")
            g["FaceConnectivity"], g["FaceOffsets"] = i64(fconn), i64(foffs)
            g["PolyhedronToFaces"], g["PolyhedronOffsets"] = i64(p2f), i64(poffs)
        for group, data, per_piece in (("PointData", point_data, lambda u, s, a: a[u]),
                                       ("CellData", cell_data, lambda u, s, a: a[s])):
            grp = g.create_group(group, track_order=True)
            for name, values in data.items():
                values = np.asarray(values)
                by_step = values if times is not None else values[None]
                rows = [per_piece(used, list(sel), by_step[s]) for s in range(steps) for used, sel, _ in pieces]
                grp[name] = np.concatenate(rows)
        if times is not None:
            s = g.create_group("Steps")
            s.attrs["NSteps"] = steps
            s["Values"] = np.asarray(times, float)
            s["NumberOfParts"] = np.full(steps, parts, "<i8")
            for name in ("PartOffsets", "PointOffsets", "CellOffsets", "ConnectivityIdOffsets"):
                s[name] = np.zeros(steps, "<i8")
            for group, data, per_step in (("PointDataOffsets", point_data, sum(npts)),
                                          ("CellDataOffsets", cell_data, sum(ncells))):
                grp = s.create_group(group)
                for name in data:
                    grp[name] = np.arange(steps, dtype="<i8") * per_step


# ---- what a .tpk holds, in an order that does not depend on point numbering -----------------------------
def read_vtu(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    return grid_arrays(r.GetOutput())


def grid_arrays(grid):
    points = vtk_to_numpy(grid.GetPoints().GetData()).astype(float)
    tets = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    data = {}
    for kind, d in (("point", grid.GetPointData()), ("cell", grid.GetCellData())):
        for i in range(d.GetNumberOfArrays()):
            data[(kind, d.GetArrayName(i))] = vtk_to_numpy(d.GetArray(i))
    return points, tets, data


def canonical(points, tets, data):
    order = np.lexsort(points.T[::-1])
    rank = np.empty(len(order), int)
    rank[order] = np.arange(len(order))
    t = np.sort(rank[tets], axis=1)
    torder = np.lexsort(t.T[::-1])
    out = {"points": points[order], "tets": t[torder]}
    for (kind, name), v in data.items():
        if name in ("source_point", "source_cell"):
            continue
        out[kind + ":" + name] = v[order] if kind == "point" else v[torder]
    return out


def summary(tpk):
    info = json.loads(tetpack("info", "--json", tpk).stdout)
    keep = {k: info.get(k) for k in ("vertices", "tets", "shell_faces", "origin", "bounds", "fields", "times")}
    keep["fields"] = [f for f in keep["fields"] or [] if f["name"] not in ("source_point", "source_cell")]
    source = info["metadata"]["source"]
    keep["source"] = (source["cells"], source["points"])
    return keep


class VtkhdfTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="tetpack-vtkhdf-")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, True)

    def path(self, name):
        return os.path.join(self.work, name)

    def convert(self, source, name):
        tpk = self.path(name + ".tpk")
        tetpack("convert", source, tpk)
        tetpack("export", tpk, "--vtu", self.path(name + ".vtu"))
        return tpk, canonical(*read_vtu(self.path(name + ".vtu")))

    def assert_same_conversion(self, vtkhdf, reference, name):
        got_tpk, got = self.convert(vtkhdf, name + "_h")
        want_tpk, want = self.convert(reference, name + "_r")
        self.assertEqual(summary(got_tpk), summary(want_tpk))
        self.assertEqual(sorted(got), sorted(want))
        for key in want:
            np.testing.assert_array_equal(got[key], want[key], err_msg="%s: %s" % (name, key))
        return got_tpk

    def volume_mesh(self, rel):
        m = meshio.read(os.path.join(DATA, rel))
        blocks = [c for c in m.cells if c.type in VTK_TYPES]
        cells = [row for c in blocks for row in c.data]
        types = [VTK_TYPES[c.type] for c in blocks for _ in c.data]
        used = np.unique(np.concatenate([np.ravel(c.data) for c in blocks]))
        if len(used) != len(m.points):  # no unused points: the partitions hold only the points cells use
            remap = -np.ones(len(m.points), int)
            remap[used] = np.arange(len(used))
            cells = [remap[c] for c in cells]
            m.points = m.points[used]
        return m.points.astype(float), cells, types, m, blocks

    # ---- reading ------------------------------------------------------------------------------------------
    def test_partitions_cell_and_point_fields(self):
        """sfepy/cylinder.vtk (1,348 tets) in three partitions and sfepy/cube_medium_hexa.mesh (1,000 hexes)
        in one, equal to meshio's VTU of the same mesh. (Hexahedra split into tets by their vertex ids, and
        merged partitions number points their own way: in several partitions the split may differ, as
        valid, so hexahedra are compared in one; test_polyhedra merges them.)"""
        for rel, name, parts in (("sfepy/cylinder.vtk", "cylinder", 3), ("sfepy/cube_medium_hexa.mesh", "hexa", 1)):
            points, cells, types, m, blocks = self.volume_mesh(rel)
            u = points[:, 0] + 2 * points[:, 1] + 3 * points[:, 2]
            vel = np.stack([points[:, 1], -points[:, 0], points[:, 2]], axis=1)
            cid = np.arange(len(cells), dtype=float)
            h = self.path(name + ".vtkhdf")
            write_vtkhdf(h, points, cells, types, {"u": u, "vel": vel}, {"cid": cid}, parts=parts, version=(1, 0))
            vtu = self.path(name + "_ref.vtu")
            meshio.write(vtu, meshio.Mesh(points, [(c.type, np.array([cells[i] for i in range(len(cells))]))
                                                   for c in blocks[:1]],
                                          point_data={"u": u, "vel": vel}, cell_data={"cid": [cid]}))
            with self.subTest(mesh=rel):
                self.assert_same_conversion(h, vtu, name)

    def test_time_steps(self):
        """sfepy/cube_medium_tetra.mesh with three steps (Version 2.0 Steps, two partitions) equals the
        .pvd series of the same steps."""
        points, cells, types, m, blocks = self.volume_mesh("sfepy/cube_medium_tetra.mesh")
        times = [0.0, 0.25, 1.5]
        u = np.stack([points[:, 0] * (1 + t) + points[:, 2] * t for t in times])
        c = np.stack([np.arange(len(cells)) * (1 + t) for t in times])
        h = self.path("steps.vtkhdf")
        write_vtkhdf(h, points, cells, types, {"u": u}, {"c": c}, parts=2, times=times)
        lines = []
        for k, t in enumerate(times):
            meshio.write(self.path("steps_%d.vtu" % k), meshio.Mesh(points, [("tetra", np.array(cells))],
                                                                   point_data={"u": u[k]}, cell_data={"c": [c[k]]}))
            lines.append('<DataSet timestep="%r" file="steps_%d.vtu"/>' % (t, k))
        with open(self.path("steps.pvd"), "w") as f:
            f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1"><Collection>%s'
                    '</Collection></VTKFile>\n' % "".join(lines))
        tpk = self.assert_same_conversion(h, self.path("steps.pvd"), "steps")
        self.assertEqual(summary(tpk)["times"], times)

    def test_polyhedra(self):
        """The hexahedra of sfepy/cube_medium_hexa.mesh, every other one as a polyhedron (VTK 42, its six
        faces) in a VTKHDF 2.x file with FaceConnectivity & co., equal to VTK's own VTU of the same cells."""
        points, cells, types, m, blocks = self.volume_mesh("sfepy/cube_medium_hexa.mesh")
        hex_faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
        poly_cells, poly_types = [], []
        for i, c in enumerate(cells):
            if i % 2:
                poly_cells.append([[int(c[k]) for k in face] for face in hex_faces])
                poly_types.append(42)
            else:
                poly_cells.append(c)
                poly_types.append(12)
        cid = np.arange(len(cells), dtype=float)
        h = self.path("poly.vtkhdf")
        write_vtkhdf(h, points, poly_cells, poly_types, {}, {"cid": cid}, parts=1, version=(2, 5))
        # In four partitions the shared points merge back: the same points and cells (the split into
        # tets may differ, as it follows the point numbering).
        h4 = self.path("poly4.vtkhdf")
        write_vtkhdf(h4, points, poly_cells, poly_types, {}, {"cid": cid}, parts=4, version=(2, 5))
        tetpack("convert", h4, self.path("poly4.tpk"))
        source = json.loads(tetpack("info", "--json", self.path("poly4.tpk")).stdout)["metadata"]["source"]
        self.assertEqual((source["cells"], source["points"]), (len(cells), len(points)))
        grid = vtk.vtkUnstructuredGrid()
        pts = vtk.vtkPoints()
        pts.SetData(numpy_to_vtk(points, deep=True))
        grid.SetPoints(pts)
        for c, t in zip(poly_cells, poly_types):
            if t == 42:
                stream = [len(c)] + [x for face in c for x in [len(face)] + face]
                ids = vtk.vtkIdList()
                for x in stream:
                    ids.InsertNextId(x)
                grid.InsertNextCell(42, ids)
            else:
                grid.InsertNextCell(t, 8, [int(x) for x in c])
        arr = numpy_to_vtk(cid, deep=True)
        arr.SetName("cid")
        grid.GetCellData().AddArray(arr)
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(self.path("poly_ref.vtu"))
        w.SetInputData(grid)
        w.SetDataModeToAscii()
        self.assertEqual(w.Write(), 1)
        tpk = self.assert_same_conversion(h, self.path("poly_ref.vtu"), "poly")
        info = json.loads(tetpack("info", "--json", tpk).stdout)
        self.assertEqual(info["metadata"]["pipeline"]["polyhedra"], 500)

    def test_detected_without_extension(self):
        """An HDF5 file named .h5 is VTKHDF by its /VTKHDF group (the registry's probe), not Exodus."""
        points, cells, types, m, blocks = self.volume_mesh("sfepy/cylinder.vtk")
        h = self.path("named.h5")
        write_vtkhdf(h, points, cells, types, {}, {}, parts=1, version=(1, 0))
        tetpack("convert", h, self.path("named.tpk"))
        info = json.loads(tetpack("info", "--json", self.path("named.tpk")).stdout)
        self.assertTrue(info["metadata"]["source"]["format"].startswith("vtkhdf-1"))
        self.assertIn("vtkhdf", tetpack("formats").stdout)

    # ---- bad inputs ---------------------------------------------------------------------------------------
    def test_bad_inputs(self):
        points, cells, types, m, blocks = self.volume_mesh("sfepy/cylinder.vtk")
        good = self.path("good.vtkhdf")
        write_vtkhdf(good, points, cells, types, {"u": points[:, 0]}, {}, parts=2, version=(1, 0))

        def broken(name, change):
            p = self.path(name + ".vtkhdf")
            shutil.copy(good, p)
            with h5py.File(p, "r+") as f:
                change(f["VTKHDF"], f)
            return p

        def set_attr(key, value):
            return lambda g, f: g.attrs.__setitem__(key, value)

        def replace(name, values):
            def change(g, f):
                del g[name]
                g[name] = values
            return change

        conn = None
        with h5py.File(good, "r") as f:
            conn = f["VTKHDF/Connectivity"][()]
        cases = {
            "no_group": (lambda g, f: f.move("VTKHDF", "Other"), "expected a group /VTKHDF"),
            "image": (set_attr("Type", np.bytes_("ImageData")), 'attribute Type: expected "UnstructuredGrid"'),
            "version3": (set_attr("Version", np.array([3, 0])), "expected major version 1 or 2, found 3.0"),
            "no_version": (lambda g, f: g.attrs.__delitem__("Version"), "expected an attribute Version"),
            "bad_id": (replace("Connectivity", np.where(np.arange(len(conn)) == 7, 10 ** 6, conn)),
                       "/VTKHDF/Connectivity: partition 0, entry 7: expected a point id below"),
            "short_points": (replace("Points", points[:10]), "/VTKHDF/Points"),
            "no_types": (lambda g, f: g.__delitem__("Types"), "expected a dataset /VTKHDF/Types, found none"),
            "counts": (replace("NumberOfCells", np.array([1], "<i8")), "/VTKHDF/NumberOfCells: expected 2 values, found 1"),
            "short_field": (replace("PointData/u", np.zeros(5)), "/VTKHDF/PointData/u"),
        }
        for name, (change, message) in cases.items():
            with self.subTest(case=name):
                p = broken(name, change)
                r = tetpack("convert", p, self.path(name + ".tpk"), ok=False)
                self.assertNotEqual(r.returncode, 0)
                self.assertIn(p, r.stderr)
                self.assertIn(message, r.stderr)
                self.assertFalse(os.path.exists(self.path(name + ".tpk")))
        junk = self.path("junk.vtkhdf")
        with open(junk, "w") as f:
            f.write("not HDF5 at all\n")
        r = tetpack("convert", junk, self.path("junk.tpk"), ok=False)
        self.assertIn("cannot open it as an HDF5 file", r.stderr)

    # ---- writing ------------------------------------------------------------------------------------------
    def test_export_read_by_vtk(self):
        """export --vtkhdf of a real mesh (one step: Version 1.0) and of a series (Version 2.0 with Steps):
        vtkHDFReader gets the counts and values export --vtu has; every step's values are where Steps says."""
        self.assertEqual(tetpack("convert", os.path.join(DATA, "sfepy/cylinder.vtk"), self.path("cyl.tpk")).returncode, 0)
        points, cells, types, m, blocks = self.volume_mesh("sfepy/cube_medium_tetra.mesh")
        times = [0.0, 0.5, 2.0]
        u = np.stack([points[:, 0] * (1 + t) for t in times])
        write_vtkhdf(self.path("series.vtkhdf"), points, cells, types, {"u": u}, {}, times=times)
        tetpack("convert", self.path("series.vtkhdf"), self.path("series.tpk"))
        for name, steps in (("cyl", 1), ("series", 3)):
            tpk = self.path(name + ".tpk")
            out, vtu = self.path(name + "_out.vtkhdf"), self.path(name + "_out.vtu")
            tetpack("export", tpk, "--vtkhdf", out, "--vtu", vtu)
            want_points, want_tets, want = read_vtu(vtu)
            reader = vtk.vtkHDFReader()
            reader.SetFileName(out)
            reader.Update()
            got_points, got_tets, got = grid_arrays(reader.GetOutput())
            with self.subTest(mesh=name):
                np.testing.assert_array_equal(got_points, want_points)
                np.testing.assert_array_equal(got_tets, want_tets)
                for (kind, field), values in got.items():
                    key = (kind, field if steps == 1 or field.startswith("source") else field + "_t0")
                    np.testing.assert_array_equal(values, want[key], err_msg=field)
                with h5py.File(out, "r") as f:
                    g = f["VTKHDF"]
                    self.assertEqual(list(g.attrs["Version"]), [1, 0] if steps == 1 else [2, 0])
                    if steps > 1:
                        self.assertEqual(list(g["Steps/Values"][()]), times)
                        for s in range(steps):
                            at = g["Steps/PointDataOffsets/u"][s]
                            np.testing.assert_array_equal(g["PointData/u"][at:at + len(want_points)],
                                                          want[("point", "u_t%d" % s)])
                # and tetpack reads its own export back to the same mesh
                tetpack("convert", out, self.path(name + "_back.tpk"))
                self.assertEqual(summary(self.path(name + "_back.tpk"))["tets"], len(want_tets))


if __name__ == "__main__":
    unittest.main()
