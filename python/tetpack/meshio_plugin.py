"""meshio support: importing tetpack registers the "tetpack" format (.tpk) with meshio, so that
meshio.read("x.tpk") reads through libtetpack and meshio.write("x.tpk", mesh) goes through
`tetpack convert` (by way of a temporary VTU, the converter's own importer does the rest)."""
import os
import tempfile


def read(path):
    from . import open as open_tpk
    with open_tpk(path) as f:
        return f.to_meshio()


def write(path, mesh, layouts=None, zstd=None):
    """Write a meshio.Mesh as .tpk: meshio writes a VTU, `tetpack convert` tetrahedralizes, orients and
    packs it (every scalar point field kept, as the tool does by default)."""
    import meshio
    from . import convert
    with tempfile.TemporaryDirectory(prefix="tetpack-meshio-") as tmp:
        vtu = os.path.join(tmp, "mesh.vtu")
        meshio.write(vtu, mesh, binary=True)
        return convert(vtu, path, layouts=layouts, zstd=zstd)


def _register():
    try:
        import meshio
    except ImportError:  # meshio is optional for the module; the tests require it
        return False
    meshio.register_format("tetpack", [".tpk"], read, {"tetpack": write})
    return True


registered = _register()
